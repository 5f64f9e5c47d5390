#include "rowloc/sim/terrain_surface.hpp"

#include <cmath>
#include <numbers>
#include <random>
#include <stdexcept>

namespace rowloc::sim {
namespace {

/// Uniform in [0, 1) from the raw 53 high bits of the engine (platform independent).
double Uniform01(std::mt19937_64& rng) { return static_cast<double>(rng() >> 11) * 0x1.0p-53; }

void CheckFinite(const Eigen::Vector2d& xy_m) {
  if (!xy_m.allFinite()) throw std::invalid_argument("TerrainSurface: position is not finite");
}

}  // namespace

std::optional<std::string> TerrainParamsProblem(const TerrainParams& p) {
  if (!std::isfinite(p.grade_east) || std::abs(p.grade_east) >= 1.0)
    return "terrain.grade_east must be finite and in (-1, 1)";
  if (!std::isfinite(p.grade_north) || std::abs(p.grade_north) >= 1.0)
    return "terrain.grade_north must be finite and in (-1, 1)";
  if (!std::isfinite(p.undulation_amplitude_m) || p.undulation_amplitude_m < 0.0)
    return "terrain.undulation_amplitude_m must be finite and >= 0";
  if (!std::isfinite(p.undulation_wavelength_m) || p.undulation_wavelength_m <= 0.0)
    return "terrain.undulation_wavelength_m must be finite and > 0";
  if (p.undulation_components < 1 || p.undulation_components > 16)
    return "terrain.undulation_components must be in [1, 16]";
  return std::nullopt;
}

TerrainSurface::TerrainSurface(const TerrainParams& params, std::uint64_t seed) : params_(params) {
  if (auto problem = TerrainParamsProblem(params)) throw std::invalid_argument(*problem);
  std::mt19937_64 rng(seed);
  constexpr double kTwoPi = 2.0 * std::numbers::pi;
  for (int i = 0; i < params.undulation_components; ++i) {
    const double wavelength_m = params.undulation_wavelength_m * (0.75 + 0.5 * Uniform01(rng));
    const double direction_rad = kTwoPi * Uniform01(rng);
    const double phase_rad = kTwoPi * Uniform01(rng);
    const double k = kTwoPi / wavelength_m;
    waves_.push_back({k * Eigen::Vector2d(std::cos(direction_rad), std::sin(direction_rad)), phase_rad});
  }
}

double TerrainSurface::HeightAt(const Eigen::Vector2d& xy_m) const {
  CheckFinite(xy_m);
  double undulation_m = 0.0;
  for (const Wave& w : waves_) undulation_m += std::sin(w.wave_vector_rad_per_m.dot(xy_m) + w.phase_rad);
  const double scale = params_.undulation_amplitude_m / static_cast<double>(waves_.size());
  return params_.grade_east * xy_m.x() + params_.grade_north * xy_m.y() + scale * undulation_m;
}

Eigen::Vector2d TerrainSurface::GradientAt(const Eigen::Vector2d& xy_m) const {
  CheckFinite(xy_m);
  Eigen::Vector2d gradient(params_.grade_east, params_.grade_north);
  const double scale = params_.undulation_amplitude_m / static_cast<double>(waves_.size());
  for (const Wave& w : waves_)
    gradient += scale * std::cos(w.wave_vector_rad_per_m.dot(xy_m) + w.phase_rad) * w.wave_vector_rad_per_m;
  return gradient;
}

}  // namespace rowloc::sim
