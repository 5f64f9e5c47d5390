// `rowloc replay LOG --vehicle CONFIG [--filter FILTER] [--map ROWMAP] -o ESTIMATES [--period S]
//  [--no-updates] [--skip TYPE ...]`: runs the vehicle EKF (rowloc/localization/vehicle_ekf.hpp) over a sensor log
// (docs/protocol.md §1) and writes the estimate stream (§3): estimate lines with the (x, y, phi)
// covariance and the per-wheel slip every --period seconds of log time (SAE slip from the filter;
// for skid-steer vehicles the track slip i = 1 - eta of the adaptive observer of seed 001) and,
// with slip-aware odometry, each wheel's calibration states R_w and kappa with their sigmas, and one
// update line per measurement update. With --map (a GeoJSON row map, docs/map-format.md) the
// ultrasonic echoes update the filter against the rows (map-aided update, issue 5; the method is the
// filter file's map_aided.method) and the summary counts what happened to every echo; --echo-log
// FILE writes one line per echo with the position ellipse before and after it (scripts/plot-echoes). --skip withholds a message type (counted; ablation runs).
// --smoothed FILE also writes the fixed-interval (RTS) smoothed estimates at the same times
// (fixed_interval_smoother.hpp; docs/localization-filter.md §6): every line then uses every
// measurement of the log, before and after it. Their slip is the same estimator on the smoothed
// state and the raw encoder speeds of that time; skid-steer track slip is the observer's, unsmoothed.
// --calibration ESTIMATES: the R_w and kappa priors of every wheel from a previous drive (the last
// `wheel_calibration` of that estimate stream, e.g. its --smoothed output) instead of the filter
// file's nominal ones (VehicleEkf::SetWheelCalibrationPrior), their sigmas widened by the filter
// file's change between drives (slip_aware_odometry.carried_*_change_sigma*).
// Same log, same configuration: same bytes (the filter is deterministic).
// A message the filter rejects (non-finite, out of range, time going backwards) is logged with its
// line number and counted, never silently dropped; an unreadable or invalid file exits with status 2.
#include "commands.hpp"

#include "rowloc/localization/filter_config.hpp"
#include "rowloc/localization/sensor_log_reader.hpp"
#include "rowloc/localization/track_slip_observer.hpp"
#include "rowloc/localization/vehicle_ekf.hpp"
#include "rowloc/localization/wheel_slip_estimate.hpp"
#include "rowloc/mapio/row_map_geojson.hpp"
#include "rowloc/mapio/vehicle_config.hpp"
#include "rowloc/sim/log_writers.hpp"
#include "rowloc/sim/trajectory_streams.hpp"

#include <nlohmann/json.hpp>
#include <spdlog/fmt/ranges.h>
#include <spdlog/spdlog.h>

#include <algorithm>
#include <cmath>
#include <stdexcept>
#include <filesystem>
#include <limits>
#include <fstream>
#include <map>
#include <memory>
#include <optional>
#include <string>
#include <variant>

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

struct UpdateCounts {
  std::size_t accepted = 0;
  std::size_t rejected = 0;
};

/// Skid-steer vehicles: the adaptive track-slip observer (seed 001 eq. (8)) fed with the filtered
/// pose and the raw sprocket speeds times the sprocket radius after every wheels message.
class TrackSlipTap {
 public:
  explicit TrackSlipTap(const mapio::VehicleConfig& vehicle) {
    if (vehicle.kind != mapio::VehicleKind::kSkidSteer) return;
    const bool first_is_right = vehicle.wheels[0].position_m.y() < vehicle.wheels[1].position_m.y();
    right_ = first_is_right ? 0 : 1;
    localization::TrackSlipObserverConfig config;
    config.track_width_m = std::abs(vehicle.wheels[0].position_m.y() - vehicle.wheels[1].position_m.y());
    observer_.emplace(config);
  }
  bool active() const { return observer_.has_value(); }

