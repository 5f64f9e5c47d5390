// Voxel downsampling (double precision) and the statistical outlier removal on FLANN (see cloud_cleaning.hpp).
#include "rowloc/mapping/cloud_cleaning.hpp"

#include <flann/algorithms/dist.h>
#include <flann/algorithms/kdtree_single_index.h>
#include <flann/util/matrix.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdint>
#include <exception>
#include <limits>
#include <stdexcept>
#include <thread>
#include <utility>
#include <vector>

namespace rowloc::mapping {
namespace {

constexpr std::int64_t kAxisCells = std::int64_t{1} << 21;

/// The 21 low bits of v spread to every third bit (bit k -> bit 3k).
std::uint64_t SpreadBits21(std::uint64_t v) {
  v &= 0x1FFFFF;
  v = (v | (v << 32)) & 0x1F00000000FFFF;
  v = (v | (v << 16)) & 0x1F0000FF0000FF;
  v = (v | (v << 8)) & 0x100F00F00F00F00F;
  v = (v | (v << 4)) & 0x10C30C30C30C30C3;
  v = (v | (v << 2)) & 0x1249249249249249;
  return v;
}

PointCloud VoxelDownsample(const PointCloud& cloud, double size_m) {
  // Voxel (i, j, k) is [i s, (i+1) s) x ... in the cloud's own coordinates: a lattice anchored at 0,
  // not at the cloud's corner, so that overlapping tiles of one survey get the same voxels.
  Eigen::Vector3d lo = cloud.points_m.front();
  Eigen::Vector3d hi = lo;
  for (const auto& p : cloud.points_m) {
    lo = lo.cwiseMin(p);
    hi = hi.cwiseMax(p);
  }
  const Eigen::Vector3d first_cell = (lo / size_m).array().floor();
  for (int a = 0; a < 3; ++a) {
    if (std::floor(hi[a] / size_m) - first_cell[a] >= static_cast<double>(kAxisCells - 1)) {
      throw std::invalid_argument("CleanCloud: the cloud spans " + std::to_string(hi[a] - lo[a]) +
                                  " m, more than 2^21 voxels of " + std::to_string(size_m) + " m");
    }
  }
  if (cloud.points_m.size() > std::numeric_limits<std::uint32_t>::max()) {
    throw std::invalid_argument("CleanCloud: more than 2^32 points in one call; tile the cloud");
  }
  const Eigen::Vector3d corner = first_cell * size_m;
  // Sort (voxel, point index) pairs and average each run: O(n log n), no hash table, and each
  // voxel's points are summed in their input order, so the centroids do not depend on the sort.
  std::vector<std::pair<std::uint64_t, std::uint32_t>> keyed(cloud.points_m.size());
  for (std::size_t n = 0; n < cloud.points_m.size(); ++n) {
    const Eigen::Vector3d& p = cloud.points_m[n];
    // Morton (Z-order) key: voxels close in space are close in the output, so that the outlier
    // removal's k-NN queries, run in this order, reuse the k-d tree's cached nodes.
    std::uint64_t key = 0;
    for (int a = 0; a < 3; ++a) {
      const auto cell = static_cast<std::uint64_t>(std::floor(p[a] / size_m) - first_cell[a]);
      key |= SpreadBits21(cell) << a;
    }
    keyed[n] = {key, static_cast<std::uint32_t>(n)};
  }
  std::sort(keyed.begin(), keyed.end());
  PointCloud out;
  for (std::size_t begin = 0; begin < keyed.size();) {
    std::size_t end = begin;
    Eigen::Vector3d sum = Eigen::Vector3d::Zero();
    while (end < keyed.size() && keyed[end].first == keyed[begin].first) {
      sum += cloud.points_m[keyed[end].second] - corner;  // relative to the corner: sums stay small
      ++end;
    }
    out.points_m.push_back(corner + sum / static_cast<double>(end - begin));
    begin = end;
  }
  return out;
}

/// The mean distance of every point to its k nearest neighbours: one FLANN k-d tree
/// (KDTreeSingleIndex, the index behind PCL's KdTreeFLANN, exact search), queried in batches
/// from `threads` threads (queries only read the tree). Calling FLANN here rather than through
/// pcl::KdTreeFLANN matters: PCL's precompiled tree enters an OpenMP parallel region per query,
/// which cost ~20 % of the time in futex calls (perf, 2026-12-04), and PCL 1.13's
/// StatisticalOutlierRemoval runs its queries on one thread. PCL's filter also drops result 0 as
/// "the query point" although its tree returns unsorted results, so it skips an arbitrary
/// neighbour; here all k + 1 distances are summed (the query point's is 0).
std::vector<float> MeanNeighbourDistances(std::vector<float>& xyz, int neighbours, int threads) {
  const std::size_t n = xyz.size() / 3;
  const flann::Matrix<float> data(xyz.data(), n, 3);
  flann::KDTreeSingleIndex<flann::L2_Simple<float>> index(data, flann::KDTreeSingleIndexParams(15));
  index.buildIndex();
  const std::size_t k = static_cast<std::size_t>(neighbours) + 1;
  std::vector<float> distances(n, 0.0F);
  const auto run = [&](std::size_t first, std::size_t last) {
    constexpr std::size_t kBatch = 2048;
    std::vector<std::size_t> found(kBatch * k);
    std::vector<float> squared(kBatch * k);
    flann::SearchParams params(flann::FLANN_CHECKS_UNLIMITED, 0.0F, false);
    for (std::size_t begin = first; begin < last; begin += kBatch) {
      const std::size_t count = std::min(kBatch, last - begin);
      const flann::Matrix<float> queries(xyz.data() + 3 * begin, count, 3);
      flann::Matrix<std::size_t> indices(found.data(), count, k);
      flann::Matrix<float> dists(squared.data(), count, k);
      index.knnSearch(queries, indices, dists, k, params);
      for (std::size_t q = 0; q < count; ++q) {
        double sum = 0.0;
        for (std::size_t j = 0; j < k; ++j) {
          if (found[q * k + j] < n) sum += std::sqrt(static_cast<double>(squared[q * k + j]));
        }
        distances[begin + q] = static_cast<float>(sum / neighbours);
      }
    }
  };
  const std::size_t parts = static_cast<std::size_t>(std::max(1, threads));
  std::vector<std::exception_ptr> errors(parts);
  const auto guarded = [&](std::size_t t) {
    try {
      run(t * n / parts, (t + 1) * n / parts);
    } catch (...) {
      errors[t] = std::current_exception();  // rethrown on the calling thread
    }
  };
  std::vector<std::thread> workers;
  for (std::size_t t = 1; t < parts; ++t) workers.emplace_back(guarded, t);
  guarded(0);
  for (auto& w : workers) w.join();
  for (const auto& e : errors) {
    if (e) std::rethrow_exception(e);
  }
  return distances;
}

PointCloud RemoveOutliers(const PointCloud& cloud, int neighbours, double stddev_factor, int threads,
                          std::size_t& removed) {
  Eigen::Vector3d centre = Eigen::Vector3d::Zero();
  for (const auto& p : cloud.points_m) centre += p;
  centre /= static_cast<double>(cloud.points_m.size());
  std::vector<float> xyz;
  xyz.reserve(3 * cloud.points_m.size());
  for (const auto& p : cloud.points_m) {
    const Eigen::Vector3d q = p - centre;
    xyz.push_back(static_cast<float>(q.x()));
    xyz.push_back(static_cast<float>(q.y()));
    xyz.push_back(static_cast<float>(q.z()));
  }
  const std::vector<float> distances = MeanNeighbourDistances(xyz, neighbours, threads);
  // Rusu et al. (2008): outlier if the mean distance exceeds mean + f * stddev over the cloud.
  double sum = 0.0;
  double squares = 0.0;
  for (const float d : distances) {
    const auto v = static_cast<double>(d);
    sum += v;
    squares += v * v;
  }
  const auto count = static_cast<double>(distances.size());
  const double mean = sum / count;
  const double variance = count > 1.0 ? std::max(0.0, (squares - sum * sum / count) / (count - 1.0)) : 0.0;
  const double threshold = mean + stddev_factor * std::sqrt(variance);
  PointCloud out;
  out.points_m.reserve(cloud.points_m.size());
  for (std::size_t i = 0; i < distances.size(); ++i) {
    if (static_cast<double>(distances[i]) <= threshold) out.points_m.push_back(cloud.points_m[i]);
  }
  removed = cloud.points_m.size() - out.points_m.size();
  return out;
}

}  // namespace

CleanResult CleanCloud(const PointCloud& cloud, const CleanParams& params, int threads) {
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
                                  params.outlier_stddev_factor, threads, result.outliers_removed);
  }
  result.outlier_seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  return result;
}

}  // namespace rowloc::mapping
