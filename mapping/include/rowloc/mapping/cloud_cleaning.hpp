// Step 1 of the map build (docs/mapping.md): voxel downsampling and statistical outlier removal.
//
// Voxel downsampling is done here in double precision (one centroid per occupied voxel of edge
// voxel_size_m, voxels keyed by floor((p - min) / size)); PCL's VoxelGrid works in float and
// refuses grids with more than 2^31 voxels, i.e. fields larger than ~250 m at 2 cm. The outlier
// removal is PCL's StatisticalOutlierRemoval (k nearest neighbours through a FLANN k-d tree), run
// on float coordinates relative to the cloud's centroid so that UTM-sized coordinates keep their
// millimetres. The output order is deterministic (voxel key order).
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
/// grid of more than 2^21 voxels along an axis.
CleanResult CleanCloud(const PointCloud& cloud, const CleanParams& params);

}  // namespace rowloc::mapping
