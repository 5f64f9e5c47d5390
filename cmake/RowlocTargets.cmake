# rowloc_add_library(NAME [PUBLIC deps...] [PRIVATE deps...] [SYSTEM_INCLUDES dirs...] [DEFINITIONS defs...])
# Builds the library of folder NAME from NAME/src/*.cpp with public headers in
# NAME/include/rowloc/NAME, and exports it as rowloc::NAME.
function(rowloc_add_library name)
  cmake_parse_arguments(ARG "" "" "PUBLIC;PRIVATE;SYSTEM_INCLUDES;DEFINITIONS" ${ARGN})
  file(GLOB _sources CONFIGURE_DEPENDS ${CMAKE_CURRENT_SOURCE_DIR}/src/*.cpp)
  if(NOT _sources)  # header-only so far
    add_library(rowloc_${name} INTERFACE)
    target_include_directories(rowloc_${name} INTERFACE ${CMAKE_CURRENT_SOURCE_DIR}/include)
    target_link_libraries(rowloc_${name} INTERFACE ${ARG_PUBLIC})
    add_library(rowloc::${name} ALIAS rowloc_${name})
    return()
  endif()
  add_library(rowloc_${name} ${_sources})
  add_library(rowloc::${name} ALIAS rowloc_${name})
  target_include_directories(rowloc_${name} PUBLIC ${CMAKE_CURRENT_SOURCE_DIR}/include)
  target_link_libraries(rowloc_${name} PUBLIC ${ARG_PUBLIC} PRIVATE rowloc_options ${ARG_PRIVATE})
  if(ARG_SYSTEM_INCLUDES)
    target_include_directories(rowloc_${name} SYSTEM PRIVATE ${ARG_SYSTEM_INCLUDES})
  endif()
  if(ARG_DEFINITIONS)
    target_compile_definitions(rowloc_${name} PRIVATE ${ARG_DEFINITIONS})
  endif()
endfunction()

# rowloc_add_tests(LIB DEPS...): one GoogleTest executable per tests/LIB/*_test.cpp,
# named test_LIB_<stem>, registered with CTest test by test.
function(rowloc_add_tests lib)
  file(GLOB _tests CONFIGURE_DEPENDS ${CMAKE_CURRENT_SOURCE_DIR}/${lib}/*_test.cpp)
  foreach(_src IN LISTS _tests)
    get_filename_component(_stem ${_src} NAME_WE)
    set(_exe test_${lib}_${_stem})
    add_executable(${_exe} ${_src})
    target_link_libraries(${_exe} PRIVATE ${ARGN} rowloc_test_support GTest::gtest GTest::gmock
                          GTest::gtest_main rowloc_options)
    # Discovery runs the executable with --gtest_list_tests before ctest starts. Under ASan, on a
    # cold page cache right after the build, listing a PCL/OctoMap-linked test took over the
    # default 5 s once in CI (2026-12-01, exit 8): allow 300 s, it is not a timing assertion.
    gtest_discover_tests(${_exe} DISCOVERY_MODE PRE_TEST DISCOVERY_TIMEOUT 300 TEST_PREFIX "${lib}."
                         PROPERTIES LABELS ${lib} ENVIRONMENT "ROWLOC_SOURCE_DIR=${PROJECT_SOURCE_DIR}")
  endforeach()
endfunction()
