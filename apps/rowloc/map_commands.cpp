// `rowloc map sample` (generate the synthetic sample row map), `rowloc map info` (read, validate
// and describe a row map file) and `rowloc map edit` (a shifted map or one with rows removed: the
// map errors of the map-aided robustness runs, docs/map-aided-update.md).
#include "commands.hpp"

#include "rowloc/geometry/row_map.hpp"
#include "rowloc/mapio/row_map_geojson.hpp"

#include <fmt/format.h>
#include <spdlog/spdlog.h>

#include <algorithm>
#include <limits>
#include <memory>
#include <stdexcept>
#include <string>
#include <vector>

namespace rowloc::apps {
namespace {

struct SampleOptions {
  geometry::SampleRowMapParams params;
  std::string output_path;
};

void RunSample(const SampleOptions& o) {
  CheckCommandFiles({}, {{"--output", o.output_path}});
  const geometry::RowMap map = geometry::MakeSampleRowMap(o.params);
  mapio::WriteRowMapGeoJson(map, o.output_path);
  spdlog::info("wrote {} rows ({} segments) to {}", map.rows.size(), map.SegmentCount(), o.output_path);
}

void RunInfo(const std::string& path) {
  CheckCommandFiles({{"file", path}}, {});
  const geometry::RowMap map = mapio::ReadRowMapGeoJson(path);
  Eigen::Vector2d lo = Eigen::Vector2d::Constant(std::numeric_limits<double>::infinity());
  Eigen::Vector2d hi = -lo;
  double length = 0.0;
  for (const geometry::Row& row : map.rows) {
    for (const auto& p : row.points_m) {
      lo = lo.cwiseMin(p);
      hi = hi.cwiseMax(p);
    }
    for (std::size_t s = 0; s < row.SegmentCount(); ++s) {
      const auto [a, b] = row.Segment(s);
      length += (b - a).norm();
    }
  }
  fmt::print("{}\n  origin: {:.8f} N, {:.8f} E, {:.3f} m (WGS84)\n", path, map.origin.latitude_deg,
             map.origin.longitude_deg, map.origin.altitude_m);
  fmt::print("  rows: {}, segments: {}, total outline length: {:.2f} m\n", map.rows.size(),
             map.SegmentCount(), length);
  fmt::print("  extent (local ENU): x [{:.2f}, {:.2f}] m, y [{:.2f}, {:.2f}] m\n", lo.x(), hi.x(),
             lo.y(), hi.y());
  for (const geometry::Row& row : map.rows) {
    fmt::print("  {:<12} {:<8} {} vertices\n", row.id, row.closed ? "polygon" : "polyline",
               row.points_m.size());
  }
}

struct EditOptions {
  std::string input_path;
  std::string output_path;
  std::vector<double> shift_m;          ///< east, north in the map's local frame
  std::vector<std::string> drop_rows;   ///< row ids to remove
};

void RunEdit(const EditOptions& o) {
  CheckCommandFiles({{"file", o.input_path}}, {{"--output", o.output_path}});
  geometry::RowMap map = mapio::ReadRowMapGeoJson(o.input_path);
  for (const std::string& id : o.drop_rows) {
    const auto it = std::find_if(map.rows.begin(), map.rows.end(), [&](const geometry::Row& r) { return r.id == id; });
    if (it == map.rows.end()) throw std::runtime_error(o.input_path + ": no row '" + id + "' to drop");
    map.rows.erase(it);
  }
  if (map.rows.empty()) throw std::runtime_error("every row dropped: an empty map is not a map");
  if (!o.shift_m.empty()) {
    const Eigen::Vector2d shift(o.shift_m[0], o.shift_m[1]);
    if (!shift.allFinite()) throw std::runtime_error("--shift must be finite");
    for (geometry::Row& row : map.rows) {
      for (Eigen::Vector2d& p : row.points_m) p += shift;
    }
  }
  mapio::WriteRowMapGeoJson(map, o.output_path);
  spdlog::info("wrote {} rows ({} segments) to {}", map.rows.size(), map.SegmentCount(), o.output_path);
}

}  // namespace

void RegisterMapCommands(CLI::App& app) {
  CLI::App* map = app.add_subcommand("map", "Row map files (GeoJSON)");
  map->require_subcommand(1);

  auto sample = std::make_shared<SampleOptions>();
  CLI::App* gen = map->add_subcommand("sample", "Write the synthetic sample row map (docs/map-format.md)");
  gen->add_option("-o,--output", sample->output_path, "Output GeoJSON file")->required();
  gen->add_option("--rows", sample->params.row_count, "Number of rows");
  gen->add_option("--spacing", sample->params.row_spacing_m, "Row spacing [m]");
  gen->add_option("--length", sample->params.row_length_m, "Row length [m]");
  gen->add_option("--width", sample->params.canopy_width_m, "Canopy width at slice height [m]");
  gen->add_option("--bow", sample->params.bow_m, "Lateral sag of the rows at mid-length [m]");
  gen->add_option("--heading", sample->params.heading_rad, "Row direction from +East, CCW [rad]");
  gen->add_option("--vertex-spacing", sample->params.vertex_spacing_m, "Vertex spacing along rows [m]");
  gen->add_option("--lat", sample->params.origin.latitude_deg, "Origin latitude [deg]");
  gen->add_option("--lon", sample->params.origin.longitude_deg, "Origin longitude [deg]");
  gen->add_option("--alt", sample->params.origin.altitude_m, "Origin height above WGS84 [m]");
  gen->callback([sample] { RunReportingInputErrors("map sample", [&sample] { RunSample(*sample); }); });

  auto info_path = std::make_shared<std::string>();
  CLI::App* info = map->add_subcommand("info", "Read, validate and describe a row map");
  info->add_option("file", *info_path, "GeoJSON row map")->required();
  info->callback([info_path] { RunReportingInputErrors("map info", [&info_path] { RunInfo(*info_path); }); });

  auto edit = std::make_shared<EditOptions>();
  CLI::App* ed = map->add_subcommand("edit", "Write a shifted row map, or one with rows removed (map errors)");
  ed->add_option("file", edit->input_path, "GeoJSON row map")->required();
  ed->add_option("-o,--output", edit->output_path, "Output GeoJSON file")->required();
  ed->add_option("--shift", edit->shift_m, "Shift every vertex by EAST NORTH metres (local frame)")->expected(2);
  ed->add_option("--drop-row", edit->drop_rows, "Remove the row with this id (repeatable)");
  ed->callback([edit] { RunReportingInputErrors("map edit", [&edit] { RunEdit(*edit); }); });
}

}  // namespace rowloc::apps
