#include "rowloc/geometry/segment2.hpp"

#include <algorithm>
#include <cmath>
#include <stdexcept>

namespace rowloc::geometry {

bool Segment2::IsProper() const {
  // Finite, distinct endpoints whose difference does not overflow.
  return a.allFinite() && b.allFinite() && a != b && std::isfinite((b - a).squaredNorm());
}

Eigen::Vector2d Segment2::Direction() const {
  if (!IsProper()) {
    throw std::invalid_argument("Segment2::Direction: segment is degenerate or not finite");
  }
  return (b - a).normalized();
}

Eigen::Vector2d Segment2::LeftNormal() const {
  const Eigen::Vector2d t = Direction();
  return {-t.y(), t.x()};
}

double Segment2::ClosestParam(const Eigen::Vector2d& x) const {
  const Eigen::Vector2d e = b - a;
  const double length_sq = e.squaredNorm();
  if (!(length_sq > 0.0)) return 0.0;
  return std::clamp((x - a).dot(e) / length_sq, 0.0, 1.0);
}

}  // namespace rowloc::geometry
