// `rowloc replay LOG --vehicle CONFIG [--filter FILTER] [--map ROWMAP] -o ESTIMATES [--period S]
//  [--no-updates] [--skip TYPE ...]`: runs a localization session (rowloc/localization/
// localization_session.hpp, the same one `rowloc serve` runs) over a sensor log (docs/protocol.md §1)
// and writes the estimate stream (§3): estimate lines with the (x, y, phi) covariance and the
// per-wheel slip every --period seconds of log time and, with slip-aware odometry, each wheel's
// calibration states R_w and kappa with their sigmas, and one update line per measurement update.
// With --map (a GeoJSON row map, docs/map-format.md) the ultrasonic echoes update the filter
// against the rows (docs/map-aided-update.md; the method is the filter file's map_aided.method) and
// the summary counts what happened to every echo; --echo-log FILE writes one line per echo with the
// position ellipse before and after it (tools/plot-echoes). --skip withholds a message type
// (counted; ablation runs). A service journal (docs/service.md §8) replays as the service ran it:
// its header's reorder_window_s orders the messages as the session's window did.
// --smoothed FILE also writes the fixed-interval (RTS) smoothed estimates at the same times
// (fixed_interval_smoother.hpp; docs/localization-filter.md §6): every line then uses every
// measurement of the log, before and after it. Their slip is the same estimator on the smoothed
// state and the raw encoder speeds of that time; skid-steer track slip is the observer's, unsmoothed.
// --calibration ESTIMATES: the R_w and kappa priors of every wheel from a previous drive (the last
// `wheel_calibration` of that estimate stream, e.g. its --smoothed output) instead of the filter
// file's nominal ones (VehicleEkf::SetWheelCalibrationPrior), their sigmas widened by the filter
// file's change between drives (slip_aware_odometry.carried_*_change_sigma*).
// Without --filter the vehicle file's recommended filter is used (filter_choice.hpp), else the
// built-in defaults; the log line "replay ... with vehicle ... and filter ..." says which.
// Same log, same configuration: same bytes (the filter is deterministic).
// A message the filter rejects (non-finite, out of range, time going backwards) is logged with its
// line number and counted, never silently dropped; an unreadable or invalid file exits with status 2.
// Outputs are written to temporaries and renamed over their targets only when the replay succeeded;
// an output naming an input (also through links) or another output is refused before anything opens.
#include "commands.hpp"
#include "option_checks.hpp"

#include "rowloc/formats/estimate_stream_writer.hpp"
#include "rowloc/formats/sensor_log_reader.hpp"
#include "rowloc/formats/trajectory_streams.hpp"
#include "rowloc/localization/filter_choice.hpp"
#include "rowloc/localization/filter_config.hpp"
#include "rowloc/localization/localization_session.hpp"
#include "rowloc/localization/reorder_buffer.hpp"
#include "rowloc/mapio/output_file.hpp"
#include "rowloc/mapio/row_map_geojson.hpp"
#include "rowloc/mapio/vehicle_config.hpp"

#include <nlohmann/json.hpp>
#include <spdlog/fmt/ranges.h>
#include <spdlog/spdlog.h>

#include <algorithm>
#include <cerrno>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <memory>
#include <optional>
#include <stdexcept>
#include <string>
#include <variant>
#include <vector>

