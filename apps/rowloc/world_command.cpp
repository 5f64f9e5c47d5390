// `rowloc world WORLD.json -o DIR`: the outputs of a simulated row world (issue 3, "World";
// docs/simulation-world.md, "Outputs: row map, survey cloud, OctoMap"):
//   DIR/row-map.geojson  the true row map at the slice height (RowWorld::TrueRowMap),
//   DIR/survey.pcd       a synthetic survey cloud (sim::SampleCanopySurface, noisy),
//   DIR/canopy.bt        an OctoMap of the canopy surface, built from a noise-free sampling at half
//                        the voxel size thickened inward into a shell one voxel deep (at most half
//                        the thinnest canopy), then read back and checked against the exact world:
//                        the ray along the normal through every canopy probe (both faces and the
//                        top, mid-band, 8 stations per row) meets an occupied voxel within one
//                        voxel of the surface, and no lane probe (half a spacing left of each row,
//                        mid-band) is occupied.
#include "commands.hpp"
#include "option_checks.hpp"

#include "rowloc/geometry/row_map.hpp"
#include "rowloc/mapio/row_map_geojson.hpp"
#include "rowloc/mapping/canopy_occupancy_map.hpp"
#include "rowloc/mapping/point_cloud.hpp"
#include "rowloc/sim/canopy_surface_sampler.hpp"
#include "rowloc/sim/row_world.hpp"

#include <fmt/format.h>
#include <spdlog/spdlog.h>

#include <algorithm>
#include <cstdint>
#include <filesystem>
#include <memory>
#include <stdexcept>
#include <string>
#include <system_error>

