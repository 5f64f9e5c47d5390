#include "rowloc/sim/terrain.hpp"

#include "rowloc/sim/wheel_slip.hpp"

#include <nlohmann/json.hpp>

#include <cmath>
#include <cstddef>
#include <fstream>
#include <span>
#include <sstream>

namespace rowloc::sim {
namespace {

constexpr std::array<std::string_view, 4> kFieldNames = {
    "traction_coefficient_max", "shear_slip_constant", "rolling_resistance_coefficient",
    "rolling_radius_factor"};

std::size_t Index(TerrainClass terrain) { return static_cast<std::size_t>(terrain); }

[[noreturn]] void Fail(const std::string& source, const std::string& key, const std::string& reason) {
  throw TerrainConfigError(source + ": key '" + key + "': " + reason);
}

double ReadNumber(const nlohmann::json& object, std::string_view field, const std::string& source,
                  const std::string& path) {
  const std::string key = path + "." + std::string(field);
  const auto it = object.find(std::string(field));
  if (it == object.end()) Fail(source, key, "missing");
  if (!it->is_number()) Fail(source, key, std::string("expected a number, got ") + it->type_name());
  const double value = it->get<double>();
  if (!std::isfinite(value)) Fail(source, key, "not finite");
  return value;
}

void RejectUnknownKeys(const nlohmann::json& object, std::span<const std::string_view> known,
                       const std::string& source, const std::string& path) {
  for (const auto& item : object.items()) {
    bool found = false;
    for (const auto name : known) found = found || item.key() == name;
    if (!found) Fail(source, path.empty() ? item.key() : path + "." + item.key(), "unknown key");
  }
}

TerrainSlipParams ParseParams(const nlohmann::json& object, const std::string& source,
                              const std::string& path) {
  if (!object.is_object()) Fail(source, path, std::string("expected an object, got ") + object.type_name());
  RejectUnknownKeys(object, kFieldNames, source, path);
  TerrainSlipParams params;
  params.traction_coefficient_max = ReadNumber(object, kFieldNames[0], source, path);
  params.shear_slip_constant = ReadNumber(object, kFieldNames[1], source, path);
  params.rolling_resistance_coefficient = ReadNumber(object, kFieldNames[2], source, path);
  params.rolling_radius_factor = ReadNumber(object, kFieldNames[3], source, path);
  if (const auto problem = TerrainSlipParamsProblem(params)) Fail(source, path, *problem);
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
  nlohmann::json root;
  try {
    root = nlohmann::json::parse(json_text);
  } catch (const nlohmann::json::exception& error) {  // parse errors and number overflow
    Fail(source_name, "(document)", std::string("invalid JSON: ") + error.what());
  }
  if (!root.is_object()) Fail(source_name, "(document)", "expected a JSON object");
  constexpr std::array<std::string_view, 1> kRootKeys = {"terrains"};
  RejectUnknownKeys(root, kRootKeys, source_name, "");
  const auto terrains = root.find("terrains");
  if (terrains == root.end()) Fail(source_name, "terrains", "missing");
  if (!terrains->is_object()) Fail(source_name, "terrains", "expected an object");
  for (const auto& item : terrains->items()) {
    if (!TerrainClassFromName(item.key())) Fail(source_name, "terrains." + item.key(), "unknown terrain class");
  }
  TerrainSlipTable table;
  for (const auto terrain : kAllTerrainClasses) {
    const std::string name(TerrainClassName(terrain));
    const auto entry = terrains->find(name);
    if (entry == terrains->end()) Fail(source_name, "terrains." + name, "missing");
    table.Set(terrain, ParseParams(*entry, source_name, "terrains." + name));
  }
  return table;
}

TerrainSlipTable LoadTerrainSlipTable(const std::filesystem::path& path) {
  std::ifstream in(path);
  if (!in) Fail(path.string(), "(document)", "cannot open file");
  std::ostringstream text;
  text << in.rdbuf();
  return ParseTerrainSlipTable(text.str(), path.string());
}

}  // namespace rowloc::sim
