#include "rowloc/sim/terrain.hpp"

#include "rowloc/sim/wheel_slip.hpp"

#include "rowloc/mapio/detail/json_object_reader.hpp"

#include <array>
#include <cmath>
#include <cstddef>
#include <sstream>

namespace rowloc::sim {
namespace {

using Reader = mapio::detail::JsonObjectReader<TerrainConfigError>;

constexpr std::array<const char*, 4> kFieldNames = {
    "traction_coefficient_max", "shear_slip_constant", "rolling_resistance_coefficient",
    "rolling_radius_factor"};

std::size_t Index(TerrainClass terrain) { return static_cast<std::size_t>(terrain); }

TerrainSlipParams ReadParams(Reader reader) {
  reader.ExpectKeys(kFieldNames);  // a misspelt field is reported as unknown, not the right one as missing
  TerrainSlipParams params;
  params.traction_coefficient_max = reader.Number(kFieldNames[0]);
  params.shear_slip_constant = reader.Number(kFieldNames[1]);
  params.rolling_resistance_coefficient = reader.Number(kFieldNames[2]);
  params.rolling_radius_factor = reader.Number(kFieldNames[3]);
  if (const auto problem = TerrainSlipParamsProblem(params)) reader.Fail(reader.path(), *problem);
  return params;
}

}  // namespace

std::string_view TerrainClassName(TerrainClass terrain) {
  switch (terrain) {
    case TerrainClass::kTiles: return "tiles";
    case TerrainClass::kGrass: return "grass";
    case TerrainClass::kGravel: return "gravel";
    case TerrainClass::kMud: return "mud";
  }
  throw std::invalid_argument("TerrainClassName: invalid TerrainClass value");
}

std::optional<TerrainClass> TerrainClassFromName(std::string_view name) {
  for (const auto terrain : kAllTerrainClasses) {
    if (TerrainClassName(terrain) == name) return terrain;
  }
  return std::nullopt;
}

std::optional<std::string> TerrainSlipParamsProblem(const TerrainSlipParams& params) {
  const auto bad = [](double v) { return !std::isfinite(v); };
  if (bad(params.traction_coefficient_max) || params.traction_coefficient_max <= 0.0) {
    return "traction_coefficient_max must be finite and > 0";
  }
  if (bad(params.shear_slip_constant) || params.shear_slip_constant <= 0.0) {
    return "shear_slip_constant must be finite and > 0";
  }
  if (bad(params.rolling_radius_factor) || params.rolling_radius_factor <= 0.5 ||
      params.rolling_radius_factor > 1.5) {
    return "rolling_radius_factor must be in (0.5, 1.5]";
  }
  if (bad(params.rolling_resistance_coefficient) || params.rolling_resistance_coefficient < 0.0) {
    return "rolling_resistance_coefficient must be finite and >= 0";
  }
  const JanosiHanamotoCurve curve(params.traction_coefficient_max, params.shear_slip_constant);
  if (params.rolling_resistance_coefficient >= curve.MaxTractionCoefficient()) {
    std::ostringstream out;
    out << "rolling_resistance_coefficient " << params.rolling_resistance_coefficient
        << " must be below the traction coefficient at full slip " << curve.MaxTractionCoefficient()
        << " (the vehicle could not hold a constant speed)";
    return out.str();
  }
  return std::nullopt;
}

TerrainSlipTable TerrainSlipTable::Defaults() {
  // Derivation: docs/simulation-slip.md; equal to config/terrains.json (tested).
  TerrainSlipTable table;
  table.Set(TerrainClass::kTiles, {.traction_coefficient_max = 0.8, .shear_slip_constant = 0.1,
                                   .rolling_resistance_coefficient = 0.0197, .rolling_radius_factor = 1.0});
  table.Set(TerrainClass::kGrass, {.traction_coefficient_max = 0.55, .shear_slip_constant = 0.3,
                                   .rolling_resistance_coefficient = 0.1002, .rolling_radius_factor = 0.98});
  table.Set(TerrainClass::kGravel, {.traction_coefficient_max = 0.5, .shear_slip_constant = 0.25,
                                    .rolling_resistance_coefficient = 0.113, .rolling_radius_factor = 0.97});
  table.Set(TerrainClass::kMud, {.traction_coefficient_max = 0.41, .shear_slip_constant = 0.25,
                                 .rolling_resistance_coefficient = 0.1508, .rolling_radius_factor = 0.95});
  return table;
}

void TerrainSlipTable::Set(TerrainClass terrain, const TerrainSlipParams& params) {
  if (const auto problem = TerrainSlipParamsProblem(params)) {
    throw std::invalid_argument("TerrainSlipTable::Set(" + std::string(TerrainClassName(terrain)) +
                                "): " + *problem);
  }
  params_.at(Index(terrain)) = params;
}

const TerrainSlipParams& TerrainSlipTable::At(TerrainClass terrain) const {
  return params_.at(Index(terrain));
}

TerrainSlipTable ParseTerrainSlipTable(const std::string& json_text, const std::string& source_name) {
  const nlohmann::json document = mapio::detail::ParseJsonText<TerrainConfigError>(json_text, source_name);
  Reader root(document, source_name, "");
  root.ExpectKeys({"terrains"});
  Reader terrains = root.Object("terrains");
  for (const std::string& name : terrains.Keys()) {
    if (!TerrainClassFromName(name)) terrains.Fail(terrains.Key(name), "unknown terrain class");
  }
  TerrainSlipTable table;
  for (const auto terrain : kAllTerrainClasses) {
    table.Set(terrain, ReadParams(terrains.Object(std::string(TerrainClassName(terrain)))));
  }
  return table;
}

TerrainSlipTable LoadTerrainSlipTable(const std::filesystem::path& path) {
  return ParseTerrainSlipTable(mapio::detail::ReadTextFile<TerrainConfigError>(path, "terrain file"), path.string());
}

}  // namespace rowloc::sim
