// World files (docs/simulation-world.md, "World files"): strict JSON -> RowWorldParams.
#include "rowloc/sim/row_world.hpp"

#include <nlohmann/json.hpp>

#include <fstream>
#include <set>
#include <sstream>
#include <stdexcept>

namespace rowloc::sim {
namespace {

using nlohmann::json;

/// Reads one JSON object with exactly the listed keys; errors name the source and the key path.
class ObjectReader {
 public:
  ObjectReader(const json& object, std::string path, std::string_view source, std::set<std::string> keys)
      : object_(object), path_(std::move(path)), source_(source) {
    if (!object.is_object()) Fail(path_.empty() ? "top level" : path_, "must be a JSON object");
    for (const auto& [key, value] : object.items())
      if (!keys.count(key)) Fail(Key(key), "unknown key");
    for (const std::string& key : keys)
      if (!object.contains(key)) Fail(Key(key), "missing");
  }
  [[noreturn]] void Fail(const std::string& key, const std::string& reason) const {
    throw std::runtime_error(std::string(source_) + ": " + key + ": " + reason);
  }
  std::string Key(const std::string& key) const { return path_.empty() ? key : path_ + "." + key; }
  const json& At(const std::string& key) const { return object_.at(key); }
  double Number(const std::string& key) const {
    const json& v = At(key);
    if (!v.is_number()) Fail(Key(key), "must be a number");
    return v.get<double>();
  }
  std::int64_t Integer(const std::string& key) const {
    const json& v = At(key);
    if (!v.is_number_integer()) Fail(Key(key), "must be an integer");
    return v.get<std::int64_t>();
  }
  std::string String(const std::string& key) const {
    const json& v = At(key);
    if (!v.is_string()) Fail(Key(key), "must be a string");
    return v.get<std::string>();
  }
  ObjectReader Object(const std::string& key, std::set<std::string> keys) const {
    return ObjectReader(At(key), Key(key), source_, std::move(keys));
  }

 private:
  const json& object_;
  std::string path_;
  std::string_view source_;
};

int SmallInt(const ObjectReader& r, const std::string& key) {
  const std::int64_t v = r.Integer(key);
  if (v < -1000000 || v > 1000000) r.Fail(r.Key(key), "out of range");
  return static_cast<int>(v);
}

RowCurvature ParseCurvature(const ObjectReader& r, const std::string& key) {
  const std::string type = r.String(key);
  if (type == "straight") return RowCurvature::kStraight;
  if (type == "arc") return RowCurvature::kArc;
  if (type == "s_curve") return RowCurvature::kSCurve;
  r.Fail(r.Key(key), "must be \"straight\", \"arc\" or \"s_curve\", not \"" + type + "\"");
}

CanopyParams ParseCanopy(const ObjectReader& r) {
  CanopyParams c;
  c.half_width_m = r.Number("half_width_m");
  c.half_width_variation_m = r.Number("half_width_variation_m");
  c.width_wavelength_m = r.Number("width_wavelength_m");
  c.bottom_m = r.Number("bottom_m");
  c.top_m = r.Number("top_m");
  c.height_variation_m = r.Number("height_variation_m");
  c.height_wavelength_m = r.Number("height_wavelength_m");
  c.roughness_amplitude_m = r.Number("roughness_amplitude_m");
  c.roughness_min_wavelength_m = r.Number("roughness_min_wavelength_m");
  c.roughness_max_wavelength_m = r.Number("roughness_max_wavelength_m");
  return c;
}

TerrainParams ParseTerrain(const ObjectReader& r) {
  TerrainParams t;
  t.grade_east = r.Number("grade_east");
  t.grade_north = r.Number("grade_north");
  t.undulation_amplitude_m = r.Number("undulation_amplitude_m");
  t.undulation_wavelength_m = r.Number("undulation_wavelength_m");
  t.undulation_components = SmallInt(r, "undulation_components");
  return t;
}

RowWorldParams ParseTop(const json& document, std::string_view source) {
  const ObjectReader top(document, "", source,
                         {"name", "seed", "origin", "rows", "curvature", "gaps", "canopy", "terrain"});
  RowWorldParams p;
  p.name = top.String("name");
  const std::int64_t seed = top.Integer("seed");
  if (seed < 0) top.Fail("seed", "must be >= 0");
  p.seed = static_cast<std::uint64_t>(seed);
  const ObjectReader origin = top.Object("origin", {"latitude_deg", "longitude_deg", "altitude_m"});
  p.origin = {origin.Number("latitude_deg"), origin.Number("longitude_deg"), origin.Number("altitude_m")};
  const ObjectReader rows = top.Object("rows", {"count", "spacing_m", "length_m", "heading_rad"});
  p.row_count = SmallInt(rows, "count");
  p.row_spacing_m = rows.Number("spacing_m");
  p.row_length_m = rows.Number("length_m");
  p.heading_rad = rows.Number("heading_rad");
  const ObjectReader curvature = top.Object("curvature", {"type", "radius_m"});
  p.curvature = ParseCurvature(curvature, "type");
  p.curvature_radius_m = curvature.Number("radius_m");
  const json& gaps = top.At("gaps");
  if (!gaps.is_array()) top.Fail("gaps", "must be an array");
  for (std::size_t i = 0; i < gaps.size(); ++i) {
    const ObjectReader g(gaps[i], "gaps[" + std::to_string(i) + "]", source, {"row", "start_m", "end_m"});
    p.gaps.push_back({SmallInt(g, "row"), g.Number("start_m"), g.Number("end_m")});
  }
  p.canopy = ParseCanopy(top.Object("canopy", {"half_width_m", "half_width_variation_m", "width_wavelength_m",
                                               "bottom_m", "top_m", "height_variation_m", "height_wavelength_m",
                                               "roughness_amplitude_m", "roughness_min_wavelength_m",
                                               "roughness_max_wavelength_m"}));
  p.terrain = ParseTerrain(top.Object("terrain", {"grade_east", "grade_north", "undulation_amplitude_m",
                                                  "undulation_wavelength_m", "undulation_components"}));
  return p;
}

}  // namespace

RowWorldParams ParseRowWorldParams(std::string_view json_text, std::string_view source_name) {
  json document;
  try {
    document = json::parse(json_text);
  } catch (const json::parse_error& e) {
    throw std::runtime_error(std::string(source_name) + ": JSON syntax error: " + e.what());
  }
  RowWorldParams p = ParseTop(document, source_name);
  if (auto problem = RowWorldParamsProblem(p)) throw std::runtime_error(std::string(source_name) + ": " + *problem);
  return p;
}

RowWorldParams LoadRowWorldParams(const std::filesystem::path& path) {
  std::ifstream in(path, std::ios::binary);
  if (!in) throw std::runtime_error(path.string() + ": cannot open the world file");
  std::ostringstream text;
  text << in.rdbuf();
  if (in.bad()) throw std::runtime_error(path.string() + ": cannot read the world file");
  return ParseRowWorldParams(text.str(), path.string());
}

}  // namespace rowloc::sim
