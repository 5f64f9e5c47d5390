// Step 1 of the map build (docs/mapping.md): voxel downsampling and statistical outlier removal.
//
// Voxel downsampling is done here in double precision (one centroid per occupied voxel of edge
// voxel_size_m, voxel (i, j, k) = [i s, (i+1) s) x [j s, ...) x [k s, ...): a lattice anchored at the
// coordinate origin, so that overlapping tiles of one survey agree on their common voxels); PCL's
// VoxelGrid works in float and refuses grids with more than 2^31 voxels, i.e. fields larger than
// ~250 m at 2 cm. At most 2^21 voxels per axis and 2^32 points per call (a tile).
//
// The outlier removal is the statistical filter of Rusu et al. (2008), as PCL's
// StatisticalOutlierRemoval computes it: for every point the mean distance d_i to its k nearest
// neighbours (PCL's KdTreeFLANN); outliers are the points with d_i > mean(d) + f stddev(d). It is
// written out here (30 lines around PCL's k-d tree) for two reasons, both measured: PCL 1.13 runs
// the k-NN queries on one thread (they are ~90 % of the map build's time), here they are split over
// `threads` threads sharing the tree; and PCL drops the first result as "the query point" although
// its tree returns unsorted results, so it skips an arbitrary neighbour instead (here the query
// point's zero distance is simply summed). It runs on float coordinates relative to the cloud's
// centroid so that UTM-sized coordinates keep their millimetres. The result does not depend on
// `threads`; the output order is deterministic (voxel order).
#pragma once

#include "rowloc/mapping/map_build_config.hpp"
#include "rowloc/mapping/point_cloud.hpp"

#include <cstddef>

namespace rowloc::mapping {

struct CleanResult {
  PointCloud cloud;                   ///< the cleaned cloud
  std::size_t points_in = 0;          ///< input points
  std::size_t points_after_voxel = 0; ///< after downsampling
  std::size_t outliers_removed = 0;   ///< removed by the outlier filter
  double voxel_seconds = 0.0;         ///< time of the downsampling
  double outlier_seconds = 0.0;       ///< time of the outlier removal
};

/// Downsamples (if voxel_size_m > 0) then removes statistical outliers (if outlier_neighbours > 0
/// and the cloud has more points than that). An empty cloud gives an empty result.
/// Throws std::invalid_argument for parameters outside the domains of map_build_config.hpp or a
/// grid of more than 2^21 voxels along an axis. threads: threads of the outlier removal's queries.
CleanResult CleanCloud(const PointCloud& cloud, const CleanParams& params, int threads = 1);

}  // namespace rowloc::mapping
