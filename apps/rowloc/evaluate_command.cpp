// `rowloc evaluate TRUTH ESTIMATES -o REPORT_DIR`: compares an estimate stream with the ground
// truth (docs/protocol.md §2-3) and writes report.txt, report.json and plots/ (docs/validation.md).
// Errors (unreadable or malformed input, an estimate outside the truth's span) exit with status 2.
#include "commands.hpp"
#include "option_checks.hpp"

#include "rowloc/formats/trajectory_streams.hpp"
#include "rowloc/geometry/segment_index.hpp"
#include "rowloc/mapio/row_map_geojson.hpp"
#include "rowloc/sim/evaluation_report.hpp"
#include "rowloc/sim/metrics.hpp"
#include "rowloc/sim/report_plots.hpp"

#include <fmt/format.h>
#include <spdlog/spdlog.h>

#include <exception>
#include <memory>
#include <optional>
#include <stdexcept>
#include <string>

namespace rowloc::apps {
namespace {

struct EvaluateOptions {
  std::string truth_path;
  std::string estimates_path;
  std::string output_dir;
  std::string map_path;
  std::size_t max_lag = 50;
  bool clip_to_truth = false;
  double settle_s = 0.0;  ///< estimates and updates of the first settle_s after the first estimate are not evaluated
  double drift_min_duration_s = 5.0;
  sim::PlotOptions plot;
  bool no_plots = false;
  bool json = false;
};

formats::LineProgress ProgressFor(const std::string& path) {
  return [path](std::size_t lines) { spdlog::info("{}: {} lines read", path, lines); };
}

void MakePlots(const EvaluateOptions& o, const sim::EvaluationResult& result, const formats::TruthStream& truth,
               const formats::EstimateStream& estimates, const std::optional<geometry::RowMap>& map) {
  const sim::PlotFiles files = sim::WritePlotFiles(result, truth, estimates, map,
                                                   std::filesystem::path(o.output_dir) / "plots", o.plot);
  const sim::GnuplotRun run = sim::RunGnuplot(files);
  if (!run.ran || run.exit_code != 0) {
    spdlog::warn("plots not drawn: {}", run.message);
    return;
  }
  for (const std::string& svg : files.svg_files) spdlog::info("plot: {}", (files.directory / svg).string());
}

/// --clip-to-truth: estimates and updates outside the truth's time span are dropped, and counted in
/// the log (a replay's last messages may follow the simulator's last truth sample).
void ClipToTruth(formats::EstimateStream& estimates, const formats::TruthStream& truth) {
  if (truth.samples.empty()) return;
  const double first = truth.samples.front().t_s, last = truth.samples.back().t_s;
  const auto outside = [&](const auto& sample) { return sample.t_s < first || sample.t_s > last; };
  const auto dropped_estimates = std::erase_if(estimates.estimates, outside);
  const auto dropped_updates = std::erase_if(estimates.updates, outside);
  if (dropped_estimates + dropped_updates > 0) {
    spdlog::warn("--clip-to-truth: {} estimates and {} updates outside the truth's span [{} s, {} s] not evaluated",
                 dropped_estimates, dropped_updates, first, last);
  }
}

/// --settle S: the filter's convergence (the first S seconds after its first estimate) is left out,
/// so that mean and max describe the converged filter; the count is logged.
void DropSettling(formats::EstimateStream& estimates, double settle_s) {
  if (settle_s <= 0.0 || estimates.estimates.empty()) return;
  const double until = estimates.estimates.front().t_s + settle_s;
  const auto settling = [&](const auto& sample) { return sample.t_s < until; };
  const auto dropped_estimates = std::erase_if(estimates.estimates, settling);
  const auto dropped_updates = std::erase_if(estimates.updates, settling);
  spdlog::info("--settle {} s: {} estimates and {} updates before t = {} s not evaluated", settle_s,
               dropped_estimates, dropped_updates, until);
  if (estimates.estimates.empty()) throw std::runtime_error("--settle: no estimate left after " + std::to_string(until) + " s");
}

void RunEvaluate(const EvaluateOptions& o) {
  const std::filesystem::path dir(o.output_dir);
  CheckCommandFiles({{"truth", o.truth_path}, {"estimates", o.estimates_path}, {"--map", o.map_path}},
                    {{"--output", (dir / "report.txt").string()}, {"--output", (dir / "report.json").string()}});
  const formats::TruthStream truth = formats::ReadTruthStream(o.truth_path, ProgressFor(o.truth_path));
  spdlog::info("{}: {} truth samples", o.truth_path, truth.samples.size());
  formats::EstimateStream estimates = formats::ReadEstimateStream(o.estimates_path, ProgressFor(o.estimates_path));
  if (o.clip_to_truth) ClipToTruth(estimates, truth);
  DropSettling(estimates, o.settle_s);
  spdlog::info("{}: {} estimates, {} updates", o.estimates_path, estimates.estimates.size(), estimates.updates.size());
  std::optional<geometry::RowMap> map;
  sim::EvaluationOptions options;
  options.max_lag = o.max_lag;
  options.drift_min_duration_s = o.drift_min_duration_s;
  if (!o.map_path.empty()) {
    map = mapio::ReadRowMapGeoJson(o.map_path);
    options.rows = geometry::SegmentIndex::FromRowMap(*map);
  }
  const sim::EvaluationResult result = sim::Evaluate(truth, estimates, options);
  const sim::ReportInputs inputs{o.truth_path, o.estimates_path, o.map_path, estimates.updates.size(),
                                 truth.skipped_lines, estimates.skipped_lines};
  sim::WriteReport(result, inputs, o.output_dir);
  if (o.json) {
    fmt::print("{}", sim::FormatReportJson(result, inputs));
  } else {
    fmt::print("{}", sim::FormatReportText(result, inputs));
  }
  spdlog::info("report: {}/report.txt, {}/report.json", o.output_dir, o.output_dir);
  if (!o.no_plots) MakePlots(o, result, truth, estimates, map);
}

}  // namespace

void RegisterEvaluateCommand(CLI::App& app) {
  auto o = std::make_shared<EvaluateOptions>();
  CLI::App* cmd = app.add_subcommand(
      "evaluate", "Compare estimates with the ground truth: error, NEES/NIS, whiteness, drift, slip, rolling radius (report + plots)");
  cmd->add_option("truth", o->truth_path, "Ground-truth stream (NDJSON, docs/protocol.md §2)")->required();
  cmd->add_option("estimates", o->estimates_path, "Estimate stream (NDJSON, docs/protocol.md §3)")->required();
  cmd->add_option("-o,--output", o->output_dir, "Report directory (report.txt, report.json, plots/)")->required();
  cmd->add_option("--map", o->map_path, "Row map (GeoJSON): along/across relative to the rows, rows in the plot");
  cmd->add_option("--max-lag", o->max_lag, "Whiteness: autocorrelation lags 1..N")->check(PositiveNumber());
  cmd->add_option("--drift-min-duration", o->drift_min_duration_s, "Shortest GNSS outage reported as drift [s]")
      ->check(NonNegativeNumber());
  cmd->add_option("--ellipse-interval", o->plot.ellipse_interval_s, "Seconds between plotted ellipses")
      ->check(PositiveNumber());
  cmd->add_option("--k-sigma", o->plot.k_sigma, "Ellipse and envelope scale k (P = k^2 S)")->check(PositiveNumber());
  cmd->add_flag("--no-plots", o->no_plots, "Do not write or draw plots");
  cmd->add_option("--settle", o->settle_s, "Leave out the first S seconds after the first estimate (convergence)")
      ->check(NonNegativeNumber());
  cmd->add_flag("--clip-to-truth", o->clip_to_truth,
                "Drop (and count) estimates outside the truth's time span instead of failing");
  cmd->add_flag("--json", o->json, "Print the JSON summary to stdout instead of the text report");
  cmd->callback([o] { RunReportingInputErrors("evaluate", [&o] { RunEvaluate(*o); }); });
}

}  // namespace rowloc::apps
