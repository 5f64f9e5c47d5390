#include "rowloc/geometry/cone_cast.hpp"

#include <cmath>
#include <numbers>
#include <stdexcept>

namespace rowloc::geometry {

namespace {

Cone2 Validated(const Cone2& cone) {
  constexpr const char* kWhat = "ConeCast";
  if (!cone.apex.allFinite()) throw std::invalid_argument("ConeCast: apex must be finite");
  Cone2 out = cone;
  out.axis = UnitDirection(cone.axis, kWhat);
  if (!(cone.half_aperture_rad >= 0.0 && cone.half_aperture_rad < std::numbers::pi / 2.0)) {
    throw std::invalid_argument("ConeCast: half aperture must be in [0, pi/2) rad (got " +
                                std::to_string(cone.half_aperture_rad) + ")");
  }
  CheckMaxRange(cone.max_range_m, kWhat);
  return out;
}

}  // namespace

PreparedCone::PreparedCone(const Cone2& cone)
    : cone_(Validated(cone)), cos_half_aperture_(std::cos(cone_.half_aperture_rad)) {
  // The axis rotated by -h and +h from one cosine and sine (cos(-h) = cos(h), sin(-h) = -sin(h)).
  const double c = cos_half_aperture_, s = std::sin(cone_.half_aperture_rad);
  const Eigen::Vector2d& v = cone_.axis;
  edge_cw_ = {c * v.x() + s * v.y(), -s * v.x() + c * v.y()};
  edge_ccw_ = {c * v.x() - s * v.y(), s * v.x() + c * v.y()};
}

bool PreparedCone::SectorContains(const Eigen::Vector2d& x) const {
  const Eigen::Vector2d v = x - cone_.apex;
  const double norm = v.norm();
  return norm == 0.0 || cone_.axis.dot(v) >= norm * cos_half_aperture_;
}

std::optional<RayHit> PreparedCone::Cast(const Segment2& s) const {
  const Eigen::Vector2d& apex = cone_.apex;
  double best_range = cone_.max_range_m;
  double best_param = -1.0;  // < 0: no candidate yet
  const auto consider = [&](double param) {
    const Eigen::Vector2d x = s.PointAt(param);
    if (!SectorContains(x)) return;
    const double range = (x - apex).norm();
    if (range <= best_range) {
      best_range = range;
      best_param = param;
    }
  };
  consider(s.ClosestParam(apex));
  consider(0.0);
  consider(1.0);
  for (const Eigen::Vector2d* edge : {&edge_cw_, &edge_ccw_}) {
    const auto hit = detail::RayCastUnchecked(s, apex, *edge, cone_.max_range_m);
    if (hit && hit->range_m <= best_range) {
      best_range = hit->range_m;
      best_param = hit->segment_param;
    }
  }
  if (best_param < 0.0) return std::nullopt;
  RayHit hit;
  hit.range_m = best_range;
  hit.segment_param = best_param;
  hit.point = s.PointAt(best_param);
  hit.normal = detail::FacingNormal(s, apex, cone_.axis);
  return hit;
}

std::optional<RayHit> ConeCast(const Segment2& s, const Cone2& cone) {
  if (!s.IsProper()) throw std::invalid_argument("ConeCast: segment is degenerate or not finite");
  return PreparedCone(cone).Cast(s);
}

}  // namespace rowloc::geometry