  /// False (with the reason in `error`) when the observer refused the input; it is then unchanged.
  bool Observe(const localization::VehicleEkf& ekf, const localization::SensorMessage& message, std::string& error) {
    if (!observer_ || !ekf.initialised() || !std::holds_alternative<localization::WheelsMessage>(message)) return true;
    const std::vector<double>& speeds = ekf.last_wheel_speeds_radps();
    const auto& wheels = ekf.vehicle().wheels;
    const std::size_t left = 1 - right_;
    const Eigen::VectorXd& x = ekf.state();
    try {
      observer_->Update({ekf.time_s(), x(0), x(1), x(2), speeds[right_] * wheels[right_].nominal_radius_m,
                         speeds[left] * wheels[left].nominal_radius_m});
    } catch (const std::invalid_argument& e) {
      error = e.what();
      return false;
    }
    return true;
  }

  /// Track slip i = 1 - eta per track name, once the observer runs.
  std::vector<std::pair<std::string, double>> Slip(const mapio::VehicleConfig& vehicle) const {
    if (!observer_ || !observer_->initialised()) return {};
    return {{vehicle.wheels[right_].name, observer_->slip_right()}, {vehicle.wheels[1 - right_].name, observer_->slip_left()}};
  }

 private:
  std::optional<localization::TrackSlipObserver> observer_;
  std::size_t right_ = 0;
};

/// R_w and kappa of every wheel with their standard deviations (empty without slip-aware odometry).
std::vector<sim::WheelCalibrationRecord> CalibrationOf(const localization::VehicleEkf& ekf, const Eigen::VectorXd& x,
                                                        const Eigen::MatrixXd& p) {
  const localization::StateLayout& layout = ekf.layout();
  if (!layout.slip_aware()) return {};
  std::vector<sim::WheelCalibrationRecord> wheels;
  for (std::size_t i = 0; i < layout.wheel_count(); ++i) {
    const int r = layout.rolling_radius[i], k = layout.slip_compliance[i];
    wheels.push_back({ekf.vehicle().wheels[i].name, x(r), std::sqrt(std::max(p(r, r), 0.0)), x(k),
                      std::sqrt(std::max(p(k, k), 0.0))});
  }
  return wheels;
}

/// The estimate line of state x with covariance p at time_s: pose, calibration, and slip (the track
/// observer's for skid-steer vehicles, else SAE slip from x and the raw encoder speeds, if any).
sim::EstimateRecord EstimateOf(const localization::VehicleEkf& ekf, double time_s, const Eigen::VectorXd& x,
                               const Eigen::MatrixXd& p, const std::vector<double>& speeds_radps,
                               const TrackSlipTap& tracks) {
  sim::EstimateRecord record;
  record.time_s = time_s;
  record.position_m = x.head<2>();
  record.heading_rad = x(localization::StateLayout::kPhi);
  record.covariance = p.topLeftCorner<3, 3>();
  record.wheel_calibration = CalibrationOf(ekf, x, p);
  if (tracks.active()) {
    record.slip = tracks.Slip(ekf.vehicle());
    return record;
  }
  if (speeds_radps.empty()) return record;
  const std::vector<double> slip = localization::EstimateWheelSlip(
      x, ekf.vehicle(), ekf.layout(), speeds_radps, ekf.config().slip_aware_odometry.slip_with_rolling_radius);
  for (std::size_t i = 0; i < slip.size(); ++i) record.slip.emplace_back(ekf.vehicle().wheels[i].name, slip[i]);
  return record;
}

