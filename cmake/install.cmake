# Installation: `cmake --install build [--prefix DIR]` puts the `omma` command in bin/, the stage
# libraries (static) in lib/, the headers in include/omma/, and a CMake package and a pkg-config file
# so that other projects build against omma:
#     find_package(omma REQUIRED)                      # lib/cmake/omma/ommaConfig.cmake
#     target_link_libraries(app PRIVATE omma::omma)    # every stage; or omma::core, omma::pano, ...
#     pkg-config --cflags --libs omma                  # lib/pkgconfig/omma.pc
# examples/cmake_consumer is such a project; tests/install_consumer_test.sh builds it against an
# installed omma.
include(CMakePackageConfigHelpers)

# omma::omma: every stage.
get_property(omma_stages GLOBAL PROPERTY OMMA_STAGES)
add_library(omma_all INTERFACE)
target_link_libraries(omma_all INTERFACE ${omma_stages})
set_target_properties(omma_all PROPERTIES EXPORT_NAME omma)
add_library(omma::omma ALIAS omma_all)
install(TARGETS omma_all EXPORT ommaTargets)

install(TARGETS omma RUNTIME DESTINATION ${CMAKE_INSTALL_BINDIR})
install(DIRECTORY ${PROJECT_SOURCE_DIR}/src/omma DESTINATION ${CMAKE_INSTALL_INCLUDEDIR}
        FILES_MATCHING PATTERN "*.h" PATTERN "testing" EXCLUDE PATTERN "bench" EXCLUDE)
install(FILES ${PROJECT_SOURCE_DIR}/LICENSE ${PROJECT_SOURCE_DIR}/CHANGELOG.md
        DESTINATION ${CMAKE_INSTALL_DATADIR}/doc/omma)

set(omma_cmake_dir ${CMAKE_INSTALL_LIBDIR}/cmake/omma)
install(EXPORT ommaTargets NAMESPACE omma:: DESTINATION ${omma_cmake_dir})
configure_package_config_file(${PROJECT_SOURCE_DIR}/cmake/ommaConfig.cmake.in
                              ${PROJECT_BINARY_DIR}/ommaConfig.cmake INSTALL_DESTINATION ${omma_cmake_dir})
write_basic_package_version_file(${PROJECT_BINARY_DIR}/ommaConfigVersion.cmake
                                 COMPATIBILITY SameMinorVersion)  # before 1.0 a minor version breaks
install(FILES ${PROJECT_BINARY_DIR}/ommaConfig.cmake ${PROJECT_BINARY_DIR}/ommaConfigVersion.cmake
        DESTINATION ${omma_cmake_dir})

# pkg-config: the stage libraries in link order (dependents first) and what they need.
set(OMMA_PC_REQUIRES "opencv4 eigen3 tbb nlohmann_json spdlog fmt zlib libtiff-4 hdf5 libxxhash cpp-httplib libavcodec libavformat libavutil libswscale")
if(OMMA_GSTREAMER_ENABLED)
  string(APPEND OMMA_PC_REQUIRES " gstreamer-1.0 gstreamer-base-1.0 gstreamer-app-1.0 gstreamer-video-1.0 gstreamer-rtsp-server-1.0")
endif()
if(OMMA_MPI_ENABLED)
  string(APPEND OMMA_PC_REQUIRES " ompi-cxx")
endif()
set(OMMA_PC_LIBS "")
foreach(stage dist hw live io render calib pano sim isp design core)
  if(TARGET omma_${stage})
    string(APPEND OMMA_PC_LIBS " -lomma_${stage}")
  endif()
endforeach()
configure_file(${PROJECT_SOURCE_DIR}/cmake/omma.pc.in ${PROJECT_BINARY_DIR}/omma.pc @ONLY)
install(FILES ${PROJECT_BINARY_DIR}/omma.pc DESTINATION ${CMAKE_INSTALL_LIBDIR}/pkgconfig)
