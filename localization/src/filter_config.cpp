// Filter configuration files (filter_config.hpp). The reader checks types and key sets; every
// value rule lives in FilterConfigProblem so that in-code and file configurations obey the same.
#include "rowloc/localization/filter_config.hpp"

#include "rowloc/mapio/detail/json_object_reader.hpp"

#include <algorithm>
#include <cmath>
#include <numbers>
#include <stdexcept>
#include <vector>

namespace rowloc::localization {
namespace {

using Reader = mapio::detail::JsonObjectReader<FilterConfigError>;

bool IsPositive(double value) { return std::isfinite(value) && value > 0.0; }
bool IsProbability(double value) { return std::isfinite(value) && value > 0.0 && value < 1.0; }

constexpr int kMaxSpeedUpdateIterations = 10;  ///< wheels.speed_update_iterations (1 to this)

/// What a value must be: finite and > 0 (the default), in (0, 1), finite and >= 0, or in [0, 1).
enum class Domain { kPositive, kProbability, kNonNegative, kFraction };

struct Rule {
  const char* key;
  double value;
  Domain domain = Domain::kPositive;
};

std::vector<Rule> Rules(const FilterConfig& c) {
  const ProcessNoise& q = c.process_noise;
  const SlipAwareOdometryConfig& s = c.slip_aware_odometry;
  const InitialisationConfig& i = c.initialisation;
  return {
      {"process_noise.jerk_mps3_per_sqrt_hz", q.jerk_mps3_per_sqrt_hz},
      {"process_noise.yaw_acceleration_radps2_per_sqrt_hz", q.yaw_acceleration_radps2_per_sqrt_hz},
      {"process_noise.velocity_mps_per_sqrt_hz", q.velocity_mps_per_sqrt_hz},
      {"process_noise.steering_rate_radps_per_sqrt_hz", q.steering_rate_radps_per_sqrt_hz},
      {"process_noise.gyro_bias_radps_per_sqrt_hz", q.gyro_bias_radps_per_sqrt_hz},
      {"process_noise.accel_bias_mps2_per_sqrt_hz", q.accel_bias_mps2_per_sqrt_hz},
      {"slip_aware_odometry.rolling_radius_sigma_m", s.rolling_radius_sigma_m},
      {"slip_aware_odometry.slip_compliance_initial", s.slip_compliance_initial},
      {"slip_aware_odometry.slip_compliance_sigma", s.slip_compliance_sigma},
      {"slip_aware_odometry.max_model_slip", s.max_model_slip, Domain::kProbability},
      {"slip_aware_odometry.rolling_radius_noise_m_per_sqrt_m", s.rolling_radius_noise_m_per_sqrt_m, Domain::kNonNegative},
      {"slip_aware_odometry.slip_compliance_noise_per_sqrt_m", s.slip_compliance_noise_per_sqrt_m, Domain::kNonNegative},
      {"slip_aware_odometry.slip_compliance_wheel_correlation", s.slip_compliance_wheel_correlation, Domain::kFraction},
      {"slip_aware_odometry.rolling_radius_noise_wheel_correlation", s.rolling_radius_noise_wheel_correlation,
       Domain::kFraction},
      {"slip_aware_odometry.rolling_radius_prior_wheel_correlation", s.rolling_radius_prior_wheel_correlation,
       Domain::kFraction},
      {"slip_aware_odometry.torque_sigma_nm", s.torque_sigma_nm, Domain::kNonNegative},
      {"slip_aware_odometry.carried_rolling_radius_change_sigma_m", s.carried_rolling_radius_change_sigma_m,
       Domain::kNonNegative},
      {"slip_aware_odometry.carried_slip_compliance_change_sigma", s.carried_slip_compliance_change_sigma,
       Domain::kNonNegative},
      {"slip_aware_odometry.traction_noise_per_sqrt_s", s.traction_noise_per_sqrt_s},
      {"initialisation.heading_baseline_m", i.heading_baseline_m},
      {"initialisation.heading_sigma_rad", i.heading_sigma_rad},
      {"initialisation.velocity_sigma_mps", i.velocity_sigma_mps},
      {"initialisation.yaw_rate_sigma_radps", i.yaw_rate_sigma_radps},
      {"initialisation.acceleration_sigma_mps2", i.acceleration_sigma_mps2},
      {"initialisation.gyro_bias_sigma_radps", i.gyro_bias_sigma_radps},
      {"initialisation.steering_sigma_rad", i.steering_sigma_rad},
      {"initialisation.accel_bias_sigma_mps2", i.accel_bias_sigma_mps2},
      {"gps.sigma_scale", c.gps.sigma_scale},
      {"gps.sigma_floor_rtk_fixed_m", c.gps.sigma_floor_rtk_fixed_m},
      {"gps.sigma_floor_rtk_float_m", c.gps.sigma_floor_rtk_float_m},
      {"gps.sigma_floor_sbas_m", c.gps.sigma_floor_sbas_m},
      {"gps.gate_probability", c.gps.gate_probability, Domain::kProbability},
      {"gps.reacquire_after_s", c.gps.reacquire_after_s},
      {"gps.bias_sigma_m", c.gps.bias_sigma_m},
      {"gps.bias_time_constant_s", c.gps.bias_time_constant_s},
      {"imu.accel_sigma_mps2", c.imu.accel_sigma_mps2},
      {"imu.gyro_sigma_radps", c.imu.gyro_sigma_radps},
      {"imu.gate_probability", c.imu.gate_probability, Domain::kProbability},
      {"wheels.speed_sigma_radps", c.wheels.speed_sigma_radps},
      {"wheels.speed_sigma_fraction", c.wheels.speed_sigma_fraction, Domain::kNonNegative},
      {"wheels.lateral_velocity_sigma_mps", c.wheels.lateral_velocity_sigma_mps},
      {"wheels.gate_probability", c.wheels.gate_probability, Domain::kProbability},
      {"wheels.max_speed_radps", c.wheels.max_speed_radps},
      {"wheels.encoder_low_pass_time_constant_s", c.wheels.encoder_low_pass_time_constant_s, Domain::kNonNegative},
      {"wheels.angle_sigma_rad", c.wheels.angle_sigma_rad},
      {"wheels.angle_rate_noise_radps_per_sqrt_hz", c.wheels.angle_rate_noise_radps_per_sqrt_hz},
      {"wheels.angle_max_prediction_sigma_rad", c.wheels.angle_max_prediction_sigma_rad},
      {"steering.angle_sigma_rad", c.steering.angle_sigma_rad},
      {"steering.gate_probability", c.steering.gate_probability, Domain::kProbability},
      {"vio.sigma_scale", c.vio.sigma_scale},
      {"vio.gate_probability", c.vio.gate_probability, Domain::kProbability},
      {"map_aided.range_sigma_m", c.map_aided.range_sigma_m},
      {"map_aided.cone_half_angle_rad", c.map_aided.cone_half_angle_rad},
      {"map_aided.max_range_m", c.map_aided.max_range_m},
      {"map_aided.k_sigma", c.map_aided.k_sigma},
      {"map_aided.row_smoothing_m", c.map_aided.row_smoothing_m},
      {"map_aided.gate_probability", c.map_aided.gate_probability, Domain::kProbability},
      {"max_prediction_step_s", c.max_prediction_step_s},
      {"max_prediction_gap_s", c.max_prediction_gap_s},
  };
}

FilterConfig ReadConfig(Reader& root) {
  FilterConfig c;
  c.name = root.String("name");
  {
    Reader q = root.Object("process_noise");
    c.process_noise = {q.Number("jerk_mps3_per_sqrt_hz"), q.Number("yaw_acceleration_radps2_per_sqrt_hz"),
                       q.Number("velocity_mps_per_sqrt_hz"), q.Number("steering_rate_radps_per_sqrt_hz"),
                       q.Number("gyro_bias_radps_per_sqrt_hz"), q.Number("accel_bias_mps2_per_sqrt_hz")};
    q.RejectUnknownKeys();
  }
  {
    Reader s = root.Object("slip_aware_odometry");
    for (const char* old : {"slip_gradient_initial_nm", "slip_gradient_sigma_nm", "min_slip_gradient_nm",
                            "slip_gradient_noise_nm_per_sqrt_m"}) {
      if (s.Has(old)) {
        s.Fail(s.Key(old), "was replaced on 2026-12-02 by the slip compliance kappa = N r / k_s (slip_compliance_initial, "
                           "slip_compliance_sigma, max_model_slip, slip_compliance_noise_per_sqrt_m; "
                           "docs/localization-filter.md §5.2)");
      }
    }
    c.slip_aware_odometry = {s.Bool("enabled"), s.Number("rolling_radius_sigma_m"),
                             s.Number("slip_compliance_initial"), s.Number("slip_compliance_sigma"),
                             s.Number("max_model_slip"), s.Number("rolling_radius_noise_m_per_sqrt_m"),
                             s.Number("slip_compliance_noise_per_sqrt_m"), s.Number("slip_compliance_wheel_correlation"),
                             s.Number("rolling_radius_noise_wheel_correlation"),
                             s.Number("rolling_radius_prior_wheel_correlation"),
                             s.Bool("traction_from_acceleration"), s.Number("torque_sigma_nm"),
                             s.Number("traction_noise_per_sqrt_s"), s.Bool("slip_with_rolling_radius"),
                             s.Number("carried_rolling_radius_change_sigma_m"),
                             s.Number("carried_slip_compliance_change_sigma")};
    s.RejectUnknownKeys();
  }
  {
    Reader i = root.Object("initialisation");
    c.initialisation = {i.Number("heading_baseline_m"),     i.Number("heading_sigma_rad"),
                        i.Number("velocity_sigma_mps"),     i.Number("yaw_rate_sigma_radps"),
                        i.Number("acceleration_sigma_mps2"), i.Number("gyro_bias_sigma_radps"),
                        i.Number("steering_sigma_rad"), i.Number("accel_bias_sigma_mps2")};
    i.RejectUnknownKeys();
  }
  {
    Reader g = root.Object("gps");
    c.gps = {g.Number("sigma_scale"), g.Number("sigma_floor_rtk_fixed_m"), g.Number("sigma_floor_rtk_float_m"),
             g.Number("sigma_floor_sbas_m"), g.Number("gate_probability"),
             g.Number("reacquire_after_s"), g.Bool("estimate_bias"), g.Number("bias_sigma_m"),
             g.Number("bias_time_constant_s")};
    g.RejectUnknownKeys();
  }
  {
    Reader m = root.Object("imu");
    c.imu = {m.Number("accel_sigma_mps2"), m.Number("gyro_sigma_radps"), m.Number("gate_probability"),
             m.Bool("estimate_accel_bias")};
    m.RejectUnknownKeys();
  }
  {
    Reader w = root.Object("wheels");
    c.wheels = {w.Number("speed_sigma_radps"), w.Number("speed_sigma_fraction"),
                w.Number("lateral_velocity_sigma_mps"), w.Number("gate_probability"),
                w.Number("max_speed_radps"), w.Number("encoder_low_pass_time_constant_s"),
                w.Bool("angle_measurement"), w.Number("angle_sigma_rad"),
                w.Number("angle_rate_noise_radps_per_sqrt_hz"), w.Number("angle_max_prediction_sigma_rad"),
                static_cast<int>(w.Integer("speed_update_iterations", 1, kMaxSpeedUpdateIterations))};
    w.RejectUnknownKeys();
  }
  {
    Reader s = root.Object("steering");
    c.steering = {s.Number("angle_sigma_rad"), s.Number("gate_probability")};
    s.RejectUnknownKeys();
  }
  {
    Reader v = root.Object("vio");
    c.vio = {v.Vector<2>("position_m"), v.Number("sigma_scale"), v.Number("gate_probability")};
    v.RejectUnknownKeys();
  }
  {
    Reader a = root.Object("map_aided");
    const std::string method = a.String("method");
    const auto parsed = MapAidedMethodFromName(method);
    if (!parsed) a.Fail(a.Key("method"), "must be \"range\", \"ellipsoid_cut\" or \"ellipsoid_cut_deprior\", got \"" + method + "\"");
    c.map_aided = {*parsed, a.Number("range_sigma_m"), a.Number("cone_half_angle_rad"), a.Number("max_range_m"),
                   a.Number("k_sigma"), a.Number("row_smoothing_m"), a.Number("gate_probability")};
    a.RejectUnknownKeys();
  }
  c.max_prediction_step_s = root.Number("max_prediction_step_s");
  c.max_prediction_gap_s = root.Number("max_prediction_gap_s");
  root.RejectUnknownKeys();
  return c;
}

}  // namespace

std::optional<std::string> FilterConfigProblem(const FilterConfig& config) {
  if (config.name.empty()) return std::string("name must not be empty");
  for (const Rule& rule : Rules(config)) {
    switch (rule.domain) {
      case Domain::kPositive:
        if (!IsPositive(rule.value)) return std::string(rule.key) + " must be finite and > 0";
        break;
      case Domain::kProbability:
        if (!IsProbability(rule.value)) return std::string(rule.key) + " must be in (0, 1)";
        break;
      case Domain::kNonNegative:
        if (!(std::isfinite(rule.value) && rule.value >= 0.0)) return std::string(rule.key) + " must be finite and >= 0";
        break;
      case Domain::kFraction:
        if (!(std::isfinite(rule.value) && rule.value >= 0.0 && rule.value < 1.0)) {
          return std::string(rule.key) + " must be in [0, 1)";
        }
        break;
    }
  }
  if (!(config.wheels.speed_update_iterations >= 1 && config.wheels.speed_update_iterations <= kMaxSpeedUpdateIterations)) {
    return "wheels.speed_update_iterations must be from 1 to " + std::to_string(kMaxSpeedUpdateIterations);
  }
  if (!config.vio.position_m.allFinite()) return std::string("vio.position_m must be finite");
  if (!(config.map_aided.cone_half_angle_rad < 0.5 * std::numbers::pi)) {
    return std::string("map_aided.cone_half_angle_rad must be < pi/2");
  }
  if (config.max_prediction_gap_s < config.max_prediction_step_s) {
    return std::string("max_prediction_gap_s must be >= max_prediction_step_s");
  }
  return std::nullopt;
}

std::string_view MapAidedMethodName(MapAidedMethod method) {
  switch (method) {
    case MapAidedMethod::kRange: return "range";
    case MapAidedMethod::kEllipsoidCut: return "ellipsoid_cut";
    case MapAidedMethod::kEllipsoidCutDeprior: return "ellipsoid_cut_deprior";
  }
  return "?";
}

std::optional<MapAidedMethod> MapAidedMethodFromName(std::string_view name) {
  for (const MapAidedMethod m :
       {MapAidedMethod::kRange, MapAidedMethod::kEllipsoidCut, MapAidedMethod::kEllipsoidCutDeprior}) {
    if (MapAidedMethodName(m) == name) return m;
  }
  return std::nullopt;
}

double GpsSigma(const GpsNoise& noise, formats::GnssFixQuality fix, double receiver_sigma_horizontal_m) {
  double floor = 0.0;
  switch (fix) {
    case formats::GnssFixQuality::kRtkFixed: floor = noise.sigma_floor_rtk_fixed_m; break;
    case formats::GnssFixQuality::kRtkFloat: floor = noise.sigma_floor_rtk_float_m; break;
    case formats::GnssFixQuality::kSbas: floor = noise.sigma_floor_sbas_m; break;
    case formats::GnssFixQuality::kNone: throw std::invalid_argument("GpsSigma: a fix quality of none has no position");
  }
  return std::max(floor, noise.sigma_scale * receiver_sigma_horizontal_m);
}

FilterConfig ParseFilterConfig(std::string_view json_text, std::string_view source_name) {
  const std::string source(source_name);
  const nlohmann::json document = mapio::detail::ParseJsonText<FilterConfigError>(json_text, source);
  Reader root(document, source, "");
  FilterConfig config = ReadConfig(root);
  if (const auto problem = FilterConfigProblem(config)) throw FilterConfigError(source + ": " + *problem);
  return config;
}

FilterConfig LoadFilterConfig(const std::filesystem::path& path) {
  return ParseFilterConfig(mapio::detail::ReadTextFile<FilterConfigError>(path, "filter file"), path.string());
}

}  // namespace rowloc::localization