/// The last `wheel_calibration` of an estimate stream, as priors (sigmas as written).
std::vector<localization::WheelCalibrationPrior> CalibrationPriorFrom(const std::string& path) {
  const sim::EstimateStream stream = sim::ReadEstimateStream(path);
  const auto last = std::find_if(stream.estimates.rbegin(), stream.estimates.rend(),
                                 [](const sim::EstimateSample& e) { return !e.wheel_calibration.empty(); });
  if (last == stream.estimates.rend()) {
    throw std::runtime_error(path + ": no estimate with a wheel_calibration (a slip-aware replay writes one)");
  }
  std::vector<localization::WheelCalibrationPrior> prior;
  for (const sim::WheelCalibrationRecord& w : last->wheel_calibration) {
    prior.push_back({w.wheel, w.rolling_radius_m, w.rolling_radius_sigma_m, w.slip_compliance, w.slip_compliance_sigma});
  }
  spdlog::info("wheel calibration prior from {} (t={} s, line {})", path, last->t_s, last->line);
  return prior;
}

/// --smoothed: what each estimate line needs besides the smoothed state (its time, the raw
/// encoder speeds and the track slip of that moment), then the smoothed stream.
class SmoothedStream {
 public:
  void Keep(const localization::VehicleEkf& ekf, const sim::EstimateRecord& filtered) {
    kept_.push_back({filtered.slip, ekf.last_wheel_speeds_radps()});
  }
  /// Writes one smoothed line per kept one; returns the number written.
  std::size_t Write(localization::VehicleEkf& ekf, const TrackSlipTap& tracks, sim::EstimateLogWriter& writer) {
    const std::vector<localization::SmoothedState> smoothed = ekf.FinishSmoothing();
    if (smoothed.size() != kept_.size()) throw std::logic_error("smoothed estimates do not match the marks");
    for (std::size_t i = 0; i < kept_.size(); ++i) {
      sim::EstimateRecord record =
          EstimateOf(ekf, smoothed[i].time_s, smoothed[i].state, smoothed[i].covariance, kept_[i].speeds_radps, tracks);
      if (tracks.active()) record.slip = kept_[i].track_slip;  // the observer's at that time
      writer.Write(record);
    }
    return kept_.size();
  }

 private:
  struct Kept {
    std::vector<std::pair<std::string, double>> track_slip;  ///< the filtered line's (observer's) slip
    std::vector<double> speeds_radps;
  };
  std::vector<Kept> kept_;
};

