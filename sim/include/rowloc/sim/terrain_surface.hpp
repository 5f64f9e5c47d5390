// TerrainSurface: the ground height of a simulated row world (issue 3, "World":
// "terrain with slope and undulation").
//
// Math: in the local ENU frame (metres), the terrain is the graph
//   z(x, y) = g_e x + g_n y + (A / n) sum_{i=1..n} sin(k_i . (x, y) + phi_i),
//   k_i = (2 pi / lambda_i) (cos alpha_i, sin alpha_i),
// a slope plane of grades (g_e, g_n) (dz/dx, dz/dy, dimensionless) plus n plane waves. The
// wavelengths lambda_i are drawn uniformly in [0.75, 1.25] lambda, the directions alpha_i and
// phases phi_i uniformly in [0, 2 pi), all from std::mt19937_64(seed) (a fully specified engine;
// the draws use its raw 64-bit output, so they are the same on every platform), hence
// |z - plane| <= A. The gradient is the exact derivative. The canopy of a row world is given as
// height above this surface.
#pragma once

#include <Eigen/Core>

#include <cstdint>
#include <optional>
#include <string>
#include <vector>

namespace rowloc::sim {

struct TerrainParams {
  double grade_east = 0.0;               ///< dz/dx of the slope plane, in (-1, 1)
  double grade_north = 0.0;              ///< dz/dy of the slope plane, in (-1, 1)
  double undulation_amplitude_m = 0.0;   ///< A >= 0: bound of the undulation, metres
  double undulation_wavelength_m = 20.0; ///< lambda > 0: mean wavelength, metres
  int undulation_components = 3;         ///< n in [1, 16]
  bool operator==(const TerrainParams&) const = default;
};

/// Why the parameters are unusable (naming the field), or nullopt.
std::optional<std::string> TerrainParamsProblem(const TerrainParams& params);

class TerrainSurface {
 public:
  /// Throws std::invalid_argument with TerrainParamsProblem's message on bad parameters.
  TerrainSurface(const TerrainParams& params, std::uint64_t seed);

  /// z(x, y), metres (up). Throws std::invalid_argument if xy_m is not finite.
  double HeightAt(const Eigen::Vector2d& xy_m) const;
  /// (dz/dx, dz/dy), dimensionless. Throws std::invalid_argument if xy_m is not finite.
  Eigen::Vector2d GradientAt(const Eigen::Vector2d& xy_m) const;

  const TerrainParams& params() const { return params_; }

 private:
  struct Wave {
    Eigen::Vector2d wave_vector_rad_per_m;
    double phase_rad;
  };
  TerrainParams params_;
  std::vector<Wave> waves_;
};

}  // namespace rowloc::sim
