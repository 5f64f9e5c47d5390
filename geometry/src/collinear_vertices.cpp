// Sleeve fitting for DropCollinearVertices (see collinear_vertices.hpp).
#include "rowloc/geometry/collinear_vertices.hpp"

#include <algorithm>
#include <cmath>
#include <numbers>

namespace rowloc::geometry {
namespace {

/// Angle of v from the reference direction ref (unit), in (-pi, pi].
double AngleFrom(const Eigen::Vector2d& ref, const Eigen::Vector2d& v) {
  return std::atan2(ref.x() * v.y() - ref.y() * v.x(), ref.dot(v));
}

std::vector<Eigen::Vector2d> DropOnOpenPath(const std::vector<Eigen::Vector2d>& p, double tol) {
  const std::size_t n = p.size();
  if (n <= 2) return p;
  std::vector<Eigen::Vector2d> kept{p[0]};
  std::size_t a = 0;
  Eigen::Vector2d ref = Eigen::Vector2d::UnitX();
  double low = -std::numbers::pi, high = std::numbers::pi, previous_distance = 0.0;
  for (std::size_t j = 1; j < n;) {
    const Eigen::Vector2d v = p[j] - p[a];
    const double distance = v.norm();
    if (j == a + 1) {  // the first vertex after the anchor: it sets the reference direction
      ref = distance > 0.0 ? Eigen::Vector2d(v / distance) : Eigen::Vector2d::UnitX();
      low = -std::numbers::pi;
      high = std::numbers::pi;
    } else {
      const double angle = AngleFrom(ref, v);
      if (angle < low || angle > high || distance <= previous_distance) {
        a = j - 1;  // p[j] cannot end a chord over the vertices before it: keep p[j - 1]
        kept.push_back(p[a]);
        continue;   // p[j] again, from the new anchor
      }
    }
    if (distance > tol) {
      const double half_width = std::asin(tol / distance);
      const double angle = j == a + 1 ? 0.0 : AngleFrom(ref, v);
      low = std::max(low, angle - half_width);
      high = std::min(high, angle + half_width);
    }
    previous_distance = distance;
    ++j;
  }
  kept.push_back(p[n - 1]);
  return kept;
}

}  // namespace

std::vector<Eigen::Vector2d> DropCollinearVertices(const std::vector<Eigen::Vector2d>& points, bool closed,
                                                   double tolerance_m) {
  if (!closed) return DropOnOpenPath(points, tolerance_m);
  if (points.size() <= 3) return points;
  std::vector<Eigen::Vector2d> path = points;
  path.push_back(points.front());  // the ring as a path from its first vertex back to it
  std::vector<Eigen::Vector2d> kept = DropOnOpenPath(path, tolerance_m);
  kept.pop_back();
  return kept.size() >= 3 ? kept : points;  // a ring flat within tol: left to RowOutlineDefect
}

}  // namespace rowloc::geometry
