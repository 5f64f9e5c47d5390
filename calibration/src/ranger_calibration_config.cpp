// The ranger calibration's configuration: a JSON overlay on the defaults, and its checks
// (ranger_calibration.hpp); and CalibrateRangers, which runs the fit on a recorded drive.
#include "rowloc/calibration/ranger_calibration.hpp"

#include <nlohmann/json.hpp>

#include <algorithm>
#include <cmath>
#include <limits>
#include <optional>
#include <string>
#include <variant>
#include <vector>

namespace rowloc::calibration {
namespace {

using Field = std::variant<double*, int*, std::size_t*, bool*>;

std::vector<std::pair<const char*, Field>> Fields(RangerCalibrationConfig& config) {
  localization::RangerMountFitConfig& c = config.fit;
  return {{"knot_interval_s", &config.knot_interval_s},
          {"association_gate_m", &c.association_gate_m},
          {"refined_gate_m", &c.refined_gate_m},
          {"range_sigma_m", &c.range_sigma_m},
          {"huber_sigmas", &c.huber_sigmas},
          {"position_walk_mps_per_sqrt_s", &c.position_walk_mps_per_sqrt_s},
          {"heading_walk_rad_per_sqrt_s", &c.heading_walk_rad_per_sqrt_s},
          {"position_anchor_sigma_m", &c.position_anchor_sigma_m},
          {"heading_anchor_sigma_rad", &c.heading_anchor_sigma_rad},
          {"mount_prior_scale_m", &c.mount_prior_scale_m},
          {"max_knot_gap_s", &c.max_knot_gap_s},
          {"outer_iterations", &c.outer_iterations},
          {"max_solver_iterations", &c.max_solver_iterations},
          {"min_echoes_per_ranger", &c.min_echoes_per_ranger},
          {"min_associated_fraction", &c.min_associated_fraction},
          {"estimate_across_beam", &c.estimate_across_beam}};
}

void Read(const nlohmann::json& value, double* out, const std::string& where) {
  if (!value.is_number()) throw RangerCalibrationError(where + ": a number is expected");
  *out = value.get<double>();
}
void Read(const nlohmann::json& value, int* out, const std::string& where) {
  if (!value.is_number_integer()) throw RangerCalibrationError(where + ": an integer is expected");
  const auto v = value.get<long long>();
  if (v < std::numeric_limits<int>::min() || v > std::numeric_limits<int>::max()) {
    throw RangerCalibrationError(where + ": out of range");
  }
  *out = static_cast<int>(v);
}
void Read(const nlohmann::json& value, std::size_t* out, const std::string& where) {
  if (!value.is_number_unsigned()) throw RangerCalibrationError(where + ": a non-negative integer is expected");
  *out = value.get<std::size_t>();
}

void Read(const nlohmann::json& value, bool* out, const std::string& where) {
  if (!value.is_boolean()) throw RangerCalibrationError(where + ": true or false is expected");
  *out = value.get<bool>();
}

bool PositiveFinite(double v) { return v > 0.0 && std::isfinite(v); }

}  // namespace

RangerCalibrationConfig ParseRangerCalibrationConfig(const std::string& json_text, const std::string& source) {
  nlohmann::json document;
  try {
    document = nlohmann::json::parse(json_text);
  } catch (const nlohmann::json::parse_error& e) {
    throw RangerCalibrationError(source + ": not JSON: " + e.what());
  }
  if (!document.is_object()) throw RangerCalibrationError(source + ": a JSON object is expected");
  RangerCalibrationConfig config;
  const auto fields = Fields(config);
  for (const auto& [key, value] : document.items()) {
    const auto it = std::find_if(fields.begin(), fields.end(), [&](const auto& f) { return key == f.first; });
    if (it == fields.end()) {
      std::string known;
      for (const auto& f : fields) known += std::string(known.empty() ? "" : ", ") + f.first;
      throw RangerCalibrationError(source + ": " + key + ": unknown key (known: " + known + ")");
    }
    std::visit([&](auto* out) { Read(value, out, source + ": " + key); }, it->second);
  }
  try {
    ValidateRangerCalibrationConfig(config);
  } catch (const RangerCalibrationError& e) {
    throw RangerCalibrationError(source + ": " + e.what());
  }
  return config;
}

void ValidateRangerCalibrationConfig(const RangerCalibrationConfig& c) {
  if (!PositiveFinite(c.knot_interval_s)) throw RangerCalibrationError("knot_interval_s must be positive and finite");
  try {
    localization::ValidateRangerMountFitConfig(c.fit);
  } catch (const localization::RangerMountFitError& e) {
    throw RangerCalibrationError(e.what());
  }
  if (c.fit.max_knot_gap_s < c.knot_interval_s) {
    throw RangerCalibrationError("max_knot_gap_s must be at least knot_interval_s");
  }
}

RangerMountFit CalibrateRangers(const DriveRecord& drive, const geometry::RowMap& map,
                                const mapio::VehicleConfig& vehicle, const localization::FilterConfig& filter,
                                const RangerCalibrationConfig& config) {
  ValidateRangerCalibrationConfig(config);
  if (vehicle.ultrasonic.empty()) {
    throw RangerCalibrationError("the vehicle '" + vehicle.name + "' has no ultrasonic sensor to calibrate");
  }
  std::optional<localization::RowMapRanging> ranging;
  try {
    ranging.emplace(map, drive.origin, filter.map_aided.row_smoothing_m);
  } catch (const std::invalid_argument& e) {
    throw RangerCalibrationError(std::string("row map: ") + e.what());
  }
  try {
    return localization::FitRangerMounts(*ranging, vehicle.ultrasonic, filter.map_aided.cone_half_angle_rad,
                                         filter.map_aided.max_range_m, drive.knots, drive.echoes, config.fit);
  } catch (const localization::RangerMountFitError& e) {
    throw RangerCalibrationError(e.what());
  }
}

mapio::VehicleConfig ApplyRangerCalibration(mapio::VehicleConfig vehicle, const RangerMountFit& calibration) {
  for (const RangerMountEstimate& r : calibration.rangers) {
    if (!r.calibrated) continue;
    for (mapio::SensorMount& m : vehicle.ultrasonic) {
      if (m.name == r.name) m.position_m.head<2>() = r.lever_arm_m;
    }
  }
  return vehicle;
}

}  // namespace rowloc::calibration
