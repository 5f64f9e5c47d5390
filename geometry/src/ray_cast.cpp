#include "rowloc/geometry/ray_cast.hpp"

#include <algorithm>
#include <cmath>
#include <stdexcept>
#include <string>

namespace rowloc::geometry {

namespace {

// A ray is parallel to a segment when |sin angle| is below this.
constexpr double kParallelSine = 1e-12;

RayHit MakeHit(const Segment2& s, double param, double range_m, const Eigen::Vector2d& origin,
               const Eigen::Vector2d& travel) {
  RayHit hit;
  hit.range_m = range_m;
  hit.segment_param = param;
  hit.point = s.PointAt(param);
  hit.normal = detail::FacingNormal(s, origin, travel);
  return hit;
}

// Collinear ray and segment: the nearest point of their overlap.
std::optional<RayHit> CollinearHit(const Segment2& s, const Eigen::Vector2d& origin,
                                   const Eigen::Vector2d& d, double max_range_m) {
  const double ta = (s.a - origin).dot(d);
  const double tb = (s.b - origin).dot(d);
  const double t_near = std::min(ta, tb);
  const double t_far = std::max(ta, tb);
  if (t_far < -kContactTolerance_m) return std::nullopt;  // entirely behind the origin
  const double t = std::max(t_near, 0.0);
  if (t > max_range_m) return std::nullopt;
  return MakeHit(s, s.ClosestParam(origin + t * d), t, origin, d);
}

}  // namespace

Eigen::Vector2d UnitDirection(const Eigen::Vector2d& direction, const char* what) {
  const double norm = direction.norm();
  if (!direction.allFinite() || !(norm > 0.0) || !std::isfinite(norm)) {
    throw std::invalid_argument(std::string(what) + ": direction must be finite and non-zero");
  }
  return direction / norm;
}

void CheckMaxRange(double max_range_m, const char* what) {
  if (!(max_range_m > 0.0)) {  // also rejects NaN
    throw std::invalid_argument(std::string(what) + ": max range must be > 0 (got " +
                                std::to_string(max_range_m) + ")");
  }
}

std::optional<RayHit> RayCast(const Segment2& s, const Eigen::Vector2d& origin,
                              const Eigen::Vector2d& direction, double max_range_m) {
  constexpr const char* kWhat = "RayCast";
  if (!s.IsProper()) throw std::invalid_argument("RayCast: segment is degenerate or not finite");
  if (!origin.allFinite()) throw std::invalid_argument("RayCast: origin must be finite");
  const Eigen::Vector2d d = UnitDirection(direction, kWhat);
  CheckMaxRange(max_range_m, kWhat);
  return detail::RayCastUnchecked(s, origin, d, max_range_m);
}

namespace detail {

std::optional<RayHit> RayCastUnchecked(const Segment2& s, const Eigen::Vector2d& origin,
                                       const Eigen::Vector2d& d, double max_range_m) {
  const Eigen::Vector2d e = s.b - s.a;
  const Eigen::Vector2d w = s.a - origin;
  const double length = e.norm();
  const double denom = Cross(d, e);
  if (std::abs(denom) <= kParallelSine * length) {
    if (std::abs(Cross(w, e)) > kContactTolerance_m * length) return std::nullopt;  // parallel
    return CollinearHit(s, origin, d, max_range_m);
  }
  const double t = Cross(w, e) / denom;
  const double param = Cross(w, d) / denom;
  const double param_tolerance = kContactTolerance_m / length;
  if (param < -param_tolerance || param > 1.0 + param_tolerance) return std::nullopt;
  if (t < -kContactTolerance_m || t > max_range_m) return std::nullopt;
  return MakeHit(s, std::clamp(param, 0.0, 1.0), std::max(t, 0.0), origin, d);
}

Eigen::Vector2d FacingNormal(const Segment2& s, const Eigen::Vector2d& origin,
                             const Eigen::Vector2d& travel) {
  const Eigen::Vector2d e = s.b - s.a;
  const double length = e.norm();
  const Eigen::Vector2d left(-e.y() / length, e.x() / length);
  const double side_m = left.dot(origin - s.a);
  if (side_m > kContactTolerance_m) return left;
  if (side_m < -kContactTolerance_m) return -left;
  return left.dot(travel) > 0.0 ? Eigen::Vector2d(-left) : left;
}

}  // namespace detail
}  // namespace rowloc::geometry
