// The live stream's observation lines (see live_observations.hpp).
#include "rowloc/service/live_observations.hpp"

#include "rowloc/formats/gnss_fix_quality.hpp"
#include "rowloc/localization/state_layout.hpp"

#include <Eigen/Geometry>
#include <nlohmann/json.hpp>

#include <algorithm>
#include <cmath>
#include <variant>

namespace rowloc::service {
namespace {

using OrderedJson = nlohmann::ordered_json;

OrderedJson Point(const Eigen::Vector2d& p) { return OrderedJson::array({p.x(), p.y()}); }

/// The one-line JSON of `j` with `"session":NAME` appended.
std::string WithSession(const OrderedJson& j, const std::string& session_json) {
  std::string line = j.dump(-1, ' ', false, nlohmann::json::error_handler_t::replace);
  line.pop_back();
  line += ",\"session\":" + session_json + "}";
  return line;
}

/// The update record of `sensor` among the step's updates, if the filter made one.
const formats::UpdateLogRecord* UpdateOf(const localization::SessionStep& step, const std::string& sensor) {
  for (const formats::UpdateLogRecord& update : step.updates) {
    if (update.sensor == sensor) return &update;
  }
  return nullptr;
}

std::vector<std::string> GnssLines(const formats::GpsMessage& gps, const localization::SessionStep& step,
                                   const mapio::LocalFrame& frame, const std::string& session_json) {
  if (!gps.position) return {};
  const formats::GpsPosition& p = *gps.position;
  const Eigen::Vector3d enu = frame.ToEnu(p.latitude_deg, p.longitude_deg, p.altitude_m);
  OrderedJson j{{"type", "gnss"},
                {"t", gps.time_s},
                {"sensor", gps.sensor},
                {"fix", formats::GnssFixQualityName(gps.fix)},
                {"x_m", enu.x()},
                {"y_m", enu.y()},
                {"sigma_m", p.sigma_horizontal_m}};
  // No update record: the filter was not initialised yet (or initialised from this fix).
  const formats::UpdateLogRecord* update = UpdateOf(step, gps.sensor.empty() ? "gnss" : gps.sensor);
  j["accepted"] = update ? OrderedJson(update->accepted) : OrderedJson(nullptr);
  j["nis"] = update ? OrderedJson(update->nis) : OrderedJson(nullptr);
  return {WithSession(j, session_json)};
}

std::vector<std::string> EchoLines(const localization::EchoTrace& echo, const localization::VehicleEkf& filter,
                                   double time_s, const std::string& session_json) {
  using L = localization::StateLayout;
  if (!filter.initialised()) return {};
  const mapio::VehicleConfig& vehicle = filter.vehicle();
  const auto mount = std::find_if(vehicle.ultrasonic.begin(), vehicle.ultrasonic.end(),
                                  [&](const mapio::SensorMount& m) { return m.name == echo.sensor; });
  if (mount == vehicle.ultrasonic.end() || !std::isfinite(echo.measured_range_m)) return {};
  const Eigen::VectorXd& x = filter.state();
  const double phi = x(L::kPhi);
  const Eigen::Vector2d position(x(L::kX), x(L::kY));
  const Eigen::Rotation2Dd rotation(phi);
  const Eigen::Vector2d from = position + rotation * mount->position_m.head<2>();
  const double direction = phi + mount->yaw_rad;
  const Eigen::Vector2d to = from + echo.measured_range_m * Eigen::Vector2d(std::cos(direction), std::sin(direction));
  OrderedJson j{{"type", "echo"},      {"t", time_s},        {"sensor", echo.sensor},
                {"range_m", echo.measured_range_m}, {"outcome", echo.outcome}, {"from", Point(from)},
                {"to", Point(to)}};
  j["segment"] = echo.segment ? OrderedJson::array({Point(echo.segment->a), Point(echo.segment->b)})
                              : OrderedJson(nullptr);
  return {WithSession(j, session_json)};
}

}  // namespace

std::vector<std::string> LiveObservationLines(const formats::SensorMessage& message,
                                              const localization::SessionStep& step,
                                              const localization::VehicleEkf& filter,
                                              const mapio::LocalFrame& frame, const std::string& session_json) {
  if (const auto* gps = std::get_if<formats::GpsMessage>(&message)) {
    return GnssLines(*gps, step, frame, session_json);
  }
  if (const auto* us = std::get_if<formats::UltrasonicMessage>(&message); us && step.echo) {
    return EchoLines(*step.echo, filter, us->time_s, session_json);
  }
  return {};
}

}  // namespace rowloc::service
