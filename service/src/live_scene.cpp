// The live view's scene message (see live_scene.hpp).
#include "rowloc/service/live_scene.hpp"

#include "rowloc/mapio/vehicle_config.hpp"

#include <nlohmann/json.hpp>

namespace rowloc::service {
namespace {

using OrderedJson = nlohmann::ordered_json;

OrderedJson VehicleJson(const mapio::VehicleConfig& vehicle) {
  OrderedJson wheels = OrderedJson::array(), rangers = OrderedJson::array();
  for (const mapio::WheelGeometry& w : vehicle.wheels) {
    wheels.push_back({{"name", w.name}, {"x_m", w.position_m.x()}, {"y_m", w.position_m.y()},
                      {"radius_m", w.nominal_radius_m}});
  }
  for (const mapio::SensorMount& m : vehicle.ultrasonic) {
    rangers.push_back({{"name", m.name}, {"x_m", m.position_m.x()}, {"y_m", m.position_m.y()}, {"yaw_rad", m.yaw_rad}});
  }
  return OrderedJson{{"name", vehicle.name},
                     {"kind", mapio::VehicleKindName(vehicle.kind)},
                     {"wheels", wheels},
                     {"ultrasonic", rangers},
                     {"gnss_antenna", {{"x_m", vehicle.gnss_antenna.position_m.x()},
                                       {"y_m", vehicle.gnss_antenna.position_m.y()}}}};
}

OrderedJson RowsJson(const geometry::RowMap& map) {
  OrderedJson rows = OrderedJson::array();
  for (const geometry::Row& row : map.rows) {
    OrderedJson points = OrderedJson::array();
    for (const Eigen::Vector2d& p : row.points_m) points.push_back(OrderedJson::array({p.x(), p.y()}));
    rows.push_back({{"id", row.id}, {"closed", row.closed}, {"points", points}});
  }
  return rows;
}

}  // namespace

std::string LiveSceneLine(const ServiceSession& session, const geometry::RowMap* map, const std::string& map_error) {
  const SessionSpec& spec = session.spec();
  // The spec's vehicle configuration was parsed when the session was built: it parses again.
  const mapio::VehicleConfig vehicle = mapio::ParseVehicleConfig(spec.vehicle_config.dump(), "vehicle");
  const OrderedJson scene{{"type", "scene"},
                          {"session", spec.name},
                          {"vehicle", VehicleJson(vehicle)},
                          {"map", spec.map.empty() ? OrderedJson(nullptr) : OrderedJson(spec.map)},
                          {"rows", map ? RowsJson(*map) : OrderedJson::array()},
                          {"map_error", map_error.empty() ? OrderedJson(nullptr) : OrderedJson(map_error)}};
  return scene.dump(-1, ' ', false, nlohmann::json::error_handler_t::replace);
}

}  // namespace rowloc::service
