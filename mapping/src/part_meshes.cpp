// A lofted mesh per row part, with its check against the map's outline (see part_meshes.hpp).
#include "rowloc/mapping/part_meshes.hpp"

#include "rowloc/geometry/segment_index.hpp"
#include "rowloc/mapping/mesh_slicer.hpp"
#include "rowloc/mapping/row_mesh.hpp"
#include "rowloc/mapping/row_outline.hpp"

#include <algorithm>
#include <cmath>
#include <limits>
#include <stdexcept>

namespace rowloc::mapping {

double LargestDistanceToPolygon(const std::vector<Eigen::Vector3d>& points_m,
                                const std::vector<Eigen::Vector2d>& polygon_m) {
  // The polygon's edges in the R-tree of rowloc::geometry (Boost.Geometry), degenerate ones left out.
  std::vector<geometry::SegmentIndex::Entry> edges;
  for (std::size_t i = 0; i < polygon_m.size(); ++i) {
    const Eigen::Vector2d& a = polygon_m[i];
    const Eigen::Vector2d& b = polygon_m[(i + 1) % polygon_m.size()];
    if ((b - a).norm() > 1e-9) edges.push_back({geometry::Segment2{a, b}, 0, i});
  }
  if (edges.empty()) return points_m.empty() ? 0.0 : std::numeric_limits<double>::infinity();
  const geometry::SegmentIndex index(std::move(edges));
  double largest = 0.0;
  for (const auto& point : points_m) largest = std::max(largest, index.Nearest(point.head<2>(), 1).front().first);
  return largest;
}

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
  for (std::size_t level = 0; level < heights.size(); ++level) {
    const std::vector<std::vector<Eigen::Vector2d>> by_part =
        AssignPointsToParts(detection, level_band_m[level], config.rows.link_radius_m);
    std::vector<Eigen::Vector2d>().swap(level_band_m[level]);
    for (std::size_t part = 0; part < part_count; ++part) {
      if (outlines_m[part].size() < 3) continue;
      const PartOutline outline = TraceOutline(by_part[part], config.outline);
      if (outline.polygon_m.size() < 3) continue;
      // The canopy is missing or thin at this height: a shorter outline would twist the loft.
      if (RingPerimeter(outline.polygon_m) < 0.9 * RingPerimeter(outlines_m[part])) continue;
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
      // The cut sampled every 1 cm along its edges (its vertices alone would miss the chords), against
      // the part's traced outline (5 cm stations).
      std::vector<Eigen::Vector3d> cut;
      for (const Polyline3& piece : SliceMesh(*out.mesh, Eigen::Vector3d::UnitZ(), h_ref)) {
        const std::size_t n = piece.points_m.size();
        for (std::size_t i = 0; i < n && n >= 2; ++i) {
          if (!piece.closed && i + 1 == n) break;
          const Eigen::Vector3d& a = piece.points_m[i];
          const Eigen::Vector3d& b = piece.points_m[(i + 1) % n];
          const int steps = std::max(1, static_cast<int>(std::ceil((b - a).norm() / 0.01)));
          for (int s = 0; s < steps; ++s) cut.push_back(a + (b - a) * (static_cast<double>(s) / steps));
        }
      }
      if (!cut.empty()) out.slice_max_m = LargestDistanceToPolygon(cut, outlines_m[part]);
    }
  }
  return meshes;
}

}  // namespace rowloc::mapping
