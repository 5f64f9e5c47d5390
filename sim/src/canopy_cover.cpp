#include "rowloc/sim/canopy_cover.hpp"

#include <algorithm>
#include <cmath>
#include <numbers>
#include <stdexcept>

namespace rowloc::sim {
namespace {
constexpr double kCastHalfApertureRad = 0.05;
constexpr double kCastRangeM = 20.0;
}  // namespace

CanopyCover::CanopyCover(CanopyCaster& caster, const RowWorld& world)
    : caster_(caster),
      canopy_top_m_(world.params().canopy.top_m),
      cast_height_m_(0.5 * (world.params().canopy.bottom_m + world.params().canopy.top_m)) {}

double CanopyCover::HiddenElevation(const Eigen::Vector2d& apex, const Eigen::Vector2d& axis,
                                    double antenna_height_m) const {
  const auto echo = caster_.ConeCast(geometry::Cone2{apex, axis, kCastHalfApertureRad, kCastRangeM}, cast_height_m_);
  if (!echo) return 0.0;
  return std::atan2(std::max(0.0, canopy_top_m_ - antenna_height_m), echo->range_m);
}

double CanopyCover::At(const Eigen::Vector2d& antenna_xy_m, double antenna_height_m, double heading_rad) const {
  if (!antenna_xy_m.allFinite() || !std::isfinite(antenna_height_m) || !std::isfinite(heading_rad)) {
    throw std::invalid_argument("CanopyCover::At: non-finite antenna position, height or heading");
  }
  const Eigen::Vector2d left(-std::sin(heading_rad), std::cos(heading_rad));
  const double hidden = HiddenElevation(antenna_xy_m, left, antenna_height_m) +
                        HiddenElevation(antenna_xy_m, -left, antenna_height_m);
  return std::clamp(hidden / std::numbers::pi, 0.0, 1.0);
}

}  // namespace rowloc::sim
