// World files (docs/simulation-world.md, "World files"): strict JSON -> RowWorldParams.
#include "rowloc/sim/row_world.hpp"

#include "rowloc/mapio/detail/json_object_reader.hpp"

#include <cstdint>
#include <limits>
#include <set>
#include <stdexcept>

namespace rowloc::sim {
namespace {

using Reader = mapio::detail::JsonObjectReader<std::runtime_error>;
/// The keys an object must have (sorted: missing keys are reported in alphabetical order).
using KeySet = std::set<std::string>;

/// `reader` after checking that it has exactly `keys` (unknown keys first, then missing ones).
Reader Expecting(Reader reader, const KeySet& keys) {
  reader.ExpectKeys(keys);
  return reader;
}

int SmallInt(Reader& r, const std::string& key) { return static_cast<int>(r.Integer(key, -1000000, 1000000)); }

RowCurvature ParseCurvature(Reader& r, const std::string& key) {
  const std::string type = r.String(key);
  if (type == "straight") return RowCurvature::kStraight;
  if (type == "arc") return RowCurvature::kArc;
  if (type == "s_curve") return RowCurvature::kSCurve;
  r.Fail(r.Key(key), "must be \"straight\", \"arc\" or \"s_curve\", not \"" + type + "\"");
}

CanopyParams ParseCanopy(Reader r) {
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

TerrainParams ParseTerrain(Reader r) {
  TerrainParams t;
  t.grade_east = r.Number("grade_east");
  t.grade_north = r.Number("grade_north");
  t.undulation_amplitude_m = r.Number("undulation_amplitude_m");
  t.undulation_wavelength_m = r.Number("undulation_wavelength_m");
  t.undulation_components = SmallInt(r, "undulation_components");
  return t;
}

RowWorldParams ParseTop(const nlohmann::json& document, const std::string& source) {
  if (!document.is_object()) throw std::runtime_error(source + ": top level: must be a JSON object");
  Reader top = Expecting(Reader(document, source, ""),
                         {"name", "seed", "origin", "rows", "curvature", "gaps", "canopy", "terrain"});
  RowWorldParams p;
  p.name = top.String("name");
  const std::int64_t seed =
      top.Integer("seed", std::numeric_limits<std::int64_t>::min(), std::numeric_limits<std::int64_t>::max());
  if (seed < 0) top.Fail("seed", "must be >= 0");
  p.seed = static_cast<std::uint64_t>(seed);
  Reader origin = Expecting(top.Object("origin"), {"latitude_deg", "longitude_deg", "altitude_m"});
  p.origin = {origin.Number("latitude_deg"), origin.Number("longitude_deg"), origin.Number("altitude_m")};
  Reader rows = Expecting(top.Object("rows"), {"count", "spacing_m", "length_m", "heading_rad"});
  p.row_count = SmallInt(rows, "count");
  p.row_spacing_m = rows.Number("spacing_m");
  p.row_length_m = rows.Number("length_m");
  p.heading_rad = rows.Number("heading_rad");
  Reader curvature = Expecting(top.Object("curvature"), {"type", "radius_m"});
  p.curvature = ParseCurvature(curvature, "type");
  p.curvature_radius_m = curvature.Number("radius_m");
  p.gaps = top.ObjectArray("gaps", [](Reader& gap) {
    gap.ExpectKeys(KeySet{"row", "start_m", "end_m"});
    return RowGap{SmallInt(gap, "row"), gap.Number("start_m"), gap.Number("end_m")};
  });
  p.canopy = ParseCanopy(Expecting(top.Object("canopy"),
                                   {"half_width_m", "half_width_variation_m", "width_wavelength_m", "bottom_m", "top_m",
                                    "height_variation_m", "height_wavelength_m", "roughness_amplitude_m",
                                    "roughness_min_wavelength_m", "roughness_max_wavelength_m"}));
  p.terrain = ParseTerrain(Expecting(top.Object("terrain"), {"grade_east", "grade_north", "undulation_amplitude_m",
                                                             "undulation_wavelength_m", "undulation_components"}));
  return p;
}

}  // namespace

RowWorldParams ParseRowWorldParams(std::string_view json_text, std::string_view source_name) {
  const std::string source(source_name);
  const nlohmann::json document = mapio::detail::ParseJsonText<std::runtime_error>(json_text, source, "JSON syntax error");
  RowWorldParams p = ParseTop(document, source);
  if (auto problem = RowWorldParamsProblem(p)) throw std::runtime_error(source + ": " + *problem);
  return p;
}

RowWorldParams LoadRowWorldParams(const std::filesystem::path& path) {
  return ParseRowWorldParams(mapio::detail::ReadTextFile<std::runtime_error>(path, "the world file"), path.string());
}

}  // namespace rowloc::sim
