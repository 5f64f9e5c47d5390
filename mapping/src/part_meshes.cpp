// A lofted mesh per row part, with its check against the map's outline (see part_meshes.hpp).
#include "rowloc/mapping/part_meshes.hpp"

#include "rowloc/geometry/row_map.hpp"
#include "rowloc/mapping/map_comparison.hpp"
#include "rowloc/mapping/mesh_slicer.hpp"
#include "rowloc/mapping/row_mesh.hpp"
#include "rowloc/mapping/row_outline.hpp"

#include <algorithm>
#include <cmath>
#include <limits>
#include <stdexcept>

namespace rowloc::mapping {

std::vector<PartMesh> BuildPartMeshes(const RowDetection& detection,
                                      std::vector<std::vector<Eigen::Vector2d>> level_band_m,
                                      const std::vector<std::vector<Eigen::Vector2d>>& outlines_m,
                                      const MapBuildConfig& config) {
  const std::vector<double> heights = MeshLevelHeights(config.mesh);
  std::size_t part_count = 0;
  for (const DetectedRow& row : detection.rows) part_count += row.parts.size();
  if (outlines_m.size() != part_count || level_band_m.size() != heights.size()) {
    throw std::invalid_argument("BuildPartMeshes: one outline per part and one band per mesh level are needed");
  }
  std::vector<PartMesh> meshes(heights.empty() ? 0 : part_count);
  if (heights.empty()) return meshes;
  // One level at a time (memory: one level's points assigned to the parts), lowest first.
  std::vector<std::vector<OutlineAtHeight>> rings(part_count);
  std::vector<double> reference_perimeter(part_count, 0.0);
  for (std::size_t part = 0; part < part_count; ++part) reference_perimeter[part] = RingPerimeter(outlines_m[part]);
  for (std::size_t level = 0; level < heights.size(); ++level) {
    const std::vector<std::vector<Eigen::Vector2d>> by_part =
        AssignPointsToParts(detection, level_band_m[level], config.rows.link_radius_m);
    std::vector<Eigen::Vector2d>().swap(level_band_m[level]);
    for (std::size_t part = 0; part < part_count; ++part) {
      if (outlines_m[part].size() < 3) continue;
      const PartOutline outline = TraceOutline(by_part[part], config.outline);
      if (outline.polygon_m.size() < 3) continue;
      // The canopy is missing or thin at this height: a shorter outline would twist the loft.
      if (RingPerimeter(outline.polygon_m) < 0.9 * reference_perimeter[part]) continue;
      rings[part].push_back({heights[level], outline.polygon_m});
    }
  }
  for (std::size_t part = 0; part < part_count; ++part) {
    if (rings[part].size() < 2) continue;
    PartMesh& out = meshes[part];
    out.mesh = LoftRings(rings[part], config.mesh.vertex_spacing_m, RingSampling::kTwoEdges);
    if (!out.mesh) continue;
    out.levels = static_cast<int>(rings[part].size());
    const double h_ref = config.band.reference_height_m;
    if (h_ref > rings[part].front().height_m && h_ref < rings[part].back().height_m) {
      // The cut, sampled every 1 cm along its edges (its vertices alone would miss the chords),
      // against the part's traced outline (5 cm stations).
      geometry::RowMap cut;
      for (const Polyline3& piece : SliceMesh(*out.mesh, Eigen::Vector3d::UnitZ(), h_ref)) {
        geometry::Row row{"cut", {}, piece.closed};
        for (const auto& p : piece.points_m) row.points_m.push_back(p.head<2>());
        if (row.points_m.size() >= 2) cut.rows.push_back(std::move(row));
      }
      geometry::RowMap outline;
      outline.rows.push_back(geometry::Row{"outline", outlines_m[part], true, 0.0});
      if (!cut.rows.empty()) out.slice_max_m = LargestDistanceToOutlines(cut, outline, 0.01);
    }
  }
  return meshes;
}

}  // namespace rowloc::mapping
