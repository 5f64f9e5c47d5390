// CleanCloud: voxel downsampling in double, statistical outlier removal, empty clouds.
#include "rowloc/mapping/cloud_cleaning.hpp"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <random>
#include <stdexcept>

namespace rowloc::mapping {
namespace {

PointCloud Grid(double step, int n, const Eigen::Vector3d& offset) {
  PointCloud cloud;
  for (int i = 0; i < n; ++i) {
    for (int j = 0; j < n; ++j) cloud.points_m.push_back(offset + Eigen::Vector3d(i * step, j * step, 0.0));
  }
  return cloud;
}

TEST(CloudCleaningTest, VoxelDownsamplingKeepsOneCentroidPerVoxel) {
  // 20 x 20 voxels of 2 cm with 4 points each, 5 mm away from the voxel faces (voxels lie on the
  // lattice of multiples of 2 cm; a lone point at (-1, -1) has a voxel of its own).
  PointCloud cloud;
  cloud.points_m.emplace_back(-1.0, -1.0, 0.0);
  for (int a = 0; a < 20; ++a) {
    for (int b = 0; b < 20; ++b) {
      for (int da = 0; da < 2; ++da) {
        for (int db = 0; db < 2; ++db) {
          cloud.points_m.emplace_back(0.02 * a + 0.005 + 0.008 * da, 0.02 * b + 0.005 + 0.008 * db, 0.0);
        }
      }
    }
  }
  const CleanResult result = CleanCloud(cloud, CleanParams{0.02, 0, 3.0});
  EXPECT_EQ(result.points_in, 1601U);
  EXPECT_EQ(result.points_after_voxel, 401U);
  ASSERT_EQ(result.cloud.points_m.size(), 401U);
  for (const auto& p : result.cloud.points_m) {
    if (p.x() < 0.0) continue;  // the anchor
    const double ka = (p.x() - 0.009) / 0.02;
    const double kb = (p.y() - 0.009) / 0.02;
    EXPECT_NEAR(ka, std::round(ka), 1e-9);  // the centroid of its four points
    EXPECT_NEAR(kb, std::round(kb), 1e-9);
  }
}

TEST(CloudCleaningTest, VoxelDownsamplingKeepsMillimetresAtUtmCoordinates) {
  // Northings of 5e6 m would lose ~0.5 m in float; the voxel centroids must stay exact.
  const Eigen::Vector3d utm(500000.123, 5000000.456, 250.0);
  const PointCloud cloud = Grid(0.1, 10, utm);
  const CleanResult result = CleanCloud(cloud, CleanParams{0.02, 0, 3.0});
  ASSERT_EQ(result.cloud.points_m.size(), 100U);
  for (const auto& p : result.cloud.points_m) {
    const Eigen::Vector3d d = (p - utm) / 0.1;
    EXPECT_NEAR(d.x(), std::round(d.x()), 1e-6);
    EXPECT_NEAR(d.y(), std::round(d.y()), 1e-6);
  }
}

TEST(CloudCleaningTest, OutlierRemovalDropsAnIsolatedPoint) {
  // A jittered plane at UTM-sized coordinates (the filter runs in float relative to the centroid).
  PointCloud cloud = Grid(0.05, 30, Eigen::Vector3d(500000.0, 5000000.0, 10.0));
  for (std::size_t k = 0; k < cloud.points_m.size(); ++k) {
    cloud.points_m[k].x() += 0.01 * std::sin(1.7 * static_cast<double>(k));
    cloud.points_m[k].y() += 0.01 * std::cos(2.3 * static_cast<double>(k));
  }
  const PointCloud plane = cloud;
  cloud.points_m.emplace_back(500000.7, 5000000.7, 12.0);  // 2 m above the plane
  const CleanResult result = CleanCloud(cloud, CleanParams{0.0, 16, 3.0});
  EXPECT_GE(result.outliers_removed, 1U);
  EXPECT_LE(result.outliers_removed, 5U);  // (the plane's corners may go too)
  // The outlier is gone and every kept point is an input point, bit for bit.
  for (const auto& p : result.cloud.points_m) {
    EXPECT_EQ(p.z(), 10.0);
    EXPECT_NE(std::find(plane.points_m.begin(), plane.points_m.end(), p), plane.points_m.end());
  }
}

TEST(CloudCleaningTest, EmptyCloudGivesAnEmptyResultAndBadParametersThrow) {
  const CleanResult result = CleanCloud(PointCloud{}, CleanParams{});
  EXPECT_TRUE(result.cloud.points_m.empty());
  EXPECT_EQ(result.points_in, 0U);
  EXPECT_THROW(CleanCloud(PointCloud{}, CleanParams{-0.1, 16, 3.0}), std::invalid_argument);
  EXPECT_THROW(CleanCloud(PointCloud{}, CleanParams{0.02, -1, 3.0}), std::invalid_argument);
}

TEST(CloudCleaningTest, ATooFineGridIsRefused) {
  PointCloud cloud;
  cloud.points_m = {Eigen::Vector3d::Zero(), Eigen::Vector3d(1e5, 0.0, 0.0)};
  EXPECT_THROW(CleanCloud(cloud, CleanParams{0.001, 0, 3.0}), std::invalid_argument);
}

TEST(CloudCleaningTest, VoxelsLieOnALatticeSoThatTilesAgree) {
  // A cloud and the same cloud with a far point at an odd position: the voxels of the common
  // points, and so their centroids, are the same (tiles of one survey see the same voxels).
  std::mt19937_64 rng(3);
  std::uniform_real_distribution<double> u(0.0, 0.5);
  PointCloud a;
  for (int k = 0; k < 3000; ++k) a.points_m.emplace_back(u(rng), u(rng), u(rng));
  PointCloud b = a;
  b.points_m.emplace_back(-0.0137, -0.0291, -0.0333);
  const CleanResult ra = CleanCloud(a, CleanParams{0.02, 0, 3.0});
  const CleanResult rb = CleanCloud(b, CleanParams{0.02, 0, 3.0});
  ASSERT_EQ(rb.cloud.points_m.size(), ra.cloud.points_m.size() + 1);
  for (const auto& p : ra.cloud.points_m) {
    const bool found = std::any_of(rb.cloud.points_m.begin(), rb.cloud.points_m.end(),
                                   [&p](const Eigen::Vector3d& q) { return (p - q).norm() < 1e-12; });
    EXPECT_TRUE(found) << p.transpose();
  }
}

TEST(CloudCleaningTest, OutlierRemovalMatchesTheBruteForceStatisticOnAnyThreadCount) {
  // Rusu et al. (2008): d_i = mean distance to the k nearest neighbours; outliers have
  // d_i > mean(d) + f stddev(d) (sample standard deviation). Brute force over 600 points.
  std::mt19937_64 rng(4);
  std::normal_distribution<double> n(0.0, 0.2);
  PointCloud cloud;
  for (int k = 0; k < 580; ++k) cloud.points_m.emplace_back(n(rng), n(rng), 0.1 * n(rng));
  std::uniform_real_distribution<double> far(-3.0, 3.0);
  for (int k = 0; k < 20; ++k) cloud.points_m.emplace_back(far(rng), far(rng), far(rng));
  const int k_nn = 8;
  const double factor = 1.5;
  std::vector<double> d;
  for (const auto& p : cloud.points_m) {
    std::vector<double> all;
    for (const auto& q : cloud.points_m) all.push_back((p - q).norm());
    std::sort(all.begin(), all.end());  // all[0] = 0: the point itself
    double sum = 0.0;
    for (int j = 1; j <= k_nn; ++j) sum += all[static_cast<std::size_t>(j)];
    d.push_back(sum / k_nn);
  }
  double mean = 0.0;
  for (double v : d) mean += v / static_cast<double>(d.size());
  double var = 0.0;
  for (double v : d) var += (v - mean) * (v - mean) / static_cast<double>(d.size() - 1);
  const double threshold = mean + factor * std::sqrt(var);
  std::vector<Eigen::Vector3d> expected;
  for (std::size_t i = 0; i < d.size(); ++i) {
    // Points within float rounding of the threshold could go either way; there are none here.
    ASSERT_GT(std::abs(d[i] - threshold), 1e-5);
    if (d[i] <= threshold) expected.push_back(cloud.points_m[i]);
  }
  ASSERT_LT(expected.size(), cloud.points_m.size());  // the test removes something
  for (int threads : {1, 2, 5}) {
    const CleanResult result = CleanCloud(cloud, CleanParams{0.0, k_nn, factor}, threads);
    EXPECT_EQ(result.cloud.points_m, expected) << threads << " threads";
    EXPECT_EQ(result.outliers_removed, cloud.points_m.size() - expected.size());
  }
}

}  // namespace
}  // namespace rowloc::mapping
