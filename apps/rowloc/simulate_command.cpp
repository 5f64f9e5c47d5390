// `rowloc simulate SCENARIO -o RUN_DIR [--seed N] [--no-baselines]`: runs a scenario
// (docs/simulation-scenarios.md) and writes RUN_DIR/sensors.ndjson, truth.ndjson,
// baseline-gnss.ndjson, baseline-odometry.ndjson and, with a world, row-map.geojson (the true row
// map at the scenario's row_map_height_m). Progress is logged every 10 % of the simulated time.
// Errors (unreadable or invalid scenario, a route the vehicle cannot drive, unwritable output)
// exit with status 2 and name the file, key and reason.
#include "commands.hpp"
#include "option_checks.hpp"

#include "rowloc/mapio/output_file.hpp"
#include "rowloc/mapio/row_map_geojson.hpp"
#include "rowloc/sim/simulation.hpp"

#include <spdlog/spdlog.h>

#include <chrono>
#include <cstdint>
#include <filesystem>
#include <memory>
#include <optional>
#include <string>

namespace rowloc::apps {
namespace {

/// Outline sampling tolerance of the written true row map (RowWorld::StepForTolerance).
constexpr double kRowMapToleranceM = 1e-3;

struct SimulateOptions {
  std::string scenario_path;
  std::string output_dir;
  std::optional<std::uint64_t> seed;
  bool no_baselines = false;
};

void WriteTrueRowMap(const sim::Scenario& scenario, const std::filesystem::path& path) {
  const sim::RowWorld world(*scenario.world);
  const geometry::RowMap map =
      world.TrueRowMap(scenario.row_map_height_m, world.StepForTolerance(kRowMapToleranceM));
  mapio::WriteRowMapGeoJson(map, path);
  spdlog::info("true row map at {} m above the terrain: {}", scenario.row_map_height_m, path.string());
}

void RunSimulate(const SimulateOptions& o) {
  const std::filesystem::path dir(o.output_dir);
  const auto file = [&dir](const char* name) { return (dir / name).string(); };
  CheckCommandFiles({{"scenario", o.scenario_path}},
                    {{"--output", file("sensors.ndjson")}, {"--output", file("truth.ndjson")},
                     {"--output", file("baseline-gnss.ndjson")}, {"--output", file("baseline-odometry.ndjson")},
                     {"--output", file("row-map.geojson")}});
  const sim::Scenario scenario = sim::LoadScenario(o.scenario_path);
  std::filesystem::create_directories(dir);
  // Temporaries renamed over the targets only when the whole run succeeded (mapio::OutputFile).
  mapio::OutputFile sensors(dir / "sensors.ndjson");
  mapio::OutputFile truth(dir / "truth.ndjson");
  std::unique_ptr<mapio::OutputFile> baseline_gnss, baseline_odometry;
  sim::SimulationOutputs outputs{&sensors.stream(), &truth.stream(), nullptr, nullptr};
  if (!o.no_baselines) {
    baseline_gnss = std::make_unique<mapio::OutputFile>(dir / "baseline-gnss.ndjson");
    baseline_odometry = std::make_unique<mapio::OutputFile>(dir / "baseline-odometry.ndjson");
    outputs.baseline_gnss = &baseline_gnss->stream();
    outputs.baseline_odometry = &baseline_odometry->stream();
  }
  sim::SimulationOptions options;
  options.seed = o.seed;
  int next_percent = 0;
  options.progress = [&next_percent](double time_s, double duration_s) {
    const int percent = duration_s > 0.0 ? static_cast<int>(100.0 * time_s / duration_s) : 100;
    if (percent >= next_percent) {
      spdlog::info("simulated {:.1f} / {:.1f} s ({}%)", time_s, duration_s, percent);
      next_percent = percent - percent % 10 + 10;
    }
  };
  spdlog::info("scenario {} (seed {}): {}", scenario.name, o.seed.value_or(scenario.seed), scenario.description);
  const auto start = std::chrono::steady_clock::now();
  const sim::SimulationSummary s = sim::RunSimulation(scenario, outputs, options);
  const double wall_s = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  sensors.Commit();
  truth.Commit();
  if (baseline_gnss) baseline_gnss->Commit();
  if (baseline_odometry) baseline_odometry->Commit();
  if (scenario.world) WriteTrueRowMap(scenario, dir / "row-map.geojson");
  spdlog::info("{:.1f} s simulated ({:.1f} m) in {:.2f} s wall time: {:.0f}x real time", s.duration_s, s.distance_m,
               wall_s, wall_s > 0.0 ? s.duration_s / wall_s : 0.0);
  spdlog::info("{} sensor messages: gps {} fixes / {} without fix ({} with multipath), imu {}, wheels {}, "
               "steering {}, vio {}, ultrasonic {} echoes / {} without echo; {} truth records",
               s.sensor_messages, s.gps_fixes, s.gps_no_fix, s.gps_multipath, s.imu, s.wheels, s.steering, s.vio,
               s.ultrasonic_echoes, s.ultrasonic_no_echo, s.truth_records);
  spdlog::info("largest |slip| {:.4f}; {} wheel samples at the traction limit", s.max_abs_slip,
               s.traction_limited_samples);
  if (!o.no_baselines) spdlog::info("baseline odometry final error {:.3f} m", s.baseline_odometry_final_error_m);
  spdlog::info("wrote {}", dir.string());
}

}  // namespace

void RegisterSimulateCommand(CLI::App& app) {
  auto o = std::make_shared<SimulateOptions>();
  CLI::App* cmd = app.add_subcommand("simulate", "Run a simulation scenario: sensor log, ground truth, baselines");
  cmd->add_option("scenario", o->scenario_path, "Scenario file (docs/simulation-scenarios.md)")->required();
  cmd->add_option("-o,--output", o->output_dir, "Run directory (created if missing)")->required();
  cmd->add_option("--seed", o->seed, "Override the scenario's seed (Monte-Carlo runs)")
      ->check(NonNegativeNumber());
  cmd->add_flag("--no-baselines", o->no_baselines, "Do not write the GNSS and odometry baseline estimates");
  cmd->callback([o] { RunReportingInputErrors("simulate", [&o] { RunSimulate(*o); }); });
}

}  // namespace rowloc::apps
