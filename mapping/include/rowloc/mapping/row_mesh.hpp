// Steps 5-6 of the map build, mesh route (docs/mapping.md, "Row meshes"): one part's outlines at
// several heights above the terrain lofted into a closed, low-complexity triangle mesh in
// height-normalized coordinates (x, y, h = height above the terrain), which CGAL's
// Polygon_mesh_slicer (mesh_slicer.hpp) cuts at any height between the lowest and highest outline.
//
// LoftRings: every ring is made counter-clockwise and resampled by arc length to the same number
// of vertices M = max(8, ceil(longest ring's perimeter / vertex_spacing_m)), each ring starting at
// its vertex nearest to the previous ring's start (so the sides do not twist); or, for outlines
// traced along a centre line (RingSampling::kTwoEdges), each of the two long edges resampled from
// corner to corner to N = max(2, ceil(longest edge / spacing) + 1) vertices; ring k's vertex i
// and ring k+1's vertices i, i+1 make the side triangles (outward normals); the lowest and the
// highest ring are closed by TriangulatePolygon (polyline_simplification.hpp, CGAL). The result has
// M * L vertices and 2 M (L - 1) + 2 (M - 2) triangles for L rings: ~800 per 100 m of row at the
// default 0.5 m spacing and 6 levels. A slice at a ring's height gives that (resampled) ring; between
// two rings, the linear interpolation of their matching vertices.
#pragma once

#include "rowloc/mapping/triangle_mesh.hpp"

#include <Eigen/Core>

#include <optional>
#include <vector>

namespace rowloc::mapping {

/// A part's outline at one height above the terrain (closed, first point not repeated).
struct OutlineAtHeight {
  double height_m = 0.0;
  std::vector<Eigen::Vector2d> ring_m;
};

/// How rings are matched vertex to vertex.
enum class RingSampling {
  /// Each ring resampled along its whole perimeter from the vertex nearest the previous ring's start.
  kPerimeter,
  /// Rings made like TraceOutline's outlines: the first half of the vertices is the right edge
  /// (forward), the second half the left edge (backward), the caps the two joins. Each edge is
  /// resampled from its first to its last vertex, so the four corners stay exact and match.
  kTwoEdges,
};

/// The lofted mesh (above) with vertices (x, y, h). nullopt if a cap ring, once resampled, is not
/// a simple polygon (or, with kTwoEdges, a ring is clockwise or has an odd number of vertices). Throws std::invalid_argument if there are fewer than two rings, heights do not
/// strictly increase, a ring has fewer than 3 vertices or a zero perimeter, a value is not finite,
/// or vertex_spacing_m is not positive.
std::optional<TriangleMesh> LoftRings(const std::vector<OutlineAtHeight>& rings, double vertex_spacing_m,
                                      RingSampling sampling = RingSampling::kPerimeter);

/// The length of a closed ring (its last point joins its first).
double RingPerimeter(const std::vector<Eigen::Vector2d>& ring_m);

/// A closed ring resampled to `count` points equally spaced by arc length, from `start` (an index
/// into ring_m). Throws std::invalid_argument for fewer than 3 points, count < 3 or a zero perimeter.
std::vector<Eigen::Vector2d> ResampleRing(const std::vector<Eigen::Vector2d>& ring_m, std::size_t start,
                                          std::size_t count);

}  // namespace rowloc::mapping
