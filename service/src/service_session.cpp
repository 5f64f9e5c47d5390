// One session of the service (see service_session.hpp).
#include "rowloc/service/service_session.hpp"

#include "rowloc/formats/estimate_stream_writer.hpp"
#include "rowloc/localization/state_layout.hpp"
#include "rowloc/mapio/local_frame.hpp"
#include "rowloc/service/live_observations.hpp"
#include "rowloc/service/service_error.hpp"

#include <Eigen/Eigenvalues>

#include <algorithm>
#include <cmath>
#include <stdexcept>

namespace rowloc::service {
namespace {

using OrderedJson = nlohmann::ordered_json;

/// Appends ,"session":NAME before the final '}' of a one-line JSON object.
std::string WithSession(std::string line, const std::string& session_json) {
  line.pop_back();  // '}'
  line += ",\"session\":";
  line += session_json;
  line += '}';
  return line;
}

/// Splits text into its lines (without newlines).
std::vector<std::string> Lines(const std::string& text) {
  std::vector<std::string> lines;
  std::size_t start = 0;
  while (start < text.size()) {
    const std::size_t end = text.find('\n', start);
    lines.push_back(text.substr(start, end - start));
    start = end == std::string::npos ? text.size() : end + 1;
  }
  return lines;
}

OrderedJson Finite(double value) { return std::isfinite(value) ? OrderedJson(value) : OrderedJson(nullptr); }

/// The 2-sigma ellipse of a 2x2 position covariance: semi-axes (m) and the major axis's angle from +East.
OrderedJson Ellipse2Sigma(const Eigen::Matrix2d& covariance) {
  const Eigen::SelfAdjointEigenSolver<Eigen::Matrix2d> eigen(0.5 * (covariance + covariance.transpose()));
  const Eigen::Vector2d values = eigen.eigenvalues().cwiseMax(0.0);  // ascending
  const Eigen::Vector2d major = eigen.eigenvectors().col(1);
  double angle = std::atan2(major.y(), major.x());
  if (angle <= -M_PI / 2) angle += M_PI;  // an axis, not a direction: (-pi/2, pi/2]
  if (angle > M_PI / 2) angle -= M_PI;
  return OrderedJson{{"semi_major_m", 2.0 * std::sqrt(values(1))},
                     {"semi_minor_m", 2.0 * std::sqrt(values(0))},
                     {"angle_rad", angle}};
}

}  // namespace

nlohmann::json SessionSpec::ToJson() const {
  nlohmann::json j;
  j["session"] = name;
  j["vehicle"] = vehicle;
  j["vehicle_config"] = vehicle_config;
  j["filter"] = filter;
  j["filter_config"] = filter_config;
  j["map"] = map;
  j["header"] = {{"origin",
                  {{"latitude_deg", header.origin.latitude_deg},
                   {"longitude_deg", header.origin.longitude_deg},
                   {"altitude_m", header.origin.altitude_m}}},
                 {"wheels", header.wheels},
                 {"ultrasonic", header.ultrasonic}};
  j["period_s"] = period_s;
  j["reorder_window_s"] = reorder_window_s;
  j["initial_pose"] = initial_pose ? nlohmann::json(*initial_pose) : nlohmann::json(nullptr);
  return j;
}

SessionSpec SessionSpec::FromJson(const nlohmann::json& j) {
  try {
    SessionSpec spec;
    spec.name = j.at("session").get<std::string>();
    spec.vehicle = j.at("vehicle").get<std::string>();
    spec.vehicle_config = j.at("vehicle_config");
    spec.filter = j.at("filter").get<std::string>();
    spec.filter_config = j.at("filter_config");
    spec.map = j.at("map").get<std::string>();
    const nlohmann::json& h = j.at("header");
    spec.header.protocol = "rowloc/1";
    spec.header.origin = {h.at("origin").at("latitude_deg").get<double>(),
                          h.at("origin").at("longitude_deg").get<double>(),
                          h.at("origin").at("altitude_m").get<double>()};
    spec.header.wheels = h.at("wheels").get<std::vector<std::string>>();
    spec.header.ultrasonic = h.at("ultrasonic").get<std::vector<std::string>>();
    spec.period_s = j.at("period_s").get<double>();
    spec.reorder_window_s = j.at("reorder_window_s").get<double>();
    if (!j.at("initial_pose").is_null()) spec.initial_pose = j.at("initial_pose").get<std::array<double, 6>>();
    return spec;
  } catch (const nlohmann::json::exception& e) {
    throw std::invalid_argument(std::string("session metadata: ") + e.what());
  }
}

ServiceSession::ServiceSession(SessionSpec spec, localization::LocalizationSession session,
                               std::unique_ptr<SessionJournal> journal, double max_time_jump_s)
    : spec_(std::move(spec)),
      session_(std::move(session)),
      reorder_(spec_.reorder_window_s),
      journal_(std::move(journal)),
      max_time_jump_s_(max_time_jump_s),
      frame_(spec_.header.origin) {}

void ServiceSession::AttachJournal(std::unique_ptr<SessionJournal> journal) {
  std::lock_guard lock(mutex_);
  journal_ = std::move(journal);
}

std::optional<std::string> ServiceSession::journal_path() const {
  std::lock_guard lock(mutex_);
  return journal_ ? std::optional<std::string>(journal_->path().string()) : std::nullopt;
}

std::size_t ServiceSession::rejected() const {
  std::lock_guard lock(mutex_);
  return session_.refused();
}

std::size_t ServiceSession::pending() const {
  std::lock_guard lock(mutex_);
  return reorder_.held();
}

void ServiceSession::Touch() {
  std::lock_guard lock(mutex_);
  last_used_ = std::chrono::steady_clock::now();
}

double ServiceSession::idle_s() const {
  std::lock_guard lock(mutex_);
  return std::chrono::duration<double>(std::chrono::steady_clock::now() - last_used_).count();
}

std::size_t ServiceSession::accepted() const {
  std::lock_guard lock(mutex_);
  return accepted_;
}

std::vector<std::string> ServiceSession::Submit(std::string_view raw_line, formats::SensorMessage message,
                                                bool journal) {
  std::lock_guard lock(mutex_);
  last_used_ = std::chrono::steady_clock::now();
  const double t = formats::TimeOf(message);
  if (t < reorder_.released_time_s()) {
    throw ServiceError(ErrorCode::kTooOld,
                       "message at t=" + std::to_string(t) + " s is older than the session's reorder window allows "
                       "(messages up to t=" + std::to_string(reorder_.released_time_s()) +
                       " s were already applied; window " + std::to_string(reorder_.window_s()) + " s)");
  }
  if (std::isfinite(reorder_.newest_time_s()) && t > reorder_.newest_time_s() + max_time_jump_s_) {
    throw ServiceError(ErrorCode::kInvalidField,
                       "t: " + std::to_string(t) + " s jumps more than max_time_jump_s (" +
                           std::to_string(max_time_jump_s_) + " s) ahead of the session's newest message (t=" +
                           std::to_string(reorder_.newest_time_s()) + " s); a new clock needs a new session");
  }
  if (journal && journal_) journal_->Append(raw_line);
  reorder_.Add(std::move(message));
  ++accepted_;
  std::vector<std::string> refusals;
  while (auto ready = reorder_.PopReady()) ProcessReleased(std::move(*ready), refusals);
  return refusals;
}

void ServiceSession::Drain() {
  std::lock_guard lock(mutex_);
  std::vector<std::string> refusals;
  while (auto held = reorder_.PopAny()) ProcessReleased(std::move(*held), refusals);
}

void ServiceSession::ProcessReleased(formats::SensorMessage message, std::vector<std::string>& refusals) {
  const localization::SessionStep step = session_.Process(message);
  if (step.error) {
    last_refusal_ = "t=" + std::to_string(formats::TimeOf(message)) + " s " +
                    std::string(formats::TypeOf(message)) + ": " + *step.error;
    refusals.push_back(*last_refusal_);
  }
  if (!subscribers_.empty()) Publish(message, step);
}

void ServiceSession::FlushJournal(bool sync) {
  std::lock_guard lock(mutex_);
  if (!journal_) return;
  if (sync) {
    journal_->Sync();
  } else {
    journal_->Flush();
  }
}

std::optional<std::string> ServiceSession::Close() {
  Drain();
  std::lock_guard lock(mutex_);
  if (!journal_) return std::nullopt;
  const std::filesystem::path path = journal_->Close();
  journal_.reset();
  return path.string();
}

std::vector<std::string> ServiceSession::EstimateLines(const localization::SessionStep& step) {
  for (const formats::UpdateLogRecord& update : step.updates) estimate_writer_->WriteUpdate(update);
  if (step.estimate) estimate_writer_->Write(*step.estimate);
  std::vector<std::string> lines = Lines(estimate_text_.str());
  estimate_text_.str("");
  const std::string session_json = OrderedJson(spec_.name).dump();
  for (std::string& line : lines) line = WithSession(std::move(line), session_json);
  return lines;
}

void ServiceSession::Publish(const formats::SensorMessage& message, const localization::SessionStep& step) {
  std::vector<std::string> estimate_lines;
  if (estimate_subscribers_ > 0) estimate_lines = EstimateLines(step);
  std::optional<std::vector<std::string>> observation_lines;  // made once, for the first live subscriber
  std::optional<std::string> state_line;
  const double t = session_.filter().time_s();
  for (auto it = subscribers_.begin(); it != subscribers_.end();) {
    const std::shared_ptr<OutputSink> sink = it->sink.lock();
    if (!sink) {
      if (it->stream == StreamKind::kEstimates) --estimate_subscribers_;
      it = subscribers_.erase(it);
      continue;
    }
    if (it->stream == StreamKind::kEstimates) {
      for (const std::string& line : estimate_lines) sink->Push(line, true);
      ++it;
      continue;
    }
    if (it->stream == StreamKind::kLive) {
      if (!observation_lines) {
        observation_lines = LiveObservationLines(message, step, session_.filter(), frame_, OrderedJson(spec_.name).dump());
      }
      for (const std::string& line : *observation_lines) sink->Push(line, true);
    }
    if (step.changed_state && (it->period_s == 0.0 || !(t < it->last_push_t_s + it->period_s))) {
      if (!state_line) {
        OrderedJson state{{"type", "state"}};
        state.update(StateLocked());
        state_line = state.dump();
      }
      sink->Push(*state_line, true);
      it->last_push_t_s = t;
    }
    ++it;
  }
}

void ServiceSession::Subscribe(const std::shared_ptr<OutputSink>& sink, StreamKind stream, double rate_hz,
                               const std::function<std::string(std::size_t subscribers)>& reply) {
  std::lock_guard lock(mutex_);
  last_used_ = std::chrono::steady_clock::now();
  for (auto it = subscribers_.begin(); it != subscribers_.end(); ++it) {
    if (it->client_id != sink->client_id()) continue;
    if (it->stream == StreamKind::kEstimates) --estimate_subscribers_;
    subscribers_.erase(it);
    break;
  }
  sink->Push(reply(subscribers_.size() + 1), false);
  if (stream == StreamKind::kEstimates) {
    if (!estimate_writer_) {
      estimate_writer_.emplace(estimate_text_, localization::kEstimateStreamSource, session_.filter().vehicle().name,
                               spec_.header.origin);
      estimate_header_ = Lines(estimate_text_.str()).at(0);
      estimate_text_.str("");
    }
    ++estimate_subscribers_;
    sink->Push(WithSession(estimate_header_, OrderedJson(spec_.name).dump()), false);
  }
  subscribers_.push_back({sink, sink->client_id(), stream, rate_hz > 0.0 ? 1.0 / rate_hz : 0.0,
                          -std::numeric_limits<double>::infinity()});
}

bool ServiceSession::Unsubscribe(std::uint64_t client_id) {
  std::lock_guard lock(mutex_);
  for (auto it = subscribers_.begin(); it != subscribers_.end(); ++it) {
    if (it->client_id != client_id) continue;
    if (it->stream == StreamKind::kEstimates) --estimate_subscribers_;
    subscribers_.erase(it);
    return true;
  }
  return false;
}

nlohmann::ordered_json ServiceSession::State() const {
  std::lock_guard lock(mutex_);
  return StateLocked();
}

nlohmann::ordered_json ServiceSession::StateLocked() const {
  using L = localization::StateLayout;
  const localization::VehicleEkf& ekf = session_.filter();
  OrderedJson j;
  j["session"] = spec_.name;
  j["t"] = Finite(ekf.time_s());
  j["initialised"] = ekf.initialised();
  if (ekf.initialised()) {
    const Eigen::VectorXd& x = ekf.state();
    const formats::EstimateRecord estimate = session_.CurrentEstimate();
    j["x_m"] = x(L::kX);
    j["y_m"] = x(L::kY);
    j["phi_rad"] = x(L::kPhi);
    const geometry::GeoOrigin geodetic = frame_.ToGeodetic(Eigen::Vector3d(x(L::kX), x(L::kY), 0.0));
    j["latitude_deg"] = geodetic.latitude_deg;
    j["longitude_deg"] = geodetic.longitude_deg;
    const Eigen::Matrix3d p = ekf.covariance().topLeftCorner<3, 3>();
    OrderedJson covariance = OrderedJson::array();
    for (int row = 0; row < 3; ++row)
      for (int col = 0; col < 3; ++col) covariance.push_back(p(row, col));
    j["covariance_xy_phi"] = covariance;  // row-major
    j["ellipse_2sigma"] = Ellipse2Sigma(p.topLeftCorner<2, 2>());
    j["velocity"] = {{"x_mps", x(L::kVx)}, {"y_mps", x(L::kVy)}, {"yaw_rate_radps", x(L::kYawRate)}};
    OrderedJson slip = OrderedJson::object();
    for (const auto& [wheel, value] : estimate.slip) slip[wheel] = Finite(value);
    j["slip"] = slip;
    if (!estimate.wheel_calibration.empty()) {
      OrderedJson calibration = OrderedJson::object();
      for (const formats::WheelCalibrationRecord& w : estimate.wheel_calibration) {
        calibration[w.wheel] = {{"rolling_radius_m", w.rolling_radius_m},
                                {"rolling_radius_sigma_m", w.rolling_radius_sigma_m},
                                {"slip_compliance", w.slip_compliance},
                                {"slip_compliance_sigma", w.slip_compliance_sigma}};
      }
      j["wheel_calibration"] = calibration;
    }
  }
  OrderedJson sensors = OrderedJson::object();
  for (const auto& [sensor, c] : session_.update_counts()) {
    sensors[sensor] = {{"accepted", c.accepted}, {"gated", c.gated}, {"last_nis", Finite(c.last_nis)}};
  }
  const std::optional<double> fix = session_.last_fix_time_s();
  j["health"] = {{"last_fix_age_s", fix ? Finite(ekf.time_s() - *fix) : OrderedJson(nullptr)},
                 {"pending", reorder_.held()},
                 {"rejected_messages", session_.refused()},
                 {"last_rejection", last_refusal_ ? OrderedJson(*last_refusal_) : OrderedJson(nullptr)},
                 {"sensors", sensors}};
  return j;
}

nlohmann::ordered_json ServiceSession::Summary() const {
  std::lock_guard lock(mutex_);
  const localization::VehicleEkf& ekf = session_.filter();
  return OrderedJson{{"session", spec_.name},
                     {"vehicle", ekf.vehicle().name},
                     {"map", spec_.map.empty() ? OrderedJson(nullptr) : OrderedJson(spec_.map)},
                     {"messages", accepted_},
                     {"t", Finite(ekf.time_s())},
                     {"initialised", ekf.initialised()},
                     {"subscribers", subscribers_.size()}};
}

}  // namespace rowloc::service
