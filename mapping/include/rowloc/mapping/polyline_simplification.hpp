// Step 7 of the map build (docs/mapping.md): simplification of a closed outline with CGAL's
// Polyline_simplification_2 (Douglas-Peucker-like vertex removal in a constrained triangulation,
// so that the result never intersects itself; cost: the largest squared distance between the
// simplified and the original polyline; stop when that would exceed tolerance_m^2).
//
// This header exposes Eigen and the standard library only; CGAL stays in polyline_simplification.cpp.
#pragma once

#include <Eigen/Core>

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

}  // namespace rowloc::mapping
