// `rowloc map build` (issue 27: survey point cloud -> georeferenced row map, docs/mapping.md) and
// `rowloc map compare` (a built map against the true one: distances, rows found, missed, invented).
#include "commands.hpp"
#include "option_checks.hpp"
#include "progress_bar.hpp"

#include "rowloc/mapio/output_file.hpp"
#include "rowloc/mapio/row_map_geojson.hpp"
#include "rowloc/mapping/map_build_config.hpp"
#include "rowloc/mapping/map_builder.hpp"
#include "rowloc/mapping/map_comparison.hpp"

#include <fmt/format.h>
#include <spdlog/spdlog.h>

#include <unistd.h>

#include <memory>
#include <stdexcept>
#include <string>
#include <vector>

namespace rowloc::apps {
namespace {

struct BuildOptions {
  std::string survey_path;
  std::string output_dir;
  std::string crs;
  std::vector<double> origin;  // lat, lon, alt
  std::string config_path;
  double octomap_resolution_m = 0.0;  // 0: no OctoMap
  std::string progress = "auto";      // auto (when stderr is a terminal), always, never
};

void RunBuild(const BuildOptions& o) {
  mapping::MapBuildRequest request;
  request.survey_path = o.survey_path;
  request.output_dir = o.output_dir;
  if (!o.crs.empty()) {
    request.georeference = mapping::Georeference::FromCrs(o.crs);
  } else if (o.origin.size() == 3) {
    request.georeference = mapping::Georeference::Local({o.origin[0], o.origin[1], o.origin[2]});
  } else {
    throw std::invalid_argument("give --origin LAT LON ALT (cloud in local ENU metres) or --crs EPSG:326zz|327zz "
                                "(cloud in UTM metres)");
  }
  if (!o.config_path.empty()) {
    request.config = mapping::LoadMapBuildConfig(o.config_path);
    request.config_source = o.config_path;
  }
  if (o.octomap_resolution_m > 0.0) request.octomap_resolution_m = o.octomap_resolution_m;
  // Before the survey is read: no output may name an input, or replace a device or directory.
  const std::filesystem::path dir(o.output_dir);
  std::vector<NamedPath> outputs;
  for (const char* name :
       {"row-map.geojson", "dtm.json", "map.svg", "report.txt", "report.json", "canopy.bt", "meshes.ply"}) {
    outputs.push_back({"--output", (dir / name).string()});
  }
  CheckCommandFiles({{"survey", o.survey_path}, {"--config", o.config_path}}, outputs);
  std::unique_ptr<ProgressBar> bar;
  if (o.progress == "always" || (o.progress == "auto" && isatty(STDERR_FILENO) != 0)) {
    bar = std::make_unique<ProgressBar>(stderr);
    request.progress = [&bar](std::string_view stage, std::size_t done, std::size_t total) {
      bar->Update(stage, done, total);
    };
  }
  const mapping::MapBuildResult result = mapping::RunMapBuild(request);
  bar.reset();  // ends the progress line before the summary
  for (const auto& stage : result.stages) {
    spdlog::info("{:<44} {:>8} {:<12} {:.3f} s", stage.name, stage.points, stage.unit.substr(0, 12), stage.seconds);
  }
  const std::filesystem::path out(o.output_dir);
  if (result.map) {
    fmt::print("{}: {}\n  map: {}\n  report: {}\n  dtm: {}\n  svg: {}\n", o.survey_path, result.message,
               (out / "row-map.geojson").string(), (out / "report.txt").string(), (out / "dtm.json").string(),
               (out / "map.svg").string());
    if (!result.meshes.triangles.empty()) {
      fmt::print("  meshes: {} ({} triangles)\n", (out / "meshes.ply").string(), result.meshes.triangles.size());
    }
    if (o.octomap_resolution_m > 0.0) fmt::print("  octomap: {}\n", (out / "canopy.bt").string());
  } else {
    fmt::print("{}: {}\n  no map written; report: {}\n", o.survey_path, result.message,
               (out / "report.txt").string());
  }
}

struct CompareOptions {
  std::string built_path;
  std::string truth_path;
  mapping::MapComparisonParams params;
  std::string json_path;
  double require_p95_m = 0.0;
};

mapping::MapComparison RunCompare(const CompareOptions& o) {
  CheckCommandFiles({{"built", o.built_path}, {"truth", o.truth_path}}, {{"--json", o.json_path}});
  const geometry::RowMap built = mapio::ReadRowMapGeoJson(o.built_path);
  const geometry::RowMap truth = mapio::ReadRowMapGeoJson(o.truth_path);
  const mapping::MapComparison c = mapping::CompareRowMaps(built, truth, o.params);
  fmt::print("{} against {}\n{}", o.built_path, o.truth_path, mapping::FormatMapComparison(c));
  if (!o.json_path.empty()) {
    mapio::WriteFileAtomically(o.json_path, mapping::FormatMapComparisonJson(c));
  }
  return c;
}

/// --require-p95: exit 1 unless the map meets the distance and finds every part, inventing none.
void CheckRequirement(const CompareOptions& o, const mapping::MapComparison& c) {
  if (o.require_p95_m > 0.0) {
    if (c.p95_m > o.require_p95_m || !c.missed.empty() || !c.invented.empty()) {
      fmt::print("FAIL: p95 {:.4f} m (required <= {:.4f} m), {} missed, {} invented\n", c.p95_m, o.require_p95_m,
                 c.missed.size(), c.invented.size());
      throw CLI::RuntimeError(1);
    }
    fmt::print("PASS: p95 {:.4f} m <= {:.4f} m, every true part found, none invented\n", c.p95_m, o.require_p95_m);
  }
}

}  // namespace

void RegisterMapBuildCommands(CLI::App& app) {
  CLI::App* map = app.get_subcommand("map");  // registered by RegisterMapCommands

  auto build = std::make_shared<BuildOptions>();
  CLI::App* b = map->add_subcommand(
      "build",
      "Build a row map from a survey point cloud: row-map.geojson, meshes.ply, dtm.json, report.txt/json, map.svg");
  b->add_option("survey", build->survey_path, "Survey point cloud (.ply, .pcd or .las)")->required();
  b->add_option("-o,--output", build->output_dir, "Output directory")->required();
  CLI::Option* crs = b->add_option("--crs", build->crs, "The cloud is in UTM metres: EPSG:326zz (north) or EPSG:327zz (south)");
  CLI::Option* origin = b->add_option("--origin", build->origin,
                                      "The cloud is in local ENU metres around LAT LON ALT (deg, deg, m above WGS84)")
                            ->expected(3);
  crs->excludes(origin);
  b->add_option("--config", build->config_path, "Parameters (JSON; default: the values of config/mapping/default.json)");
  b->add_option("--octomap", build->octomap_resolution_m,
                "Also write canopy.bt, an OctoMap of the canopy points in the map frame, voxels of this size [m]")
      ->check(PositiveNumber());
  b->add_option("--progress", build->progress,
                "Progress bars on stderr: auto (when stderr is a terminal), always, never")
      ->check(CLI::IsMember({"auto", "always", "never"}))
      ->default_str("auto");
  b->callback([build] { RunReportingInputErrors("map build", [&build] { RunBuild(*build); }); });

  auto compare = std::make_shared<CompareOptions>();
  CLI::App* c = map->add_subcommand("compare", "Compare a built row map with the true one (distances, rows found)");
  c->add_option("built", compare->built_path, "Built row map (GeoJSON)")->required();
  c->add_option("truth", compare->truth_path, "True row map (GeoJSON)")->required();
  c->add_option("--step", compare->params.sample_step_m, "Sampling step along the outlines [m]")->check(PositiveNumber());
  c->add_option("--match-distance", compare->params.match_distance_m, "Largest median distance of a matched part [m]")
      ->check(PositiveNumber());
  c->add_option("--json", compare->json_path, "Also write the comparison as JSON");
  c->add_option("--require-p95", compare->require_p95_m,
                "Exit 1 unless p95 <= this [m], every true part is found and none is invented")
      ->check(PositiveNumber());
  c->callback([compare] {
    mapping::MapComparison result;
    RunReportingInputErrors("map compare", [&compare, &result] { result = RunCompare(*compare); });
    CheckRequirement(*compare, result);
  });
}

}  // namespace rowloc::apps