namespace rowloc::apps {
namespace {

namespace fs = std::filesystem;

struct WorldCommandOptions {
  std::string world_path;
  std::string output_dir;
  double slice_height_m = 1.0;
  double step_m = 0.05;
  double survey_spacing_m = 0.05;
  double survey_noise_m = 0.005;
  double survey_dropout = 0.0;
  double survey_outliers = 0.0;
  bool survey_one_sided = false;
  bool survey_terrain = false;
  double terrain_spacing_m = 0.1;
  double octomap_resolution_m = 0.05;
  std::uint64_t seed = 0;
  bool seed_given = false;
  bool no_survey = false;
  bool no_octomap = false;
};

/// Stations probed per row by the OctoMap check, and the probes at each.
constexpr int kProbesPerRow = 8;
constexpr const char* kProbeNames[] = {"left face", "right face", "top"};

struct OctoMapCheck {
  int canopy_probes = 0;
  int canopy_missed = 0;
  int lane_probes = 0;
  int lane_occupied = 0;
};

/// True if the ray along the unit normal through p meets an occupied voxel within one voxel of p
/// (a surface that cuts a voxel only at a corner may leave that voxel empty, but a ray crossing
/// the surface must not slip through the map).
bool SurfaceOccupied(const mapping::CanopyOccupancyMap& map, const Eigen::Vector3d& p, const Eigen::Vector3d& normal) {
  constexpr int kSteps = 8;  // per voxel edge
  const double step_m = map.resolution_m() / kSteps;
  for (int i = -kSteps; i <= kSteps; ++i)
    if (map.IsOccupied(p + i * step_m * normal)) return true;
  return false;
}

OctoMapCheck CheckOctoMap(const sim::RowWorld& world, const mapping::CanopyOccupancyMap& map) {
  const sim::RowWorldParams& p = world.params();
  const sim::TerrainSurface& terrain = world.terrain();
  OctoMapCheck check;
  const auto at = [&](const Eigen::Vector2d& xy, double height_m) {
    return Eigen::Vector3d(xy.x(), xy.y(), terrain.HeightAt(xy) + height_m);
  };
  for (int row = 0; row < p.row_count; ++row) {
    for (int i = 0; i < kProbesPerRow; ++i) {
      const double s = p.row_length_m * (i + 0.5) / kProbesPerRow;
      const double mid_m = 0.5 * (world.BandBottom(row, s) + world.BandTop(row, s));
      const Eigen::Vector2d n = world.ReferenceNormal(s);
      const Eigen::Vector2d centre = world.RowCentre(row, s);
      const Eigen::Vector3d n3(n.x(), n.y(), 0.0);
      ++check.lane_probes;
      if (map.IsOccupied(at(centre + 0.5 * p.row_spacing_m * n, mid_m))) ++check.lane_occupied;
      if (!world.HasCanopy(row, s, mid_m)) continue;  // a gap
      const Eigen::Vector3d probes[] = {at(centre + world.LeftHalfWidth(row, s) * n, mid_m),
                                        at(centre - world.RightHalfWidth(row, s) * n, mid_m),
                                        at(centre, world.BandTop(row, s))};
      const Eigen::Vector3d normals[] = {n3, -n3, Eigen::Vector3d::UnitZ()};
      for (int j = 0; j < 3; ++j) {
        ++check.canopy_probes;
        if (SurfaceOccupied(map, probes[j], normals[j])) continue;
        ++check.canopy_missed;
        spdlog::debug("canopy probe without an occupied voxel: row {}, station {} m, {} at ({:.4f}, {:.4f}, {:.4f})",
                      row, s, kProbeNames[j], probes[j].x(), probes[j].y(), probes[j].z());
      }
    }
  }
  return check;
}

fs::path PrepareOutputDirectory(const std::string& dir) {
  std::error_code ec;
  fs::create_directories(dir, ec);
  if (ec || !fs::is_directory(dir))
    throw std::runtime_error("cannot create output directory '" + dir + "': " +
                             (ec ? ec.message() : std::string("not a directory")));
  return fs::path(dir);
}

/// Runs a sampling step, naming the command-line options when the parameters are refused.
template <typename Sample>
mapping::PointCloud Sampled(const std::string& options, const Sample& sample) {
  try {
    return sample();
  } catch (const std::invalid_argument& e) {
    throw std::invalid_argument(options + ": " + e.what());
  }
}

mapping::PointCloud SampleSurveyCloud(const sim::RowWorld& world, const WorldCommandOptions& o) {
  sim::SurveyParams params;
  params.spacing_m = o.survey_spacing_m;
  params.noise_sigma_m = o.survey_noise_m;
  params.dropout_fraction = o.survey_dropout;
  params.outlier_fraction = o.survey_outliers;
  params.one_sided = o.survey_one_sided;
  params.include_terrain = o.survey_terrain;
  params.terrain_spacing_m = o.terrain_spacing_m;
  params.seed = o.seed;
  spdlog::info("sampling the survey cloud (spacing {} m, noise {} m)", o.survey_spacing_m, o.survey_noise_m);
  return Sampled(fmt::format("--survey-spacing {} m, --terrain-spacing {} m", o.survey_spacing_m, o.terrain_spacing_m),
                 [&] { return mapping::PointCloud{sim::SampleCanopySurface(world, params)}; });
}

/// The noise-free canopy surface at half the voxel size, plus two copies moved inward along the
/// normal by depth/2 and depth (depth = one voxel, at most half the thinnest canopy): a shell, so
/// that a voxel the surface only cuts at a corner is still filled from the inside.
mapping::PointCloud SampleCanopyShell(const sim::RowWorld& world, const WorldCommandOptions& o) {
  sim::SurveyParams params;
  params.spacing_m = 0.5 * o.octomap_resolution_m;
  params.noise_sigma_m = 0.0;
  params.seed = o.seed;
  const sim::CanopyParams& canopy = world.params().canopy;
  const double thinnest_m =
      std::min(2.0 * (canopy.half_width_m - canopy.half_width_variation_m - canopy.roughness_amplitude_m),
               canopy.top_m - canopy.bottom_m - 2.0 * canopy.height_variation_m);
  const double depth_m = std::min(o.octomap_resolution_m, 0.5 * thinnest_m);
  spdlog::info("sampling the canopy shell for the OctoMap (spacing {} m)", params.spacing_m);
  return Sampled(fmt::format("--octomap-resolution {} m (canopy sampled at half of it)", o.octomap_resolution_m), [&] {
    mapping::PointCloud cloud;
    sim::SampleSurvey(world, params, [&](const sim::SurveySample& sample) {
      for (double layer : {0.0, 0.5, 1.0}) cloud.points_m.push_back(sample.position_m - layer * depth_m * sample.normal);
    });
    return cloud;
  });
}

struct OctoMapResult {
  mapping::OctoMapSummary summary;
  OctoMapCheck check;
};

OctoMapResult WriteCheckedOctoMap(const sim::RowWorld& world, const mapping::PointCloud& shell, double resolution_m,
                                  const fs::path& path) {
  spdlog::info("writing the OctoMap ({} m voxels) of {} shell points to {}", resolution_m, shell.points_m.size(),
               path.string());
  OctoMapResult result;
  result.summary = mapping::WriteOctoMap(shell, mapping::OctoMapOptions{resolution_m}, path);
  result.check = CheckOctoMap(world, mapping::CanopyOccupancyMap::Load(path));
  const OctoMapCheck& c = result.check;
  if (c.canopy_missed > 0 || c.lane_occupied > 0)
    throw std::runtime_error(fmt::format("OctoMap check failed for {}: {} of {} canopy probes without an occupied "
                                         "voxel, {} of {} lane probes occupied",
                                         path.string(), c.canopy_missed, c.canopy_probes, c.lane_occupied,
                                         c.lane_probes));
  return result;
}

void RunWorld(WorldCommandOptions o) {
  const fs::path out(o.output_dir);
  CheckCommandFiles({{"world", o.world_path}}, {{"--output", (out / "row-map.geojson").string()},
                                                {"--output", (out / "survey.pcd").string()},
                                                {"--output", (out / "canopy.bt").string()}});
  const sim::RowWorld world(sim::LoadRowWorldParams(o.world_path));
  if (!o.seed_given) o.seed = world.params().seed;
  // Everything is computed before the first file is written, so bad options leave no partial output.
  spdlog::info("slicing the true row map at {} m above the terrain", o.slice_height_m);
  const geometry::RowMap map = world.TrueRowMap(o.slice_height_m, o.step_m);
  const mapping::PointCloud survey = o.no_survey ? mapping::PointCloud{} : SampleSurveyCloud(world, o);
  const mapping::PointCloud shell = o.no_octomap ? mapping::PointCloud{} : SampleCanopyShell(world, o);

  const fs::path dir = PrepareOutputDirectory(o.output_dir);
  const fs::path map_path = dir / "row-map.geojson";
  const fs::path survey_path = dir / "survey.pcd";
  const fs::path octomap_path = dir / "canopy.bt";
  mapio::WriteRowMapGeoJson(map, map_path);
  if (!o.no_survey) {
    spdlog::info("writing {} survey points to {}", survey.points_m.size(), survey_path.string());
    mapping::WritePointCloud(survey, survey_path);
  }
  OctoMapResult octomap;
  if (!o.no_octomap) octomap = WriteCheckedOctoMap(world, shell, o.octomap_resolution_m, octomap_path);

  const sim::RowWorldParams& p = world.params();
  fmt::print("world '{}' ({}): {} rows, {} m long, {} m apart\n", p.name, o.world_path, p.row_count, p.row_length_m,
             p.row_spacing_m);
  fmt::print("  {}: {} parts at {} m above the terrain (step {} m)\n", map_path.string(), map.rows.size(),
             o.slice_height_m, o.step_m);
  if (!o.no_survey)
    fmt::print("  {}: {} points (spacing {} m, noise {} m, dropout {}, outliers {}, {}, terrain {}, seed {})\n",
               survey_path.string(), survey.points_m.size(), o.survey_spacing_m, o.survey_noise_m, o.survey_dropout,
               o.survey_outliers, o.survey_one_sided ? "one-sided" : "both faces", o.survey_terrain ? "yes" : "no",
               o.seed);
  if (!o.no_octomap) {
    const OctoMapCheck& c = octomap.check;
    fmt::print("  {}: {} occupied voxels of {} m (from {} noise-free canopy shell points)\n", octomap_path.string(),
               octomap.summary.occupied_leaves, octomap.summary.resolution_m, shell.points_m.size());
    fmt::print("  OctoMap check passed: {}/{} canopy probes occupied, {}/{} lane probes free\n",
               c.canopy_probes - c.canopy_missed, c.canopy_probes, c.lane_probes - c.lane_occupied, c.lane_probes);
  }
}

}  // namespace

void RegisterWorldCommand(CLI::App& app) {
  auto o = std::make_shared<WorldCommandOptions>();
  CLI::App* cmd = app.add_subcommand("world", "Write the true row map, a survey cloud and an OctoMap of a world");
  cmd->add_option("world", o->world_path, "World file (config/worlds/*.json)")->required();
  cmd->add_option("-o,--output", o->output_dir, "Output directory (created if missing)")->required();
  cmd->add_option("--slice-height", o->slice_height_m, "Height of the row map slice above the terrain [m]")
      ->capture_default_str();
  cmd->add_option("--step", o->step_m, "Station step of the row map outlines [m]")
      ->check(FiniteInRange(1e-4, 10.0, "RANGE"))
      ->capture_default_str();
  cmd->add_option("--survey-spacing", o->survey_spacing_m, "Survey point spacing on the canopy surface [m]")
      ->check(FiniteInRange(1e-3, 10.0, "RANGE"))
      ->capture_default_str();
  cmd->add_option("--survey-noise", o->survey_noise_m, "Survey noise sigma along the surface normal [m]")
      ->check(FiniteInRange(0.0, 1.0, "RANGE"))
      ->capture_default_str();
  cmd->add_option("--survey-dropout", o->survey_dropout, "Fraction of survey points dropped")
      ->check(FiniteInRange(0.0, 0.99, "RANGE"))
      ->capture_default_str();
  cmd->add_option("--survey-outliers", o->survey_outliers,
                  "Outliers added, as a fraction of the survey's points, uniform in its bounding box grown by 1 m")
      ->check(FiniteInRange(0.0, 0.5, "RANGE"))
      ->capture_default_str();
  cmd->add_flag("--survey-one-sided", o->survey_one_sided,
                "Leave out the right face of every row (a scanner that saw each row from one side)");
  cmd->add_flag("--survey-terrain", o->survey_terrain, "Also sample the ground not covered by canopy");
  cmd->add_option("--terrain-spacing", o->terrain_spacing_m, "Survey point spacing on the ground [m]")
      ->check(FiniteInRange(1e-3, 100.0, "RANGE"))
      ->capture_default_str();
  cmd->add_option("--octomap-resolution", o->octomap_resolution_m, "OctoMap voxel size [m]")
      ->check(FiniteInRange(2e-3, 20.0, "RANGE"))
      ->capture_default_str();
  cmd->add_option("--seed", o->seed, "Seed of the survey sampling (default: the world's seed)");
  cmd->add_flag("--no-survey", o->no_survey, "Do not write survey.pcd");
  cmd->add_flag("--no-octomap", o->no_octomap, "Do not write canopy.bt");
  cmd->callback([o, cmd] {
    o->seed_given = cmd->count("--seed") > 0;
    RunReportingInputErrors("world", [&o] { RunWorld(*o); });
  });
}

}  // namespace rowloc::apps
