#include "rowloc/geometry/line2.hpp"

#include <cmath>
#include <stdexcept>

namespace rowloc::geometry {

namespace {
// Lines whose unit normals have |cross| below this are treated as parallel (angle < 1e-12 rad).
constexpr double kParallelSine = 1e-12;
}  // namespace

Line2 Line2::Through(const Eigen::Vector2d& a, const Eigen::Vector2d& b) {
  if (!a.allFinite() || !b.allFinite()) {
    throw std::invalid_argument("Line2::Through: points must be finite");
  }
  const Eigen::Vector2d d = b - a;
  const double length = d.norm();
  if (!(length > 0.0) || !std::isfinite(length)) {
    throw std::invalid_argument("Line2::Through: the two points must be distinct");
  }
  Line2 line;
  line.normal = Eigen::Vector2d(-d.y(), d.x()) / length;
  line.offset = line.normal.dot(a);
  return line;
}

Line2 Line2::FromNormal(const Eigen::Vector2d& n, double offset) {
  if (!n.allFinite() || !std::isfinite(offset)) {
    throw std::invalid_argument("Line2::FromNormal: normal and offset must be finite");
  }
  const double length = n.norm();
  if (!(length > 0.0) || !std::isfinite(length)) {
    throw std::invalid_argument("Line2::FromNormal: the normal must be non-zero");
  }
  Line2 line;
  line.normal = n / length;
  line.offset = offset / length;
  return line;
}

double Line2::Distance(const Eigen::Vector2d& x) const { return std::abs(SignedDistance(x)); }

std::optional<Eigen::Vector2d> Line2::Intersect(const Line2& other) const {
  // Solve [n1^T; n2^T] x = [c1; c2] by Cramer's rule.
  const double det = normal.x() * other.normal.y() - normal.y() * other.normal.x();
  if (std::abs(det) <= kParallelSine) return std::nullopt;
  return Eigen::Vector2d((offset * other.normal.y() - normal.y() * other.offset) / det,
                         (normal.x() * other.offset - offset * other.normal.x()) / det);
}

}  // namespace rowloc::geometry
