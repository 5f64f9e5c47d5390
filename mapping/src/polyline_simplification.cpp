// Outline simplification with CGAL::Polyline_simplification_2 (see polyline_simplification.hpp).
// A CGAL translation unit (slow to compile, ~35 s and 1.5 GB): keep it small.
#include "rowloc/mapping/polyline_simplification.hpp"

#include <CGAL/Exact_predicates_inexact_constructions_kernel.h>
#include <CGAL/Polygon_2.h>
#include <CGAL/Polyline_simplification_2/Squared_distance_cost.h>
#include <CGAL/Polyline_simplification_2/Stop_above_cost_threshold.h>
#include <CGAL/Polyline_simplification_2/simplify.h>

#include <cmath>
#include <stdexcept>

namespace rowloc::mapping {
namespace {

using Kernel = CGAL::Exact_predicates_inexact_constructions_kernel;
using Polygon = CGAL::Polygon_2<Kernel>;
namespace PS = CGAL::Polyline_simplification_2;

}  // namespace

SimplifiedPolygon SimplifyPolygon(const std::vector<Eigen::Vector2d>& polygon_m, double tolerance_m) {
  if (!(tolerance_m >= 0.0) || !std::isfinite(tolerance_m)) {
    throw std::invalid_argument("SimplifyPolygon: tolerance must be finite and >= 0");
  }
  for (const auto& p : polygon_m) {
    if (!p.allFinite()) throw std::invalid_argument("SimplifyPolygon: non-finite point");
  }
  SimplifiedPolygon result{polygon_m, false};
  if (tolerance_m == 0.0 || polygon_m.size() < 4) return result;
  Polygon polygon;
  for (const auto& p : polygon_m) polygon.push_back(Kernel::Point_2(p.x(), p.y()));
  // The constrained triangulation refuses intersecting constraints (exact predicates tag).
  if (!polygon.is_simple()) return result;
  const Polygon simple = PS::simplify(polygon, PS::Squared_distance_cost(),
                                      PS::Stop_above_cost_threshold(tolerance_m * tolerance_m));
  result.points_m.clear();
  for (auto it = simple.vertices_begin(); it != simple.vertices_end(); ++it) {
    result.points_m.emplace_back(CGAL::to_double(it->x()), CGAL::to_double(it->y()));
  }
  result.simplified = true;
  return result;
}

}  // namespace rowloc::mapping
