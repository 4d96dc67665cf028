# cmake -DDIR=... -DPREFIX=... -P amalgamate.cmake
# After Verilator has written its C++ into DIR, writes PREFIX__ALL_fast.cpp and PREFIX__ALL_slow.cpp
# that #include every generated file (as Verilator's own makefiles do with verilator_includer), so
# that CMake knows the sources at configure time although the generated file names depend on the
# design (hw/rtl/CMakeLists.txt: the pipeline's package is itself generated at build time).
file(GLOB cpps "${DIR}/${PREFIX}*.cpp")
set(fast "// generated: every fast-path file of ${PREFIX}\n")
set(slow "// generated: every slow-path (construction) file of ${PREFIX}\n")
foreach(f ${cpps})
  get_filename_component(n "${f}" NAME)
  if(n MATCHES "__ALL_")
    continue()
  elseif(n MATCHES "__Slow|__Syms")
    string(APPEND slow "#include \"${n}\"\n")
  else()
    string(APPEND fast "#include \"${n}\"\n")
  endif()
endforeach()
file(WRITE "${DIR}/${PREFIX}__ALL_fast.cpp" "${fast}")
file(WRITE "${DIR}/${PREFIX}__ALL_slow.cpp" "${slow}")
