// Voxel downsampling (double precision) and PCL's statistical outlier removal (see cloud_cleaning.hpp).
#include "rowloc/mapping/cloud_cleaning.hpp"

#include <pcl/filters/statistical_outlier_removal.h>
#include <pcl/point_cloud.h>
#include <pcl/point_types.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdint>
#include <stdexcept>
#include <unordered_map>
#include <utility>
#include <vector>

namespace rowloc::mapping {
namespace {

constexpr std::int64_t kAxisCells = std::int64_t{1} << 21;

PointCloud VoxelDownsample(const PointCloud& cloud, double size_m) {
  Eigen::Vector3d lo = cloud.points_m.front();
  Eigen::Vector3d hi = lo;
  for (const auto& p : cloud.points_m) {
    lo = lo.cwiseMin(p);
    hi = hi.cwiseMax(p);
  }
  for (int a = 0; a < 3; ++a) {
    if ((hi[a] - lo[a]) / size_m >= static_cast<double>(kAxisCells - 1)) {
      throw std::invalid_argument("CleanCloud: the cloud spans " + std::to_string(hi[a] - lo[a]) +
                                  " m, more than 2^21 voxels of " + std::to_string(size_m) + " m");
    }
  }
  struct Sum {
    Eigen::Vector3d sum = Eigen::Vector3d::Zero();
    std::size_t count = 0;
  };
  std::unordered_map<std::uint64_t, Sum> voxels;
  voxels.reserve(cloud.points_m.size());
  for (const auto& p : cloud.points_m) {
    std::uint64_t key = 0;
    for (int a = 0; a < 3; ++a) {
      const auto cell = static_cast<std::uint64_t>(std::floor((p[a] - lo[a]) / size_m));
      key = (key << 21) | cell;
    }
    Sum& s = voxels[key];
    s.sum += p - lo;  // relative to the corner: sums stay small
    ++s.count;
  }
  std::vector<std::pair<std::uint64_t, Eigen::Vector3d>> centroids;
  centroids.reserve(voxels.size());
  for (const auto& [key, s] : voxels) {
    centroids.emplace_back(key, lo + s.sum / static_cast<double>(s.count));
  }
  std::sort(centroids.begin(), centroids.end(),
            [](const auto& a, const auto& b) { return a.first < b.first; });
  PointCloud out;
  out.points_m.reserve(centroids.size());
  for (const auto& c : centroids) out.points_m.push_back(c.second);
  return out;
}

PointCloud RemoveOutliers(const PointCloud& cloud, int neighbours, double stddev_factor,
                          std::size_t& removed) {
  Eigen::Vector3d centre = Eigen::Vector3d::Zero();
  for (const auto& p : cloud.points_m) centre += p;
  centre /= static_cast<double>(cloud.points_m.size());
  pcl::PointCloud<pcl::PointXYZ>::Ptr input(new pcl::PointCloud<pcl::PointXYZ>);
  input->points.reserve(cloud.points_m.size());
  for (const auto& p : cloud.points_m) {
    const Eigen::Vector3d q = p - centre;
    input->points.emplace_back(static_cast<float>(q.x()), static_cast<float>(q.y()),
                               static_cast<float>(q.z()));
  }
  input->width = static_cast<std::uint32_t>(input->points.size());
  input->height = 1;
  input->is_dense = true;
  pcl::StatisticalOutlierRemoval<pcl::PointXYZ> filter;
  filter.setInputCloud(input);
  filter.setMeanK(neighbours);
  filter.setStddevMulThresh(stddev_factor);
  pcl::Indices kept;
  filter.filter(kept);
  std::sort(kept.begin(), kept.end());
  PointCloud out;
  out.points_m.reserve(kept.size());
  for (const auto i : kept) out.points_m.push_back(cloud.points_m[static_cast<std::size_t>(i)]);
  removed = cloud.points_m.size() - out.points_m.size();
  return out;
}

}  // namespace

CleanResult CleanCloud(const PointCloud& cloud, const CleanParams& params) {
  if (!(params.voxel_size_m >= 0.0 && params.voxel_size_m <= 1.0)) {
    throw std::invalid_argument("CleanCloud: voxel_size_m must be in [0, 1]");
  }
  if (params.outlier_neighbours < 0 || params.outlier_neighbours > 200) {
    throw std::invalid_argument("CleanCloud: outlier_neighbours must be in [0, 200]");
  }
  if (!(params.outlier_stddev_factor > 0.0) || !std::isfinite(params.outlier_stddev_factor)) {
    throw std::invalid_argument("CleanCloud: outlier_stddev_factor must be positive");
  }
  CleanResult result;
  result.points_in = cloud.points_m.size();
  if (cloud.points_m.empty()) return result;
  auto start = std::chrono::steady_clock::now();
  result.cloud = params.voxel_size_m > 0.0 ? VoxelDownsample(cloud, params.voxel_size_m) : cloud;
  result.points_after_voxel = result.cloud.points_m.size();
  result.voxel_seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  start = std::chrono::steady_clock::now();
  if (params.outlier_neighbours > 0 &&
      result.cloud.points_m.size() > static_cast<std::size_t>(params.outlier_neighbours)) {
    result.cloud = RemoveOutliers(result.cloud, params.outlier_neighbours,
                                  params.outlier_stddev_factor, result.outliers_removed);
  }
  result.outlier_seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  return result;
}

}  // namespace rowloc::mapping
