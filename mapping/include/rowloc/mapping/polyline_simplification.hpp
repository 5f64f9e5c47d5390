// Step 7 of the map build (docs/mapping.md): simplification of a closed outline with CGAL's
// Polyline_simplification_2 (Douglas-Peucker-like vertex removal in a constrained triangulation,
// so that the result never intersects itself; cost: the largest squared distance between the
// simplified and the original polyline; stop when that would exceed tolerance_m^2).
//
// This header exposes Eigen and the standard library only; CGAL stays in polyline_simplification.cpp.
#pragma once

#include <Eigen/Core>

#include <array>
#include <vector>

namespace rowloc::mapping {

struct SimplifiedPolygon {
  std::vector<Eigen::Vector2d> points_m;  ///< closed, first point not repeated
  bool simplified = false;  ///< false: returned unchanged (tolerance 0, < 4 vertices or not simple)
};

/// Simplifies a closed polygon to within tolerance_m of the original. A polygon that is not simple
/// (self-intersecting: CGAL's triangulation would refuse its constraints) or has fewer than four
/// vertices is returned unchanged with simplified = false. Throws std::invalid_argument for a
/// negative or non-finite tolerance or non-finite points.
SimplifiedPolygon SimplifyPolygon(const std::vector<Eigen::Vector2d>& polygon_m, double tolerance_m);

/// The triangles of a simple polygon (closed, first point not repeated), as indices into polygon_m,
/// counter-clockwise: a constrained Delaunay triangulation of its edges (CGAL), the faces inside
/// kept. Uses the polygon's vertices only (no new points), so it closes a mesh whose rim is the
/// polygon. Empty if the polygon has fewer than 3 vertices or is not simple. Throws
/// std::invalid_argument on a non-finite point.
std::vector<std::array<int, 3>> TriangulatePolygon(const std::vector<Eigen::Vector2d>& polygon_m);

}  // namespace rowloc::mapping
