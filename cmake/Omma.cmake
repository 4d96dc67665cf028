# omma_stage(NAME [INTERNAL] DEPS dep1 dep2 ... TEST_DEPS ...)
# The omma libraries NAME builds on come from the table OMMA_LIBRARIES (top-level CMakeLists.txt);
# DEPS are the outside libraries; TEST_DEPS what the tests link besides.
# Builds library omma_NAME from every *.cc in the current folder except *_test.cc, and, when tests
# are on, one GoogleTest executable omma_NAME_test from the *_test.cc files beside the sources
# (COLMAP's foo.h / foo.cc / foo_test.cc layout). Helpers add files without touching CMake.
include(GNUInstallDirs)
function(omma_stage name)
  cmake_parse_arguments(ARG "INTERNAL" "" "DEPS;TEST_DEPS" ${ARGN})
  file(GLOB all_cc CONFIGURE_DEPENDS ${CMAKE_CURRENT_SOURCE_DIR}/*.cc)
  file(GLOB test_cc CONFIGURE_DEPENDS ${CMAKE_CURRENT_SOURCE_DIR}/*_test.cc)
  set(lib_cc ${all_cc})
  set(omma_deps)
  foreach(dep ${OMMA_DEPS_${name}})  # the table OMMA_LIBRARIES in the top-level CMakeLists.txt
    list(APPEND omma_deps omma_${dep})
  endforeach()
  if(test_cc)
    list(REMOVE_ITEM lib_cc ${test_cc})
  endif()
  if(lib_cc)
    add_library(omma_${name} STATIC ${lib_cc})
    target_include_directories(omma_${name} PUBLIC $<BUILD_INTERFACE:${PROJECT_SOURCE_DIR}/src>
                                                   $<INSTALL_INTERFACE:${CMAKE_INSTALL_INCLUDEDIR}>)
    target_link_libraries(omma_${name} PUBLIC ${omma_deps} ${ARG_DEPS})
  else()
    add_library(omma_${name} INTERFACE)
    target_include_directories(omma_${name} INTERFACE $<BUILD_INTERFACE:${PROJECT_SOURCE_DIR}/src>
                                                      $<INSTALL_INTERFACE:${CMAKE_INSTALL_INCLUDEDIR}>)
    target_link_libraries(omma_${name} INTERFACE ${omma_deps} ${ARG_DEPS})
  endif()
  add_library(omma::${name} ALIAS omma_${name})
  # Installed and exported as omma::NAME (cmake/install.cmake: find_package(omma) in other projects),
  # except INTERNAL libraries (test fixtures, benchmark workloads), which only omma's own programs link.
  if(NOT ARG_INTERNAL)
    set_target_properties(omma_${name} PROPERTIES EXPORT_NAME ${name})
    install(TARGETS omma_${name} EXPORT ommaTargets
            ARCHIVE DESTINATION ${CMAKE_INSTALL_LIBDIR} LIBRARY DESTINATION ${CMAKE_INSTALL_LIBDIR})
    set_property(GLOBAL APPEND PROPERTY OMMA_STAGES omma_${name})
  endif()
  if(OMMA_BUILD_TESTS AND test_cc)
    add_executable(omma_${name}_test ${test_cc})
    target_link_libraries(omma_${name}_test PRIVATE omma_${name} ${ARG_TEST_DEPS} GTest::gtest GTest::gtest_main)
    target_compile_definitions(omma_${name}_test PRIVATE
      OMMA_SOURCE_DIR="${PROJECT_SOURCE_DIR}"
      OMMA_DATA_DIR="${PROJECT_SOURCE_DIR}/../shared/data"
      OMMA_BINARY="$<TARGET_FILE:omma>")
    gtest_discover_tests(omma_${name}_test WORKING_DIRECTORY ${PROJECT_BINARY_DIR} DISCOVERY_TIMEOUT 60
                         PROPERTIES LABELS ${name})
  endif()
endfunction()
