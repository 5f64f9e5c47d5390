#include "rowloc/sim/ultrasonic_model.hpp"

#include <cmath>
#include <stdexcept>
#include <vector>

namespace rowloc::sim {
namespace {

double Uniform01(std::mt19937_64& rng) { return static_cast<double>(rng() >> 11) * 0x1.0p-53; }

/// Standard normal by Box-Muller from two uniform draws (platform independent).
double StandardNormal(std::mt19937_64& rng) {
  const double u1 = 1.0 - Uniform01(rng);  // (0, 1]
  const double u2 = Uniform01(rng);
  return std::sqrt(-2.0 * std::log(u1)) * std::cos(2.0 * std::numbers::pi * u2);
}

geometry::SegmentIndex BuildIndex(const RowWorld& world, double height_m, double step_m) {
  std::vector<geometry::SegmentIndex::Entry> entries;
  for (const OutlinePart& part : world.OutlineAt(height_m, step_m)) {
    const std::size_t n = part.polygon_m.size();
    for (std::size_t i = 0; i < n; ++i)
      entries.push_back({{part.polygon_m[i], part.polygon_m[(i + 1) % n]}, static_cast<std::size_t>(part.row), i});
  }
  return geometry::SegmentIndex(std::move(entries));
}

}  // namespace

CanopySlice::CanopySlice(const RowWorld& world, double height_m, double step_m)
    : height_m_(height_m), index_(BuildIndex(world, height_m, step_m)) {}

std::optional<CanopyEcho> CanopySlice::ConeCast(const geometry::Cone2& cone) const {
  const auto hit = index_.ConeCast(cone);
  if (!hit) return std::nullopt;
  return CanopyEcho{hit->hit.range_m, hit->hit.point, hit->hit.normal,
                    static_cast<int>(index_.entries()[hit->entry].row)};
}

CanopyCaster::CanopyCaster(const RowWorld& world, double tolerance_m, double height_quantum_m)
    : world_(world), step_m_(world.StepForTolerance(tolerance_m)), height_quantum_m_(height_quantum_m) {
  if (!(height_quantum_m >= 1e-4 && height_quantum_m <= 1.0))
    throw std::invalid_argument("CanopyCaster: height quantum must be in [1e-4, 1] m");
}

std::optional<CanopyEcho> CanopyCaster::ConeCast(const geometry::Cone2& cone, double height_m) {
  if (!std::isfinite(height_m) || std::abs(height_m) > 1e6)
    throw std::invalid_argument("CanopyCaster: height must be finite and within 1e6 m");
  const auto key = static_cast<long long>(std::llround(height_m / height_quantum_m_));
  auto it = slices_.find(key);
  if (it == slices_.end())
    it = slices_.emplace(key, CanopySlice(world_, static_cast<double>(key) * height_quantum_m_, step_m_)).first;
  return it->second.ConeCast(cone);
}

std::optional<std::string> UltrasonicParamsProblem(const UltrasonicParams& p) {
  if (!std::isfinite(p.min_range_m) || p.min_range_m < 0) return "ultrasonic.min_range_m must be finite and >= 0";
  if (!std::isfinite(p.max_range_m) || p.max_range_m <= p.min_range_m)
    return "ultrasonic.max_range_m must be finite and > min_range_m";
  if (!(p.half_aperture_rad >= 0 && p.half_aperture_rad < std::numbers::pi / 2))
    return "ultrasonic.half_aperture_rad must be in [0, pi/2)";
  if (!std::isfinite(p.range_sigma_m) || p.range_sigma_m < 0) return "ultrasonic.range_sigma_m must be finite and >= 0";
  if (!(p.miss_probability >= 0 && p.miss_probability <= 1)) return "ultrasonic.miss_probability must be in [0, 1]";
  return std::nullopt;
}

namespace {
UltrasonicParams Checked(const UltrasonicParams& p) {
  if (auto problem = UltrasonicParamsProblem(p)) throw std::invalid_argument("UltrasonicModel: " + *problem);
  return p;
}
}  // namespace

UltrasonicModel::UltrasonicModel(const UltrasonicParams& params, std::uint64_t seed)
    : params_(Checked(params)), rng_(seed) {}

std::optional<UltrasonicReading> UltrasonicModel::Measure(CanopyCaster& caster, const Eigen::Vector2d& apex_m,
                                                          const Eigen::Vector2d& axis, double height_m) {
  const double miss_draw = Uniform01(rng_);
  const double noise = StandardNormal(rng_);
  const auto echo = caster.ConeCast({apex_m, axis, params_.half_aperture_rad, params_.max_range_m}, height_m);
  if (!echo || echo->range_m < params_.min_range_m || miss_draw < params_.miss_probability) return std::nullopt;
  const double range_m = echo->range_m + params_.range_sigma_m * noise;
  if (range_m < params_.min_range_m || range_m > params_.max_range_m) return std::nullopt;
  return UltrasonicReading{range_m, *echo};
}

}  // namespace rowloc::sim
