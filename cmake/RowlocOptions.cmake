# Compiler flags shared by every rowloc target, carried by the interface target rowloc_options.
find_program(ROWLOC_CCACHE ccache)
if(ROWLOC_CCACHE AND NOT CMAKE_CXX_COMPILER_LAUNCHER)
  # CCACHE_BASEDIR makes paths relative, so that fresh clones (CI) hit the cache of earlier ones.
  set(_launcher ${CMAKE_COMMAND} -E env CCACHE_BASEDIR=${PROJECT_SOURCE_DIR} ${ROWLOC_CCACHE})
  set(CMAKE_CXX_COMPILER_LAUNCHER ${_launcher})
  set(CMAKE_C_COMPILER_LAUNCHER ${_launcher})
endif()

add_library(rowloc_options INTERFACE)
target_compile_options(rowloc_options INTERFACE
  -Wall -Wextra -Wpedantic -Wshadow -Wnon-virtual-dtor -Woverloaded-virtual
  -Wcast-align -Wdouble-promotion -Wimplicit-fallthrough
  # No fused multiply-add contraction (GCC contracts by default in C++, and always where FMA is baseline,
  # e.g. aarch64): every product rounds on its own, so the covariance kernels that rely on commuted
  # products being equal stay exactly symmetric, and results do not depend on the CPU's FMA.
  -ffp-contract=off)
if(ROWLOC_WERROR)
  target_compile_options(rowloc_options INTERFACE -Werror)
  # GCC 12 reports -Wrestrict on `"literal" + std::string` at -O3 (GCC bug 105329, a false positive
  # fixed in GCC 13): it stays a warning there, not an error, so that the idiom need not be avoided.
  if(CMAKE_CXX_COMPILER_ID STREQUAL "GNU" AND CMAKE_CXX_COMPILER_VERSION VERSION_LESS 13)
    target_compile_options(rowloc_options INTERFACE -Wno-error=restrict)
  endif()
endif()
# Never -march=native: Debian's PCL is built for baseline x86-64 and a different Eigen
# alignment aborts at run time (docs/building.md).
if(ROWLOC_SANITIZE)
  set(_san -fsanitize=address,undefined -fno-omit-frame-pointer -fno-sanitize-recover=undefined)
  target_compile_options(rowloc_options INTERFACE ${_san})
  target_link_options(rowloc_options INTERFACE ${_san})
  # Required with PCL under ASan, or "free on address which was not malloc()-ed".
  target_compile_definitions(rowloc_options INTERFACE EIGEN_MALLOC_ALREADY_ALIGNED=1)
endif()
