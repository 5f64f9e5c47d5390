# Every third-party library, from Debian 12 packages installed by scripts/setup.
find_package(Threads REQUIRED)
find_package(Eigen3 3.4 REQUIRED NO_MODULE)
find_package(Boost 1.74 REQUIRED)                 # Geometry, Asio, Beast: header-only parts
find_package(nlohmann_json 3.10 REQUIRED)
find_package(spdlog REQUIRED)
find_package(CLI11 REQUIRED)
find_package(Ceres 2.1 REQUIRED)
find_package(octomap REQUIRED)
find_package(CGAL 5.5 REQUIRED)
# GeographicLib ships no CMake config on Debian, only a find module.
list(APPEND CMAKE_MODULE_PATH /usr/share/cmake/geographiclib)
find_package(GeographicLib 2.1 REQUIRED)
# No VTK part of PCL is used; not finding VTK cuts every link by seconds.
set(CMAKE_DISABLE_FIND_PACKAGE_VTK ON)
find_package(PCL 1.13 REQUIRED COMPONENTS common io)
# FLANN (libflann-dev, a PCL dependency) is used header-only by mapping's outlier removal; its
# headers call LZ4 (serialization), so liblz4 is linked. FLANN's own CMake target would link its
# whole static library into every program.
find_path(ROWLOC_FLANN_INCLUDE_DIR flann/algorithms/kdtree_single_index.h REQUIRED)
find_library(ROWLOC_LZ4_LIBRARY lz4 REQUIRED)
if(ROWLOC_BUILD_TESTS)
  find_package(GTest REQUIRED)
endif()
if(ROWLOC_BUILD_BENCH)
  find_package(benchmark REQUIRED)
endif()