namespace rowloc::apps {
namespace {

struct ReplayOptions {
  std::string log_path;
  std::string vehicle_path;
  std::string filter_path;
  std::string map_path;
  std::string echo_log_path;  ///< --echo-log: one NDJSON line per echo (EchoTrace)
  std::string smoothed_path;  ///< --smoothed: the fixed-interval smoothed estimate stream
  std::string calibration_path;  ///< --calibration: an estimate stream of a previous drive
  std::string output_path;
  double period_s = 0.1;
  bool no_updates = false;
  std::vector<std::string> skip_types;  ///< message types not given to the filter (ablation runs)
};

/// The last `wheel_calibration` of an estimate stream, as priors (sigmas as written).
std::vector<localization::WheelCalibrationPrior> CalibrationPriorFrom(const std::string& path) {
  const formats::EstimateStream stream = formats::ReadEstimateStream(path);
  const auto last = std::find_if(stream.estimates.rbegin(), stream.estimates.rend(),
                                 [](const formats::EstimateSample& e) { return !e.wheel_calibration.empty(); });
  if (last == stream.estimates.rend()) {
    throw std::runtime_error(path + ": no estimate with a wheel_calibration (a slip-aware replay writes one)");
  }
  std::vector<localization::WheelCalibrationPrior> prior;
  for (const formats::WheelCalibrationRecord& w : last->wheel_calibration) {
    prior.push_back({w.wheel, w.rolling_radius_m, w.rolling_radius_sigma_m, w.slip_compliance, w.slip_compliance_sigma});
  }
  spdlog::info("wheel calibration prior from {} (t={} s, line {})", path, last->t_s, last->line);
  return prior;
}

/// `echo` lines of --echo-log: the position (m) and its covariance (m^2, row-major) before and after
/// the echo, its outcome, and the row segment and local straight row it was measured against.
nlohmann::ordered_json EchoLine(double time_s, const localization::EchoTrace& e) {
  const auto position = [](const Eigen::Vector2d& p, const Eigen::Matrix2d& c) {
    return nlohmann::ordered_json{{"x_m", p.x()}, {"y_m", p.y()}, {"covariance_xy", {c(0, 0), c(0, 1), c(1, 0), c(1, 1)}}};
  };
  nlohmann::ordered_json line{{"type", "echo"},
                      {"t", time_s},
                      {"sensor", e.sensor},
                      {"range_m", e.measured_range_m},
                      {"outcome", e.outcome},
                      {"prior", position(e.prior_position_m, e.prior_covariance)},
                      {"posterior", position(e.posterior_position_m, e.posterior_covariance)},
                      {"segment", nullptr},
                      {"line", nullptr}};
  if (e.segment) line["segment"] = {{e.segment->a.x(), e.segment->a.y()}, {e.segment->b.x(), e.segment->b.y()}};
  if (e.line) line["line"] = {{"normal", {e.line->normal.x(), e.line->normal.y()}}, {"offset_m", e.line->offset_m}};
  return line;
}

void LogSummary(const localization::LocalizationSession& session, const formats::SensorLogReader& reader,
                std::size_t refused_lines, const ReplayOptions& o) {
  const localization::VehicleEkf& ekf = session.filter();
  spdlog::info("{} messages, {} estimates, {} rejected inputs", reader.messages_read(), session.estimates(),
               session.refused() + refused_lines);
  if (session.ultrasonic_pings() > 0 && !ekf.has_row_map()) {
    spdlog::info("{} ultrasonic pings read but not used (no row map: --map)", session.ultrasonic_pings());
  }
  if (ekf.has_row_map()) {
    const localization::MapAidedStats& s = ekf.map_aided_stats();
    spdlog::info("map-aided ({}): {} echoes; {} without a row segment in the cone, {} with several candidates, "
                 "{} contradicting, {} uninformative, {} degenerate",
                 localization::MapAidedMethodName(ekf.config().map_aided.method), s.echoes, s.no_segment, s.ambiguous,
                 s.contradicting, s.uninformative, s.degenerate);
    spdlog::info("map-aided association: {} echoes skipped with an uncertain heading, {} with the sensor inside a "
                 "canopy outline, {} with an ambiguous lane; {} near a corner with an ambiguous along-row position (used "
                 "across the row only, or not at all); range sigma now {:.4f} m",
                 s.heading_uncertain, s.inside_outline, s.lane_ambiguous, s.along_ambiguous, ekf.map_aided_range_sigma_m());
    const geometry::SegmentQueryCache& cache = ekf.row_search_cache();
    spdlog::info("row search: {} of {} R-tree box queries answered from the cache ({} m margin)", cache.hits(),
                 cache.hits() + cache.misses(), cache.margin_m());
  }
  if (session.skipped() > 0) {
    spdlog::info("{} messages skipped (--skip {})", session.skipped(), fmt::join(o.skip_types, ","));
  }
  for (const auto& [sensor, c] : session.update_counts()) {
    spdlog::info("updates {}: {} accepted, {} gated out", sensor, c.accepted, c.gated);
  }
  if (!ekf.initialised()) {
    spdlog::warn("the filter never initialised (no GNSS baseline of {} m)", ekf.config().initialisation.heading_baseline_m);
  }
}

/// The output files of a replay, checked and created (as temporaries) before the run starts, and
/// renamed over their targets only when the whole replay succeeded (mapio::OutputFile).
struct ReplayOutputs {
  std::unique_ptr<mapio::OutputFile> estimates, echoes, smoothed;
  std::size_t echo_lines = 0;
};

/// The files the filter was read from (the recommended one, the bases it extends) are inputs too:
/// no output may overwrite them.
void CheckFilterFilesAreNotOutputs(const localization::FilterChoice& filter, const ReplayOptions& o) {
  if (filter.file.empty()) return;
  std::vector<NamedPath> inputs;
  for (const std::filesystem::path& file : localization::FilterConfigFiles(filter.file)) {
    inputs.push_back({"filter file", file.string()});
  }
  CheckCommandFiles(inputs, {{"--output", o.output_path}, {"--echo-log", o.echo_log_path},
                             {"--smoothed", o.smoothed_path}});
}

void RunReplay(const ReplayOptions& o) {
  // Before anything is opened: no output may name an input (or another output), or a device.
  CheckCommandFiles({{"log", o.log_path}, {"--vehicle", o.vehicle_path}, {"--filter", o.filter_path},
                     {"--map", o.map_path}, {"--calibration", o.calibration_path}},
                    {{"--output", o.output_path}, {"--echo-log", o.echo_log_path}, {"--smoothed", o.smoothed_path}});
  const mapio::VehicleFile vehicle_file = mapio::LoadVehicleFile(o.vehicle_path);
  const mapio::VehicleConfig& vehicle = vehicle_file.vehicle;
  const localization::FilterChoice filter = localization::ChooseFilter(o.filter_path, vehicle_file, o.vehicle_path);
  CheckFilterFilesAreNotOutputs(filter, o);
  const localization::FilterConfig& config = filter.config;
  std::ifstream log(o.log_path, std::ios::binary);
  if (!log) throw std::runtime_error(o.log_path + ": cannot open sensor log: " + std::strerror(errno));
  formats::SensorLogReader reader(log, o.log_path);
  localization::LocalizationSession session(
      vehicle, config, reader.header(),
      {.estimate_period_s = o.period_s, .record_updates = !o.no_updates, .skip_types = o.skip_types});
  if (!o.map_path.empty()) {
    try {
      session.AttachRowMap(mapio::ReadRowMapGeoJson(o.map_path));
    } catch (const std::invalid_argument& e) {
      throw std::runtime_error(o.map_path + ": " + e.what());
    }
  }
  if (!o.calibration_path.empty()) {
    try {
      session.SetWheelCalibrationPrior(CalibrationPriorFrom(o.calibration_path));
    } catch (const std::invalid_argument& e) {
      throw std::runtime_error(o.calibration_path + ": " + e.what());
    }
  }
  ReplayOutputs out;
  out.estimates = std::make_unique<mapio::OutputFile>(o.output_path);
  if (!o.echo_log_path.empty()) {
    if (!session.filter().has_row_map()) {
      throw std::runtime_error("--echo-log needs --map (echoes are used only against a row map)");
    }
    out.echoes = std::make_unique<mapio::OutputFile>(o.echo_log_path);
    out.echoes->stream() << nlohmann::ordered_json{{"type", "echo_header"}, {"source", "rowloc replay"},
                                         {"vehicle", vehicle.name},
                                         {"method", localization::MapAidedMethodName(config.map_aided.method)}}.dump()
               << '\n';
  }
  formats::EstimateLogWriter writer(out.estimates->stream(), localization::kEstimateStreamSource, vehicle.name,
                                    reader.header().origin);
  if (!o.smoothed_path.empty()) {
    out.smoothed = std::make_unique<mapio::OutputFile>(o.smoothed_path);
    session.EnableSmoothing();
  }
  spdlog::info("replay {} with vehicle {} and {}", o.log_path, vehicle.name,
               localization::DescribeFilterChoice(filter, o.vehicle_path));
  if (reader.header().reorder_window_s > 0) {
    spdlog::info("a journal in arrival order: messages ordered within its reorder window of {} s",
                 reader.header().reorder_window_s);
  }

  localization::ReorderBuffer reorder(reader.header().reorder_window_s);
  const auto process = [&](const formats::SensorMessage& message) {
    const localization::SessionStep step = session.Process(message);
    if (step.skipped) return;
    if (step.error) spdlog::warn("{}:{}: rejected: {}", o.log_path, reader.line_number(), *step.error);
    if (step.notice) spdlog::info("{}:{}: {}", o.log_path, reader.line_number(), *step.notice);
    for (const formats::UpdateLogRecord& update : step.updates) writer.WriteUpdate(update);
    if (step.echo && out.echoes) {
      out.echoes->stream() << EchoLine(session.filter().time_s(), *step.echo).dump() << '\n';
      ++out.echo_lines;
    }
    if (step.estimate) writer.Write(*step.estimate);
  };
  // A line the reader refuses (malformed, a value outside its domain, time going backwards) is
  // rejected with its line and key, as the service refuses such a message, and the replay goes on.
  std::size_t refused_lines = 0;
  const auto next = [&]() -> std::optional<formats::SensorMessage> {
    for (;;) {
      try {
        return reader.Next();
      } catch (const formats::SensorLogError& e) {
        if (!reader.readable()) throw;
        spdlog::warn("{}:{}: rejected: {}: {}", o.log_path, e.line(), e.subject(), e.reason());
        ++refused_lines;
      }
    }
  };
  while (auto message = next()) {
    if (reorder.Add(std::move(*message)) == localization::ReorderBuffer::Admission::kTooOld) {
      spdlog::warn("{}:{}: rejected: older than the journal's reorder window", o.log_path, reader.line_number());
      ++refused_lines;
      continue;
    }
    while (auto ready = reorder.PopReady()) process(*ready);
  }
  while (auto held = reorder.PopAny()) process(*held);

  LogSummary(session, reader, refused_lines, o);
  if (out.smoothed) {
    const std::size_t nodes = session.filter().smoother()->nodes();
    formats::EstimateLogWriter smoothed_writer(out.smoothed->stream(), "rowloc replay --smoothed", vehicle.name,
                                               reader.header().origin);
    const std::vector<formats::EstimateRecord> smoothed = session.FinishSmoothing();
    for (const formats::EstimateRecord& record : smoothed) smoothed_writer.Write(record);
    out.smoothed->Commit();
    spdlog::info("wrote {}: {} smoothed estimates over {} filter nodes", o.smoothed_path, smoothed.size(), nodes);
  }
  if (out.echoes) {
    out.echoes->Commit();
    spdlog::info("wrote echo log {}: {} echoes", o.echo_log_path, out.echo_lines);
  }
  out.estimates->Commit();
  spdlog::info("wrote {}", o.output_path);
}

}  // namespace

void RegisterReplayCommand(CLI::App& app) {
  auto o = std::make_shared<ReplayOptions>();
  CLI::App* cmd = app.add_subcommand("replay", "Run the localization filter over a sensor log: estimate stream");
  cmd->add_option("log", o->log_path, "Sensor log (docs/protocol.md §1) or a service journal")->required();
  cmd->add_option("--vehicle", o->vehicle_path, "Vehicle file (config/vehicles/*.json)")->required();
  cmd->add_option("--filter", o->filter_path,
                  "Filter file (config/filters/*.json); default: the one the vehicle file recommends "
                  "(recommended_filter), else the built-in defaults (= config/filters/default.json). The log "
                  "says which filter was used");
  cmd->add_option("--map", o->map_path, "Row map (GeoJSON): use the ultrasonic echoes against its rows");
  cmd->add_option("--echo-log", o->echo_log_path,
                  "With --map: one NDJSON line per echo, the position ellipse before and after it");
  cmd->add_option("-o,--output", o->output_path, "Estimate stream to write (docs/protocol.md §3)")->required();
  cmd->add_option("--calibration", o->calibration_path,
                  "Estimate stream of a previous drive: its last wheel_calibration as the R_w and kappa priors "
                  "(sigmas widened by the filter file's carried_*_change_sigma*)");
  cmd->add_option("--smoothed", o->smoothed_path,
                  "Also write the fixed-interval (RTS) smoothed estimates, same times and format (post-run)");
  cmd->add_option("--period", o->period_s, "Log time between estimate lines, s")->check(PositiveNumber());
  cmd->add_flag("--no-updates", o->no_updates, "Do not write update lines (NIS)");
  cmd->add_option("--skip", o->skip_types, "Message types not given to the filter (e.g. imu: odometry-only runs)")
      ->check(CLI::IsMember({"gps", "imu", "wheels", "steering", "ultrasonic", "vio"}));
  cmd->callback([o] { RunReportingInputErrors("replay", [&o] { RunReplay(*o); }); });
}

}  // namespace rowloc::apps
