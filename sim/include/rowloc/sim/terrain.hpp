// Terrain classes and their longitudinal slip parameters (issue 3, "Terrain patches with their own
// slip behaviour: tiles, grass, gravel, mud at least"; the design's "terrain-dependent slip").
//
// Each class carries the parameters of the Janosi-Hanamoto traction/slip curve of Lindgren et al. 2002 eq. (21),
// written in normalized form (see wheel_slip.hpp):
//   T(s) = T_max [1 - (B/s)(1 - exp(-s/B))],   T_max = mu_max * N * r_roll,
// i.e. the peak traction torque is a dimensionless traction coefficient mu_max times the wheel's
// normal load N (newton) times its rolling radius r_roll (metres). The rolling radius depends on the
// soil (Lindgren et al. 2002, conclusion: "effective wheel rolling radius ... depends upon soil properties"):
//   r_roll = r_nominal * rolling_radius_factor.
// Rolling resistance is a force c_rr * N opposing the motion. At constant speed the wheel must
// deliver exactly that force, so the steady slip s* solves mu(s*) = c_rr (docs/simulation-slip.md
// derives the shipped values from the AgriMaRo runs of Danzi 2026 ch. 7).
//
// The parameters are data: config/terrains.json, equal to TerrainSlipTable::Defaults() (tested).
#pragma once

#include <array>
#include <filesystem>
#include <optional>
#include <stdexcept>
#include <string>
#include <string_view>

namespace rowloc::sim {

enum class TerrainClass { kTiles = 0, kGrass = 1, kGravel = 2, kMud = 3 };

inline constexpr std::array<TerrainClass, 4> kAllTerrainClasses = {
    TerrainClass::kTiles, TerrainClass::kGrass, TerrainClass::kGravel, TerrainClass::kMud};

/// "tiles", "grass", "gravel", "mud" (the JSON keys).
std::string_view TerrainClassName(TerrainClass terrain);
/// Inverse of TerrainClassName; nullopt for an unknown name.
std::optional<TerrainClass> TerrainClassFromName(std::string_view name);

/// Longitudinal slip parameters of one terrain class (all dimensionless).
struct TerrainSlipParams {
  double traction_coefficient_max = 0.0;       ///< mu_max > 0: T_max = mu_max * N * r_roll
  double shear_slip_constant = 0.0;            ///< B > 0: Janosi-Hanamoto slip constant (K / contact length)
  double rolling_resistance_coefficient = 0.0; ///< c_rr >= 0: resisting force c_rr * N; < mu(s = 1)
  double rolling_radius_factor = 1.0;          ///< r_roll / r_nominal, in (0.5, 1.5]

  friend bool operator==(const TerrainSlipParams&, const TerrainSlipParams&) = default;
};

/// Why the parameters are unusable (naming the field), or nullopt. Includes the requirement that
/// the terrain can sustain constant speed: c_rr below the traction coefficient at full slip.
std::optional<std::string> TerrainSlipParamsProblem(const TerrainSlipParams& params);

/// Error in a terrain file: the message names the file, the key and the reason.
class TerrainConfigError : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

/// Slip parameters for every terrain class.
class TerrainSlipTable {
 public:
  /// The shipped values (equal to config/terrains.json).
  static TerrainSlipTable Defaults();

  /// Throws std::invalid_argument if the parameters are unusable (TerrainSlipParamsProblem).
  void Set(TerrainClass terrain, const TerrainSlipParams& params);
  const TerrainSlipParams& At(TerrainClass terrain) const;

  friend bool operator==(const TerrainSlipTable&, const TerrainSlipTable&) = default;

 private:
  std::array<TerrainSlipParams, kAllTerrainClasses.size()> params_{};
};

/// Parses {"terrains": {"tiles": {...}, "grass": {...}, "gravel": {...}, "mud": {...}}}; every
/// class and every field is required, unknown keys are rejected. source_name appears in errors.
/// Throws TerrainConfigError.
TerrainSlipTable ParseTerrainSlipTable(const std::string& json_text, const std::string& source_name);

/// Reads and parses a terrain file. Throws TerrainConfigError (including for a missing file).
TerrainSlipTable LoadTerrainSlipTable(const std::filesystem::path& path);

}  // namespace rowloc::sim
