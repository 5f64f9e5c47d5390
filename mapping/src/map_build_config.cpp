// Reading, validating and writing MapBuildConfig (see map_build_config.hpp). One table lists every
// key with its member and domain, so that the reader, the validator and the writer agree.
#include "rowloc/mapping/map_build_config.hpp"

#include "rowloc/mapio/detail/json_object_reader.hpp"

#include <nlohmann/json.hpp>

#include <cmath>
#include <sstream>
#include <string>
#include <string_view>
#include <vector>

namespace rowloc::mapping {
namespace {

using Reader = mapio::detail::JsonObjectReader<MapBuildConfigError>;

/// One key: its section, name, domain, and accessors into a config.
struct Field {
  const char* section;
  const char* key;
  double low;
  double high;
  bool integer;
  double* (*number)(MapBuildConfig&);
  int* (*whole)(MapBuildConfig&);
};

#define ROWLOC_NUMBER(section, member, key, low, high) \
  Field{section, key, low, high, false, [](MapBuildConfig& c) { return &c.member; }, nullptr}
#define ROWLOC_INTEGER(section, member, key, low, high) \
  Field{section, key, low, high, true, nullptr, [](MapBuildConfig& c) { return &c.member; }}

const std::vector<Field>& Fields() {
  static const std::vector<Field> fields = {
      ROWLOC_NUMBER("tiles", tiles.size_m, "size_m", 5.0, 10000.0),
      ROWLOC_NUMBER("tiles", tiles.overlap_m, "overlap_m", 0.0, 100.0),
      ROWLOC_INTEGER("tiles", tiles.threads, "threads", 0, 64),
      ROWLOC_NUMBER("clean", clean.voxel_size_m, "voxel_size_m", 0.0, 1.0),
      ROWLOC_INTEGER("clean", clean.outlier_neighbours, "outlier_neighbours", 0, 200),
      ROWLOC_NUMBER("clean", clean.outlier_stddev_factor, "outlier_stddev_factor", 0.1, 100.0),
      ROWLOC_NUMBER("terrain", terrain.cell_size_m, "cell_size_m", 0.05, 20.0),
      ROWLOC_NUMBER("terrain", terrain.classification_radius_m, "classification_radius_m", 0.1, 100.0),
      ROWLOC_NUMBER("terrain", terrain.ground_tolerance_m, "ground_tolerance_m", 0.001, 10.0),
      ROWLOC_NUMBER("terrain", terrain.ground_thickness_m, "ground_thickness_m", 0.0, 1.0),
      ROWLOC_INTEGER("terrain", terrain.min_ground_points, "min_ground_points", 1, 1000),
      ROWLOC_INTEGER("terrain", terrain.smoothing_passes, "smoothing_passes", 0, 20),
      ROWLOC_NUMBER("band", band.reference_height_m, "reference_height_m", 0.0, 20.0),
      ROWLOC_NUMBER("band", band.band_half_width_m, "band_half_width_m", 0.005, 10.0),
      ROWLOC_NUMBER("rows", rows.raster_cell_m, "raster_cell_m", 0.005, 1.0),
      ROWLOC_NUMBER("rows", rows.link_radius_m, "link_radius_m", 0.0, 2.0),
      ROWLOC_INTEGER("rows", rows.min_part_points, "min_part_points", 1, 100000000),
      ROWLOC_NUMBER("rows", rows.min_part_length_m, "min_part_length_m", 0.0, 1000.0),
      ROWLOC_NUMBER("rows", rows.max_gap_m, "max_gap_m", 0.0, 100.0),
      ROWLOC_NUMBER("rows", rows.max_link_angle_rad, "max_link_angle_rad", 0.0, 1.5707963267948966),
      ROWLOC_NUMBER("rows", rows.max_link_offset_m, "max_link_offset_m", 0.0, 10.0),
      ROWLOC_NUMBER("rows", rows.end_window_m, "end_window_m", 0.1, 100.0),
      ROWLOC_NUMBER("outline", outline.centreline_bin_m, "centreline_bin_m", 0.05, 20.0),
      ROWLOC_NUMBER("outline", outline.station_step_m, "station_step_m", 0.005, 5.0),
      ROWLOC_NUMBER("outline", outline.edge_quantile, "edge_quantile", 0.0, 1.0),
      ROWLOC_NUMBER("outline", outline.end_exclusion_m, "end_exclusion_m", 0.0, 5.0),
      ROWLOC_NUMBER("outline", outline.min_width_m, "min_width_m", 0.0, 10.0),
      ROWLOC_NUMBER("outline", outline.simplify_tolerance_m, "simplify_tolerance_m", 0.0, 10.0),
      ROWLOC_NUMBER("outline", outline.one_sided_max_width_m, "one_sided_max_width_m", 0.0, 10.0),
      ROWLOC_NUMBER("outline", outline.one_sided_window_m, "one_sided_window_m", 0.1, 20.0),
      ROWLOC_INTEGER("mesh", mesh.levels, "levels", 0, 20),
      ROWLOC_NUMBER("mesh", mesh.lowest_m, "lowest_m", 0.0, 20.0),
      ROWLOC_NUMBER("mesh", mesh.highest_m, "highest_m", 0.0, 20.0),
      ROWLOC_NUMBER("mesh", mesh.vertex_spacing_m, "vertex_spacing_m", 0.05, 10.0),
  };
  return fields;
}
#undef ROWLOC_NUMBER
#undef ROWLOC_INTEGER

const std::vector<const char*>& Sections() {
  static const std::vector<const char*> sections = {"tiles", "clean", "terrain", "band", "rows", "outline", "mesh"};
  return sections;
}

std::string FormatNumber(double value) {
  std::ostringstream text;
  text.precision(15);
  text << value;
  return text.str();
}

}  // namespace

std::vector<double> MeshLevelHeights(const MeshParams& mesh) {
  std::vector<double> heights;
  for (int k = 0; k < mesh.levels; ++k) {
    heights.push_back(mesh.levels == 1 ? mesh.lowest_m
                                       : mesh.lowest_m + (mesh.highest_m - mesh.lowest_m) * k / (mesh.levels - 1));
  }
  return heights;
}

std::optional<std::string> ValidateMapBuildConfig(const MapBuildConfig& config) {
  MapBuildConfig copy = config;
  for (const Field& f : Fields()) {
    const double value = f.integer ? static_cast<double>(*f.whole(copy)) : *f.number(copy);
    if (!std::isfinite(value) || value < f.low || value > f.high) {
      return std::string(f.section) + "." + f.key + ": must be in [" + FormatNumber(f.low) + ", " +
             FormatNumber(f.high) + "], got " + FormatNumber(value);
    }
  }
  // A tile's DTM near its core's edge must see the ground plane's whole neighbourhood.
  if (config.tiles.overlap_m < config.terrain.classification_radius_m) {
    return "tiles.overlap_m: must be at least terrain.classification_radius_m (" +
           FormatNumber(config.terrain.classification_radius_m) + "), got " + FormatNumber(config.tiles.overlap_m);
  }
  if (config.mesh.levels == 1) return std::string("mesh.levels: must be 0 (no meshes) or at least 2, got 1");
  if (config.mesh.levels >= 2 && !(config.mesh.highest_m > config.mesh.lowest_m)) {
    return "mesh.highest_m: must be above mesh.lowest_m (" + FormatNumber(config.mesh.lowest_m) + "), got " +
           FormatNumber(config.mesh.highest_m);
  }
  return std::nullopt;
}

MapBuildConfig LoadMapBuildConfig(const std::filesystem::path& path) {
  const std::string source = path.string();
  const std::string text = mapio::detail::ReadTextFile<MapBuildConfigError>(path, "map build configuration");
  const nlohmann::json root = mapio::detail::ParseJsonText<MapBuildConfigError>(text, source);
  Reader reader(root, source, "");
  // An overlay on the code's defaults: a section or key left out keeps its default; a misspelt
  // one is rejected as unknown.
  MapBuildConfig config;
  for (const char* section : Sections()) {
    if (!reader.Has(section)) continue;
    Reader part = reader.Object(section);
    for (const Field& f : Fields()) {
      if (std::string_view(f.section) != section || !part.Has(f.key)) continue;
      if (f.integer) {
        *f.whole(config) = static_cast<int>(part.Integer(f.key, static_cast<std::int64_t>(f.low),
                                                         static_cast<std::int64_t>(f.high)));
      } else {
        *f.number(config) = part.NumberIn(f.key, f.low, f.high);
      }
    }
    part.RejectUnknownKeys();
  }
  reader.RejectUnknownKeys();
  if (const auto problem = ValidateMapBuildConfig(config)) throw MapBuildConfigError(source + ": " + *problem);
  return config;
}

std::string FormatMapBuildConfig(const MapBuildConfig& config) {
  MapBuildConfig copy = config;
  nlohmann::ordered_json root = nlohmann::ordered_json::object();
  for (const char* section : Sections()) root[section] = nlohmann::ordered_json::object();
  for (const Field& f : Fields()) {
    if (f.integer) {
      root[f.section][f.key] = *f.whole(copy);
    } else {
      root[f.section][f.key] = *f.number(copy);
    }
  }
  return root.dump(2) + "\n";
}

}  // namespace rowloc::mapping