void WriteUpdates(const localization::ProcessResult& result, sim::EstimateLogWriter& writer, bool write,
                  std::map<std::string, UpdateCounts>& counts) {
  for (const localization::UpdateRecord& u : result.updates) {
    UpdateCounts& c = counts[u.sensor];
    ++(u.outcome.accepted ? c.accepted : c.rejected);
    if (!write || !std::isfinite(u.outcome.nis)) continue;
    writer.WriteUpdate({u.time_s, u.sensor, u.outcome.innovation, u.outcome.innovation_covariance, u.outcome.nis,
                        u.outcome.accepted});
  }
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

void RunReplay(const ReplayOptions& o) {
  const mapio::VehicleConfig vehicle = mapio::LoadVehicleConfig(o.vehicle_path);
  const localization::FilterConfig config =
      o.filter_path.empty() ? localization::FilterConfig{} : localization::LoadFilterConfig(o.filter_path);
  std::ifstream log(o.log_path, std::ios::binary);
  if (!log) throw std::runtime_error(o.log_path + ": cannot open sensor log");
  localization::SensorLogReader reader(log, o.log_path);
  localization::VehicleEkf ekf(vehicle, config, reader.header().origin, reader.header().wheels);
  if (!o.map_path.empty()) {
    try {
      ekf.AttachRowMap(mapio::ReadRowMapGeoJson(o.map_path));
    } catch (const std::invalid_argument& e) {
      throw std::runtime_error(o.map_path + ": " + e.what());
    }
  }
  if (!o.calibration_path.empty()) {
    try {
      ekf.SetWheelCalibrationPrior(CalibrationPriorFrom(o.calibration_path));
    } catch (const std::invalid_argument& e) {
      throw std::runtime_error(o.calibration_path + ": " + e.what());
    }
  }
  std::ofstream out(o.output_path, std::ios::binary | std::ios::trunc);
  if (!out) throw std::runtime_error(o.output_path + ": cannot open for writing");
  std::ofstream echo_log;
  if (!o.echo_log_path.empty()) {
    if (!ekf.has_row_map()) throw std::runtime_error("--echo-log needs --map (echoes are used only against a row map)");
    echo_log.open(o.echo_log_path, std::ios::binary | std::ios::trunc);
    if (!echo_log) throw std::runtime_error(o.echo_log_path + ": cannot open for writing");
    echo_log << nlohmann::ordered_json{{"type", "echo_header"}, {"source", "rowloc replay"}, {"vehicle", vehicle.name},
                               {"method", localization::MapAidedMethodName(config.map_aided.method)}}.dump()
             << '\n';
  }
  sim::EstimateLogWriter writer(out, "rowloc replay", vehicle.name, reader.header().origin);
  std::ofstream smoothed_out;
  std::optional<SmoothedStream> smoothed;
  if (!o.smoothed_path.empty()) {
    if (o.smoothed_path == o.output_path) throw std::runtime_error("--smoothed: the same file as --output");
    smoothed_out.open(o.smoothed_path, std::ios::binary | std::ios::trunc);
    if (!smoothed_out) throw std::runtime_error(o.smoothed_path + ": cannot open for writing");
    ekf.EnableSmoothing();
    smoothed.emplace();
  }
  spdlog::info("replay {} with vehicle {} and filter {}", o.log_path, vehicle.name, config.name);

  TrackSlipTap tracks(vehicle);
  std::map<std::string, UpdateCounts> counts;
  std::size_t input_errors = 0, estimates = 0, skipped = 0, ultrasonic = 0, echo_lines = 0;
  double next_output_s = -std::numeric_limits<double>::infinity();
  while (const auto message = reader.Next()) {
    if (std::find(o.skip_types.begin(), o.skip_types.end(), localization::TypeOf(*message)) != o.skip_types.end()) {
      ++skipped;
      continue;
    }
    if (std::holds_alternative<localization::UltrasonicMessage>(*message)) ++ultrasonic;
    localization::ProcessResult result;
    try {
      result = ekf.Process(*message);
    } catch (const localization::FilterInputError& e) {
      ++input_errors;
      spdlog::warn("{}:{}: rejected: {}", o.log_path, reader.line_number(), e.what());
      continue;
    }
    if (result.notice) spdlog::info("{}:{}: {}", o.log_path, reader.line_number(), *result.notice);
    if (std::string error; !tracks.Observe(ekf, *message, error)) {
      ++input_errors;
      spdlog::warn("{}:{}: track-slip observer rejected the input: {}", o.log_path, reader.line_number(), error);
    }
    WriteUpdates(result, writer, !o.no_updates, counts);
    if (result.echo && echo_log.is_open()) {
      echo_log << EchoLine(ekf.time_s(), *result.echo).dump() << '\n';
      ++echo_lines;
    }
    if (ekf.initialised() && ekf.time_s() >= next_output_s) {
      const sim::EstimateRecord record =
          EstimateOf(ekf, ekf.time_s(), ekf.state(), ekf.covariance(), ekf.last_wheel_speeds_radps(), tracks);
      writer.Write(record);
      if (smoothed) {
        smoothed->Keep(ekf, record);
        ekf.MarkForSmoothing();
      }
      ++estimates;
      next_output_s = ekf.time_s() + o.period_s;
    }
  }
  spdlog::info("{} messages, {} estimates, {} rejected inputs", reader.messages_read(), estimates, input_errors);
  if (ultrasonic > 0 && !ekf.has_row_map()) {
    spdlog::info("{} ultrasonic pings read but not used (no row map: --map)", ultrasonic);
  }
  if (ekf.has_row_map()) {
    const localization::MapAidedStats& s = ekf.map_aided_stats();
    spdlog::info("map-aided ({}): {} echoes; {} without a row segment in the cone, {} with several candidates, "
                 "{} contradicting, {} uninformative, {} degenerate",
                 localization::MapAidedMethodName(config.map_aided.method), s.echoes, s.no_segment, s.ambiguous,
                 s.contradicting, s.uninformative, s.degenerate);
    spdlog::info("map-aided association: {} echoes skipped with an uncertain heading, {} with the sensor inside a "
                 "canopy outline, {} with an ambiguous lane",
                 s.heading_uncertain, s.inside_outline, s.lane_ambiguous);
    const geometry::SegmentQueryCache& cache = ekf.row_search_cache();
    spdlog::info("row search: {} of {} R-tree box queries answered from the cache ({} m margin)", cache.hits(),
                 cache.hits() + cache.misses(), cache.margin_m());
  }
  if (skipped > 0) spdlog::info("{} messages skipped (--skip {})", skipped, fmt::join(o.skip_types, ","));
  for (const auto& [sensor, c] : counts) {
    spdlog::info("updates {}: {} accepted, {} gated out", sensor, c.accepted, c.rejected);
  }
  if (!ekf.initialised()) spdlog::warn("the filter never initialised (no GNSS baseline of {} m)",
                                       config.initialisation.heading_baseline_m);
  if (echo_log.is_open()) {
    echo_log.flush();
    if (!echo_log) throw std::runtime_error(o.echo_log_path + ": write failed");
    spdlog::info("wrote echo log {}: {} echoes", o.echo_log_path, echo_lines);
  }
  spdlog::info("wrote {}", o.output_path);
  if (smoothed) {
    const std::size_t nodes = ekf.smoother()->nodes();
    sim::EstimateLogWriter smoothed_writer(smoothed_out, "rowloc replay --smoothed", vehicle.name,
                                           reader.header().origin);
    const std::size_t lines = smoothed->Write(ekf, tracks, smoothed_writer);
    smoothed_out.flush();
    if (!smoothed_out) throw std::runtime_error(o.smoothed_path + ": write failed");
    spdlog::info("wrote {}: {} smoothed estimates over {} filter nodes", o.smoothed_path, lines, nodes);
  }
}

}  // namespace

