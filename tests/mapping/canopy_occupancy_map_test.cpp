// Tests of WriteOctoMap / CanopyOccupancyMap (mapping/canopy_occupancy_map.hpp): the occupied
// voxels are exactly the voxels floor(p / r) the points fall in, round trip through a .bt file,
// and every rejected input.
#include "rowloc/mapping/canopy_occupancy_map.hpp"

#include "test_support.hpp"

#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include <sys/stat.h>

#include <array>
#include <cmath>
#include <fstream>
#include <limits>
#include <random>
#include <set>
#include <utility>

namespace rowloc::mapping {
namespace {

using ::testing::HasSubstr;
using VoxelIndex = std::array<long long, 3>;

VoxelIndex VoxelOf(const Eigen::Vector3d& p, double resolution_m) {
  return {static_cast<long long>(std::floor(p.x() / resolution_m)),
          static_cast<long long>(std::floor(p.y() / resolution_m)),
          static_cast<long long>(std::floor(p.z() / resolution_m))};
}

/// True if p is at least `margin` (in voxels) away from every voxel boundary, so that the test's
/// floor(p / r) and OctoMap's floor(p * (1 / r)) cannot disagree by rounding.
bool AwayFromVoxelFaces(const Eigen::Vector3d& p, double resolution_m, double margin) {
  for (int axis = 0; axis < 3; ++axis) {
    const double scaled = p[axis] / resolution_m;
    const double frac = scaled - std::floor(scaled);
    if (frac < margin || frac > 1.0 - margin) return false;
  }
  return true;
}

struct PlaneCloud {
  PointCloud cloud;
  Eigen::Vector3d unit_normal;
};

/// Points on the plane z = 0.3 + 0.2 x - 0.1 y over [-1, 1.5] x [-0.5, 2] m.
PlaneCloud PointsOnPlane(std::size_t count, double resolution_m, unsigned seed) {
  std::mt19937 rng(seed);
  std::uniform_real_distribution<double> x(-1.0, 1.5);
  std::uniform_real_distribution<double> y(-0.5, 2.0);
  PlaneCloud plane{{}, Eigen::Vector3d(-0.2, 0.1, 1.0).normalized()};
  while (plane.cloud.points_m.size() < count) {
    const double px = x(rng);
    const double py = y(rng);
    const Eigen::Vector3d p(px, py, 0.3 + 0.2 * px - 0.1 * py);
    if (AwayFromVoxelFaces(p, resolution_m, 1e-6)) plane.cloud.points_m.push_back(p);
  }
  return plane;
}

TEST(WriteOctoMap, OccupiesExactlyTheVoxelsOfThePointsAndRoundTrips) {
  test::ScratchDir dir;
  const double resolution_m = 0.05;
  const PlaneCloud plane = PointsOnPlane(3000, resolution_m, 7);
  std::set<VoxelIndex> voxels;
  for (const Eigen::Vector3d& p : plane.cloud.points_m) voxels.insert(VoxelOf(p, resolution_m));

  const OctoMapSummary summary =
      WriteOctoMap(plane.cloud, OctoMapOptions{resolution_m}, dir / "canopy.bt");
  EXPECT_EQ(summary.occupied_leaves, voxels.size());
  EXPECT_DOUBLE_EQ(summary.resolution_m, resolution_m);
  ASSERT_TRUE(std::filesystem::exists(dir / "canopy.bt"));

  const CanopyOccupancyMap map = CanopyOccupancyMap::Load(dir / "canopy.bt");
  EXPECT_DOUBLE_EQ(map.resolution_m(), resolution_m);
  EXPECT_EQ(map.occupied_leaves(), voxels.size());
  for (const Eigen::Vector3d& p : plane.cloud.points_m) {
    EXPECT_TRUE(map.IsOccupied(p)) << p.transpose();
    EXPECT_FALSE(map.IsOccupied(p + plane.unit_normal)) << "1 m off the plane at " << p.transpose();
    EXPECT_FALSE(map.IsOccupied(p - plane.unit_normal)) << "1 m off the plane at " << p.transpose();
  }
}

TEST(WriteOctoMap, SummaryBoxIsTheBoxOfTheOccupiedVoxels) {
  test::ScratchDir dir;
  const double resolution_m = 0.1;
  const PlaneCloud plane = PointsOnPlane(500, resolution_m, 3);
  Eigen::Vector3d lo = Eigen::Vector3d::Constant(std::numeric_limits<double>::infinity());
  Eigen::Vector3d hi = -lo;
  for (const Eigen::Vector3d& p : plane.cloud.points_m) {
    const VoxelIndex v = VoxelOf(p, resolution_m);
    const Eigen::Vector3d corner(static_cast<double>(v[0]), static_cast<double>(v[1]),
                                 static_cast<double>(v[2]));
    lo = lo.cwiseMin(corner * resolution_m);
    hi = hi.cwiseMax((corner + Eigen::Vector3d::Ones()) * resolution_m);
  }
  const OctoMapSummary summary =
      WriteOctoMap(plane.cloud, OctoMapOptions{resolution_m}, dir / "canopy.bt");
  EXPECT_TRUE(summary.min_m.isApprox(lo, 1e-9)) << summary.min_m.transpose() << " vs " << lo.transpose();
  EXPECT_TRUE(summary.max_m.isApprox(hi, 1e-9)) << summary.max_m.transpose() << " vs " << hi.transpose();
}

TEST(WriteOctoMap, VoxelsAreFlooredNotCentredOrTruncated) {
  // OctoMap's key is floor(x / r) + 32768: voxel i covers [i r, (i + 1) r). A point just below
  // zero is in voxel -1 (truncation towards zero would put it in voxel 0).
  test::ScratchDir dir;
  const double r = 0.05;
  const PointCloud cloud{{Eigen::Vector3d(-0.01, -0.01, -0.01), Eigen::Vector3d(0.26, 0.01, 0.49)}};
  const OctoMapSummary summary = WriteOctoMap(cloud, OctoMapOptions{r}, dir / "two.bt");
  EXPECT_EQ(summary.occupied_leaves, 2U);
  const CanopyOccupancyMap map = CanopyOccupancyMap::Load(dir / "two.bt");
  EXPECT_TRUE(map.IsOccupied(Eigen::Vector3d(-0.049, -0.049, -0.049)));  // same voxel (-1,-1,-1)
  EXPECT_TRUE(map.IsOccupied(Eigen::Vector3d(-0.001, -0.001, -0.001)));
  EXPECT_FALSE(map.IsOccupied(Eigen::Vector3d(0.001, 0.001, 0.001)));    // voxel (0,0,0)
  EXPECT_FALSE(map.IsOccupied(Eigen::Vector3d(-0.051, -0.01, -0.01)));   // voxel (-2,-1,-1)
  EXPECT_TRUE(map.IsOccupied(Eigen::Vector3d(0.251, 0.001, 0.451)));    // voxel (5,0,9)
  EXPECT_TRUE(map.IsOccupied(Eigen::Vector3d(0.299, 0.049, 0.499)));
  EXPECT_FALSE(map.IsOccupied(Eigen::Vector3d(0.301, 0.01, 0.49)));     // voxel (6,0,9)
}

TEST(WriteOctoMap, DuplicatePointsCountOnce) {
  test::ScratchDir dir;
  const Eigen::Vector3d p(1.23, -4.56, 0.78);
  const PointCloud cloud{{p, p, p, p + Eigen::Vector3d::Constant(1e-4)}};
  EXPECT_EQ(WriteOctoMap(cloud, OctoMapOptions{0.05}, dir / "dup.bt").occupied_leaves, 1U);
}

TEST(WriteOctoMap, RejectsBadResolution) {
  test::ScratchDir dir;
  const PointCloud cloud{{Eigen::Vector3d(0.5, 0.5, 0.5)}};
  for (const double resolution_m : {0.0, -0.05, 1e-9, 1e6, std::numeric_limits<double>::quiet_NaN(),
                                    std::numeric_limits<double>::infinity()}) {
    EXPECT_THROW(WriteOctoMap(cloud, OctoMapOptions{resolution_m}, dir / "bad.bt"),
                 std::invalid_argument)
        << resolution_m;
  }
  EXPECT_FALSE(std::filesystem::exists(dir / "bad.bt"));
}

TEST(WriteOctoMap, RejectsEmptyCloud) {
  test::ScratchDir dir;
  EXPECT_THROW(WriteOctoMap(PointCloud{}, OctoMapOptions{}, dir / "empty.bt"), std::invalid_argument);
}

TEST(WriteOctoMap, RejectsNonFiniteAndOutOfRangePointsNamingThem) {
  test::ScratchDir dir;
  PointCloud cloud{{Eigen::Vector3d::Zero(), Eigen::Vector3d(0.0, std::nan(""), 0.0)}};
  try {
    WriteOctoMap(cloud, OctoMapOptions{}, dir / "nan.bt");
    ADD_FAILURE() << "no error for a NaN point";
  } catch (const std::invalid_argument& e) {
    EXPECT_THAT(e.what(), HasSubstr("point 1"));
  }
  // At 5 cm the octree spans [-1638.4, 1638.4) m per axis.
  cloud.points_m[1] = Eigen::Vector3d(0.0, 1638.5, 0.0);
  EXPECT_THROW(WriteOctoMap(cloud, OctoMapOptions{0.05}, dir / "far.bt"), std::invalid_argument);
  cloud.points_m[1] = Eigen::Vector3d(0.0, 1e300, 0.0);
  EXPECT_THROW(WriteOctoMap(cloud, OctoMapOptions{0.05}, dir / "far.bt"), std::invalid_argument);
  cloud.points_m[1] = Eigen::Vector3d(-1638.3, 1638.3, 0.0);  // just inside
  EXPECT_EQ(WriteOctoMap(cloud, OctoMapOptions{0.05}, dir / "edge.bt").occupied_leaves, 2U);
}

TEST(WriteOctoMap, ReportsUnwritablePath) {
  test::ScratchDir dir;
  const PointCloud cloud{{Eigen::Vector3d(0.5, 0.5, 0.5)}};
  EXPECT_THROW(WriteOctoMap(cloud, OctoMapOptions{}, dir / "missing" / "map.bt"), OccupancyMapError);
}

TEST(CanopyOccupancyMap, LoadRejectsMissingAndGarbageFiles) {
  test::ScratchDir dir;
  EXPECT_THROW(CanopyOccupancyMap::Load(dir / "absent.bt"), OccupancyMapError);
  {
    std::ofstream out(dir / "garbage.bt");
    out << "# Octomap OcTree binary file\nnot really\n";
  }
  EXPECT_THROW(CanopyOccupancyMap::Load(dir / "garbage.bt"), OccupancyMapError);
  {
    std::ofstream out(dir / "text.bt");
    out << "hello\n";
  }
  EXPECT_THROW(CanopyOccupancyMap::Load(dir / "text.bt"), OccupancyMapError);
}

TEST(CanopyOccupancyMap, LoadChecksTheHeaderAgainstTheTree) {
  // A real file, then the same file with its header changed: each is refused with the reason.
  test::ScratchDir dir;
  PointCloud cloud;
  for (int k = 0; k < 50; ++k) cloud.points_m.emplace_back(0.1 * k, 0.0, 1.0);
  WriteOctoMap(cloud, OctoMapOptions{0.05}, dir / "good.bt");
  std::stringstream good;
  good << std::ifstream(dir / "good.bt", std::ios::binary).rdbuf();
  const std::string bytes = good.str();
  EXPECT_EQ(CanopyOccupancyMap::Load(dir / "good.bt").occupied_leaves(), 50U);
  const auto expect_refused = [&](const std::string& from, const std::string& to, const std::string& reason) {
    std::string patched = bytes;
    const auto at = patched.find(from);
    ASSERT_NE(at, std::string::npos) << from;
    patched.replace(at, from.size(), to);
    std::ofstream(dir / "patched.bt", std::ios::binary) << patched;
    try {
      CanopyOccupancyMap::Load(dir / "patched.bt");
      ADD_FAILURE() << "accepted: " << to;
    } catch (const OccupancyMapError& e) {
      EXPECT_THAT(e.what(), ::testing::HasSubstr(reason)) << to;
    }
  };
  expect_refused("id OcTree", "id ColorOcTree", "the tree type is 'ColorOcTree', not OcTree");
  expect_refused("\nsize ", "\nsize 9", "do not match its header");  // one more digit: more nodes than the data
  expect_refused("\ndata\n", "\n", "unknown header line '");  // the tree's bytes, shown as '?'
  expect_refused("id OcTree", "data", "'data' before 'id', 'size' and 'res'");
  expect_refused("\nres ", "\nrez ", "unknown header line 'rez ");
}

TEST(CanopyOccupancyMap, LoadReadsOnlyARegularFileOfBoundedSize) {
  // Issue 26 sibling: a FIFO, a device or a directory was "no such file", and OctoMap read the first
  // line of any regular file whole (a 256 MiB line of zeros: 256 MiB held).
  test::ScratchDir dir;
  const auto error_of = [](const std::filesystem::path& path) -> std::string {
    try {
      (void)CanopyOccupancyMap::Load(path);
    } catch (const OccupancyMapError& e) {
      return e.what();
    }
    return "loaded";
  };
  ASSERT_EQ(::mkfifo((dir / "fifo.bt").c_str(), 0600), 0);
  EXPECT_THAT(error_of(dir / "fifo.bt"), HasSubstr("fifo.bt': is a FIFO (named pipe), not a regular file"));
  EXPECT_THAT(error_of("/dev/zero"), HasSubstr("is a character device, not a regular file"));
  std::filesystem::create_directories(dir / "folder.bt");
  EXPECT_THAT(error_of(dir / "folder.bt"), HasSubstr("folder.bt': is a directory, not a regular file"));
  EXPECT_THAT(error_of(dir / "absent.bt"), HasSubstr("absent.bt': cannot open OctoMap file: No such file or directory"));
  std::ofstream(dir / "big.bt") << "# Octomap OcTree binary file";
  std::filesystem::resize_file(dir / "big.bt", kMaxOctoMapFileBytes + 1);  // sparse: zeros, no newline
  EXPECT_THAT(error_of(dir / "big.bt"), HasSubstr("big.bt': is larger than the limit of 256 MiB (OctoMap file)"));
}

TEST(CanopyOccupancyMap, QueriesOutsideTheMapAndBadQueries) {
  test::ScratchDir dir;
  WriteOctoMap(PointCloud{{Eigen::Vector3d(0.5, 0.5, 0.5)}}, OctoMapOptions{0.1}, dir / "one.bt");
  const CanopyOccupancyMap map = CanopyOccupancyMap::Load(dir / "one.bt");
  EXPECT_TRUE(map.IsOccupied(Eigen::Vector3d(0.55, 0.55, 0.55)));
  EXPECT_FALSE(map.IsOccupied(Eigen::Vector3d(1e9, 0.0, 0.0)));  // beyond the octree: unknown
  EXPECT_FALSE(map.IsOccupied(Eigen::Vector3d(-1e300, 0.0, 0.0)));
  EXPECT_THROW(map.IsOccupied(Eigen::Vector3d(std::nan(""), 0.0, 0.0)), std::invalid_argument);
}

TEST(CanopyOccupancyMap, IsMovableAndAMovedFromMapRefusesUse) {
  test::ScratchDir dir;
  WriteOctoMap(PointCloud{{Eigen::Vector3d(0.5, 0.5, 0.5)}}, OctoMapOptions{0.1}, dir / "one.bt");
  CanopyOccupancyMap first = CanopyOccupancyMap::Load(dir / "one.bt");
  CanopyOccupancyMap second = std::move(first);
  EXPECT_TRUE(second.IsOccupied(Eigen::Vector3d(0.5, 0.5, 0.5)));
  EXPECT_EQ(second.occupied_leaves(), 1U);
  EXPECT_THROW(first.resolution_m(), std::logic_error);  // NOLINT(bugprone-use-after-move)
  first = std::move(second);
  EXPECT_DOUBLE_EQ(first.resolution_m(), 0.1);
}

}  // namespace
}  // namespace rowloc::mapping
