// Steps 5-6 of the map build, mesh route (docs/mapping.md, "Row meshes"): a lofted mesh per row part.
//
// BuildPartMeshes: the band points at each mesh level (MeshLevelHeights; gathered per tile by
// NormalizeTile) are given to the parts they lie near (AssignPointsToParts, rows.link_radius_m);
// per part and level, TraceOutline; the outlines at least 90 % as long as the part's outline at
// h_ref (a level where the canopy is missing or thin gives a shorter or no outline: left out) are
// lofted (LoftRings) into a mesh in (x, y, h), h = height above the terrain. Each mesh is then cut
// at h_ref by CGAL's Polygon_mesh_slicer (SliceMesh) and the cut compared with the part's outline
// traced at h_ref (LargestDistanceToOutlines, map_comparison.hpp): the largest distance is reported
// (a check that the mesh and the map agree).
#pragma once

#include "rowloc/mapping/map_build_config.hpp"
#include "rowloc/mapping/row_segmentation.hpp"
#include "rowloc/mapping/triangle_mesh.hpp"

#include <Eigen/Core>

#include <optional>
#include <vector>

namespace rowloc::mapping {

struct PartMesh {
  std::optional<TriangleMesh> mesh;  ///< vertices (x, y, h); nullopt: fewer than two usable levels
  int levels = 0;                    ///< outlines lofted
  std::optional<double> slice_max_m; ///< largest distance of the cut at h_ref (sampled every 1 cm) to the h_ref outline
};

/// One PartMesh per part of `detection` (rows[r].parts[p] flattened). level_band_m: per mesh level,
/// the band points (x, y) at that height (taken: each level is freed once given to the parts); outlines_m: per part, its outline at h_ref (empty: the
/// part has none, and gets no mesh). Returns no meshes when config.mesh.levels is 0. Throws
/// std::invalid_argument if the list sizes do not match the detection and the configuration.
std::vector<PartMesh> BuildPartMeshes(const RowDetection& detection,
                                      std::vector<std::vector<Eigen::Vector2d>> level_band_m,
                                      const std::vector<std::vector<Eigen::Vector2d>>& outlines_m,
                                      const MapBuildConfig& config);

}  // namespace rowloc::mapping