void RegisterReplayCommand(CLI::App& app) {
  auto o = std::make_shared<ReplayOptions>();
  CLI::App* cmd = app.add_subcommand("replay", "Run the localization filter over a sensor log: estimate stream");
  cmd->add_option("log", o->log_path, "Sensor log (docs/protocol.md §1)")->required();
  cmd->add_option("--vehicle", o->vehicle_path, "Vehicle file (config/vehicles/*.json)")->required();
  cmd->add_option("--filter", o->filter_path, "Filter file (config/filters/*.json); default: built-in defaults "
                                              "(= config/filters/default.json)");
  cmd->add_option("--map", o->map_path, "Row map (GeoJSON): use the ultrasonic echoes against its rows");
  cmd->add_option("--echo-log", o->echo_log_path,
                  "With --map: one NDJSON line per echo, the position ellipse before and after it");
  cmd->add_option("-o,--output", o->output_path, "Estimate stream to write (docs/protocol.md §3)")->required();
  cmd->add_option("--calibration", o->calibration_path,
                  "Estimate stream of a previous drive: its last wheel_calibration as the R_w and kappa priors "
                  "(sigmas widened by the filter file's carried_*_change_sigma*)");
  cmd->add_option("--smoothed", o->smoothed_path,
                  "Also write the fixed-interval (RTS) smoothed estimates, same times and format (post-run)");
  cmd->add_option("--period", o->period_s, "Log time between estimate lines, s")->check(CLI::PositiveNumber);
  cmd->add_flag("--no-updates", o->no_updates, "Do not write update lines (NIS)");
  cmd->add_option("--skip", o->skip_types, "Message types not given to the filter (e.g. imu: odometry-only runs)")
      ->check(CLI::IsMember({"gps", "imu", "wheels", "steering", "ultrasonic", "vio"}));
  cmd->callback([o] { RunReportingInputErrors("replay", [&o] { RunReplay(*o); }); });
}

}  // namespace rowloc::apps
