// Filter configuration files (filter_config.hpp). A file is an overlay on the in-code defaults
// (mapio/config_overlay.hpp): the defaults are serialized (ConfigDocument), the file's layers are
// merged onto them, and the complete document is read. The reader checks types and key sets; every
// value rule lives in FilterConfigProblem so that in-code and file configurations obey the same.
#include "rowloc/localization/filter_config.hpp"

#include "rowloc/mapio/config_overlay.hpp"
#include "rowloc/mapio/detail/json_object_reader.hpp"

#include <algorithm>
#include <cmath>
#include <iomanip>
#include <numbers>
#include <sstream>
#include <stdexcept>
#include <vector>

namespace rowloc::localization {
namespace {

using Reader = mapio::detail::JsonObjectReader<FilterConfigError>;

constexpr int kMaxSpeedUpdateIterations = 10;  ///< wheels.speed_update_iterations (1 to this)
constexpr int kMaxRangeSigmaWindowEchoes = 100000;  ///< map_aided.adaptive_range_sigma.window_echoes (1 to this)

/// What a value must be: in [min, max] (both finite: a physical range, not only a sign), a gate's
/// probability in [0.5, 1) (below 0.5 a gate rejects most consistent measurements), or a correlation
/// in [0, 1).
enum class Domain { kRange, kGateProbability, kCorrelation };

struct Rule {
  const char* key;
  double value;
  double min = 0.0;
  double max = 0.0;
  Domain domain = Domain::kRange;
};

constexpr double kMinGateProbability = 0.5;
Rule Probability(const char* key, double value) { return {key, value, kMinGateProbability, 1.0, Domain::kGateProbability}; }
Rule Correlation(const char* key, double value) { return {key, value, 0.0, 1.0, Domain::kCorrelation}; }

/// Every numeric value with its domain. The ranges are wide around what a field robot needs (the
/// shipped filter files use values decades inside them) but exclude the values that hang or overflow
/// the filter: a prediction step of 1e-300 s (no progress), a sigma of 1e300 (its square overflows),
/// a gap of 1e300 s (10^16 prediction steps).
std::vector<Rule> Rules(const FilterConfig& c) {
  const ProcessNoise& q = c.process_noise;
  const SlipAwareOdometryConfig& s = c.slip_aware_odometry;
  const InitialisationConfig& i = c.initialisation;
  const GpsNoise& g = c.gps;
  const WheelNoise& w = c.wheels;
  const MapAidedConfig& a = c.map_aided;
  return {
      {"process_noise.jerk_mps3_per_sqrt_hz", q.jerk_mps3_per_sqrt_hz, 1e-6, 1e3},
      {"process_noise.yaw_acceleration_radps2_per_sqrt_hz", q.yaw_acceleration_radps2_per_sqrt_hz, 1e-6, 1e3},
      {"process_noise.velocity_mps_per_sqrt_hz", q.velocity_mps_per_sqrt_hz, 1e-9, 100.0},
      {"process_noise.steering_rate_radps_per_sqrt_hz", q.steering_rate_radps_per_sqrt_hz, 1e-6, 100.0},
      {"process_noise.gyro_bias_radps_per_sqrt_hz", q.gyro_bias_radps_per_sqrt_hz, 1e-12, 1.0},
      {"process_noise.accel_bias_mps2_per_sqrt_hz", q.accel_bias_mps2_per_sqrt_hz, 1e-12, 10.0},
      {"slip_aware_odometry.rolling_radius_sigma_m", s.rolling_radius_sigma_m, 1e-6, 1.0},
      {"slip_aware_odometry.slip_compliance_initial", s.slip_compliance_initial, 1e-6, 1e3},
      {"slip_aware_odometry.slip_compliance_sigma", s.slip_compliance_sigma, 1e-6, 1e3},
      {"slip_aware_odometry.max_model_slip", s.max_model_slip, 0.01, 0.99},
      {"slip_aware_odometry.rolling_radius_noise_m_per_sqrt_m", s.rolling_radius_noise_m_per_sqrt_m, 0.0, 1.0},
      {"slip_aware_odometry.slip_compliance_noise_per_sqrt_m", s.slip_compliance_noise_per_sqrt_m, 0.0, 10.0},
      Correlation("slip_aware_odometry.slip_compliance_wheel_correlation", s.slip_compliance_wheel_correlation),
      Correlation("slip_aware_odometry.rolling_radius_noise_wheel_correlation", s.rolling_radius_noise_wheel_correlation),
      Correlation("slip_aware_odometry.rolling_radius_prior_wheel_correlation", s.rolling_radius_prior_wheel_correlation),
      {"slip_aware_odometry.torque_sigma_nm", s.torque_sigma_nm, 0.0, 1e4},
      {"slip_aware_odometry.carried_rolling_radius_change_sigma_m", s.carried_rolling_radius_change_sigma_m, 0.0, 1.0},
      {"slip_aware_odometry.carried_slip_compliance_change_sigma", s.carried_slip_compliance_change_sigma, 0.0, 1e3},
      {"slip_aware_odometry.traction_noise_per_sqrt_s", s.traction_noise_per_sqrt_s, 1e-9, 10.0},
      {"slip_aware_odometry.terrain_change.cusum_drift_sigma", s.terrain_change.cusum_drift_sigma, 0.0, 100.0},
      {"slip_aware_odometry.terrain_change.cusum_threshold_sigma", s.terrain_change.cusum_threshold_sigma, 1e-3, 1e6},
      {"slip_aware_odometry.terrain_change.radius_sigma_fraction", s.terrain_change.radius_sigma_fraction, 1e-6, 1.0},
      {"slip_aware_odometry.terrain_change.max_yaw_rate_radps", s.terrain_change.max_yaw_rate_radps, 0.0, 100.0},
      {"initialisation.heading_baseline_m", i.heading_baseline_m, 0.1, 100.0},
      {"initialisation.heading_sigma_rad", i.heading_sigma_rad, 1e-6, 10.0},
      {"initialisation.velocity_sigma_mps", i.velocity_sigma_mps, 1e-6, 100.0},
      {"initialisation.yaw_rate_sigma_radps", i.yaw_rate_sigma_radps, 1e-6, 100.0},
      {"initialisation.acceleration_sigma_mps2", i.acceleration_sigma_mps2, 1e-6, 1e3},
      {"initialisation.gyro_bias_sigma_radps", i.gyro_bias_sigma_radps, 1e-9, 10.0},
      {"initialisation.steering_sigma_rad", i.steering_sigma_rad, 1e-9, 10.0},
      {"initialisation.accel_bias_sigma_mps2", i.accel_bias_sigma_mps2, 1e-9, 100.0},
      {"initialisation.map_heading_sigma_rad", i.map_heading_sigma_rad, 0.0, 1.0},
      {"gps.sigma_scale", g.sigma_scale, 1e-3, 1e3},
      {"gps.sigma_floor_rtk_fixed_m", g.sigma_floor_rtk_fixed_m, 1e-6, 1e3},
      {"gps.sigma_floor_rtk_float_m", g.sigma_floor_rtk_float_m, 1e-6, 1e3},
      {"gps.sigma_floor_sbas_m", g.sigma_floor_sbas_m, 1e-6, 1e3},
      Probability("gps.gate_probability", g.gate_probability),
      {"gps.reacquire_after_s", g.reacquire_after_s, 0.01, 3600.0},
      {"gps.bias_sigma_m", g.bias_sigma_m, 1e-6, 1e3},
      {"gps.bias_time_constant_s", g.bias_time_constant_s, 1e-3, 1e6},
      {"imu.accel_sigma_mps2", c.imu.accel_sigma_mps2, 1e-9, 1e3},
      {"imu.gyro_sigma_radps", c.imu.gyro_sigma_radps, 1e-9, 100.0},
      Probability("imu.gate_probability", c.imu.gate_probability),
      {"wheels.speed_sigma_radps", w.speed_sigma_radps, 1e-9, 1e3},
      {"wheels.speed_sigma_fraction", w.speed_sigma_fraction, 0.0, 10.0},
      // Up to 1e6 m/s: a sigma that large switches the non-holonomic constraint off (tests do).
      {"wheels.lateral_velocity_sigma_mps", w.lateral_velocity_sigma_mps, 1e-9, 1e6},
      Probability("wheels.gate_probability", w.gate_probability),
      {"wheels.max_speed_radps", w.max_speed_radps, 1e-3, 1e4},
      {"wheels.encoder_low_pass_time_constant_s", w.encoder_low_pass_time_constant_s, 0.0, 10.0},
      {"wheels.angle_sigma_rad", w.angle_sigma_rad, 1e-9, 10.0},
      {"wheels.angle_rate_noise_radps_per_sqrt_hz", w.angle_rate_noise_radps_per_sqrt_hz, 1e-12, 100.0},
      {"wheels.angle_max_prediction_sigma_rad", w.angle_max_prediction_sigma_rad, 1e-9, 100.0},
      {"steering.angle_sigma_rad", c.steering.angle_sigma_rad, 1e-9, 10.0},
      Probability("steering.gate_probability", c.steering.gate_probability),
      {"vio.sigma_scale", c.vio.sigma_scale, 1e-3, 1e3},
      Probability("vio.gate_probability", c.vio.gate_probability),
      {"map_aided.range_sigma_m", a.range_sigma_m, 1e-6, 100.0},
      {"map_aided.cone_half_angle_rad", a.cone_half_angle_rad, 1e-6, 0.5 * std::numbers::pi},
      {"map_aided.max_range_m", a.max_range_m, 0.01, 1e3},
      {"map_aided.k_sigma", a.k_sigma, 0.5, 100.0},
      {"map_aided.row_smoothing_m", a.row_smoothing_m, 1e-3, 1e3},
      Probability("map_aided.gate_probability", a.gate_probability),
      {"map_aided.adaptive_range_sigma.max_sigma_m", a.adaptive_range_sigma.max_sigma_m, 1e-6, 100.0},
      {"max_prediction_step_s", c.max_prediction_step_s, 1e-4, 1.0},
      {"max_prediction_gap_s", c.max_prediction_gap_s, 1e-4, 3600.0},
      {"max_time_jump_s", c.max_time_jump_s, 1e-4, 1e6},
  };
}

/// "key must be in [min, max], got value" with short numbers (6 significant digits, like %g).
std::optional<std::string> RuleProblem(const Rule& rule) {
  const double v = rule.value;
  bool ok = false;
  std::ostringstream text;
  text << std::setprecision(6) << rule.key << " must be in ";
  switch (rule.domain) {
    case Domain::kRange:
      ok = v >= rule.min && v <= rule.max;  // false for NaN
      text << "[" << rule.min << ", " << rule.max << "]";
      break;
    case Domain::kGateProbability:
      ok = v >= kMinGateProbability && v < 1.0;
      text << "(0, 1) and at least " << kMinGateProbability;
      break;
    case Domain::kCorrelation:
      ok = v >= 0.0 && v < 1.0;
      text << "[0, 1)";
      break;
  }
  if (ok) return std::nullopt;
  text << ", got " << v;
  return text.str();
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
                           "docs/localization-filter.md §1 and §3)");
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
                             s.Number("carried_slip_compliance_change_sigma"), {}};
    Reader t = s.Object("terrain_change");
    c.slip_aware_odometry.terrain_change = {t.Bool("enabled"), t.Number("cusum_drift_sigma"),
                                            t.Number("cusum_threshold_sigma"), t.Number("radius_sigma_fraction"),
                                            t.Number("max_yaw_rate_radps")};
    t.RejectUnknownKeys();
    s.RejectUnknownKeys();
  }
  {
    Reader i = root.Object("initialisation");
    c.initialisation = {i.Number("heading_baseline_m"),     i.Number("heading_sigma_rad"),
                        i.Number("velocity_sigma_mps"),     i.Number("yaw_rate_sigma_radps"),
                        i.Number("acceleration_sigma_mps2"), i.Number("gyro_bias_sigma_radps"),
                        i.Number("steering_sigma_rad"), i.Number("accel_bias_sigma_mps2"),
                        i.Number("map_heading_sigma_rad")};
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
                   a.Number("k_sigma"), a.Number("row_smoothing_m"), a.Number("gate_probability"), {}};
    Reader r = a.Object("adaptive_range_sigma");
    c.map_aided.adaptive_range_sigma = {r.Bool("enabled"), r.Number("max_sigma_m"),
                                        static_cast<int>(r.Integer("window_echoes", 1, kMaxRangeSigmaWindowEchoes)),
                                        static_cast<int>(r.Integer("min_echoes", 1, kMaxRangeSigmaWindowEchoes))};
    r.RejectUnknownKeys();
    a.RejectUnknownKeys();
  }
  c.max_prediction_step_s = root.Number("max_prediction_step_s");
  c.max_prediction_gap_s = root.Number("max_prediction_gap_s");
  c.max_time_jump_s = root.Number("max_time_jump_s");
  root.RejectUnknownKeys();
  return c;
}

/// The inverse of ReadConfig, in the file's key order.
nlohmann::ordered_json ConfigDocument(const FilterConfig& c) {
  const ProcessNoise& q = c.process_noise;
  const SlipAwareOdometryConfig& s = c.slip_aware_odometry;
  const InitialisationConfig& i = c.initialisation;
  const GpsNoise& g = c.gps;
  const WheelNoise& w = c.wheels;
  const MapAidedConfig& a = c.map_aided;
  using Object = nlohmann::ordered_json;
  return Object{
      {"name", c.name},
      {"process_noise",
       Object{{"jerk_mps3_per_sqrt_hz", q.jerk_mps3_per_sqrt_hz},
              {"yaw_acceleration_radps2_per_sqrt_hz", q.yaw_acceleration_radps2_per_sqrt_hz},
              {"velocity_mps_per_sqrt_hz", q.velocity_mps_per_sqrt_hz},
              {"steering_rate_radps_per_sqrt_hz", q.steering_rate_radps_per_sqrt_hz},
              {"gyro_bias_radps_per_sqrt_hz", q.gyro_bias_radps_per_sqrt_hz},
              {"accel_bias_mps2_per_sqrt_hz", q.accel_bias_mps2_per_sqrt_hz}}},
      {"slip_aware_odometry",
       Object{{"enabled", s.enabled},
              {"rolling_radius_sigma_m", s.rolling_radius_sigma_m},
              {"slip_compliance_initial", s.slip_compliance_initial},
              {"slip_compliance_sigma", s.slip_compliance_sigma},
              {"max_model_slip", s.max_model_slip},
              {"rolling_radius_noise_m_per_sqrt_m", s.rolling_radius_noise_m_per_sqrt_m},
              {"slip_compliance_noise_per_sqrt_m", s.slip_compliance_noise_per_sqrt_m},
              {"slip_compliance_wheel_correlation", s.slip_compliance_wheel_correlation},
              {"rolling_radius_noise_wheel_correlation", s.rolling_radius_noise_wheel_correlation},
              {"rolling_radius_prior_wheel_correlation", s.rolling_radius_prior_wheel_correlation},
              {"traction_from_acceleration", s.traction_from_acceleration},
              {"torque_sigma_nm", s.torque_sigma_nm},
              {"traction_noise_per_sqrt_s", s.traction_noise_per_sqrt_s},
              {"slip_with_rolling_radius", s.slip_with_rolling_radius},
              {"carried_rolling_radius_change_sigma_m", s.carried_rolling_radius_change_sigma_m},
              {"carried_slip_compliance_change_sigma", s.carried_slip_compliance_change_sigma},
              {"terrain_change",
               Object{{"enabled", s.terrain_change.enabled},
                      {"cusum_drift_sigma", s.terrain_change.cusum_drift_sigma},
                      {"cusum_threshold_sigma", s.terrain_change.cusum_threshold_sigma},
                      {"radius_sigma_fraction", s.terrain_change.radius_sigma_fraction},
                      {"max_yaw_rate_radps", s.terrain_change.max_yaw_rate_radps}}}}},
      {"initialisation",
       Object{{"heading_baseline_m", i.heading_baseline_m},
              {"heading_sigma_rad", i.heading_sigma_rad},
              {"velocity_sigma_mps", i.velocity_sigma_mps},
              {"yaw_rate_sigma_radps", i.yaw_rate_sigma_radps},
              {"acceleration_sigma_mps2", i.acceleration_sigma_mps2},
              {"gyro_bias_sigma_radps", i.gyro_bias_sigma_radps},
              {"steering_sigma_rad", i.steering_sigma_rad},
              {"accel_bias_sigma_mps2", i.accel_bias_sigma_mps2},
              {"map_heading_sigma_rad", i.map_heading_sigma_rad}}},
      {"gps",
       Object{{"sigma_scale", g.sigma_scale},
              {"sigma_floor_rtk_fixed_m", g.sigma_floor_rtk_fixed_m},
              {"sigma_floor_rtk_float_m", g.sigma_floor_rtk_float_m},
              {"sigma_floor_sbas_m", g.sigma_floor_sbas_m},
              {"gate_probability", g.gate_probability},
              {"reacquire_after_s", g.reacquire_after_s},
              {"estimate_bias", g.estimate_bias},
              {"bias_sigma_m", g.bias_sigma_m},
              {"bias_time_constant_s", g.bias_time_constant_s}}},
      {"imu",
       Object{{"accel_sigma_mps2", c.imu.accel_sigma_mps2},
              {"gyro_sigma_radps", c.imu.gyro_sigma_radps},
              {"gate_probability", c.imu.gate_probability},
              {"estimate_accel_bias", c.imu.estimate_accel_bias}}},
      {"wheels",
       Object{{"speed_sigma_radps", w.speed_sigma_radps},
              {"speed_sigma_fraction", w.speed_sigma_fraction},
              {"lateral_velocity_sigma_mps", w.lateral_velocity_sigma_mps},
              {"gate_probability", w.gate_probability},
              {"max_speed_radps", w.max_speed_radps},
              {"encoder_low_pass_time_constant_s", w.encoder_low_pass_time_constant_s},
              {"angle_measurement", w.angle_measurement},
              {"angle_sigma_rad", w.angle_sigma_rad},
              {"angle_rate_noise_radps_per_sqrt_hz", w.angle_rate_noise_radps_per_sqrt_hz},
              {"angle_max_prediction_sigma_rad", w.angle_max_prediction_sigma_rad},
              {"speed_update_iterations", w.speed_update_iterations}}},
      {"steering", Object{{"angle_sigma_rad", c.steering.angle_sigma_rad},
                          {"gate_probability", c.steering.gate_probability}}},
      {"vio", Object{{"position_m", {c.vio.position_m.x(), c.vio.position_m.y()}},
                     {"sigma_scale", c.vio.sigma_scale},
                     {"gate_probability", c.vio.gate_probability}}},
      {"map_aided",
       Object{{"method", std::string(MapAidedMethodName(a.method))},
              {"range_sigma_m", a.range_sigma_m},
              {"cone_half_angle_rad", a.cone_half_angle_rad},
              {"max_range_m", a.max_range_m},
              {"k_sigma", a.k_sigma},
              {"row_smoothing_m", a.row_smoothing_m},
              {"gate_probability", a.gate_probability},
              {"adaptive_range_sigma",
               Object{{"enabled", a.adaptive_range_sigma.enabled},
                      {"max_sigma_m", a.adaptive_range_sigma.max_sigma_m},
                      {"window_echoes", a.adaptive_range_sigma.window_echoes},
                      {"min_echoes", a.adaptive_range_sigma.min_echoes}}}}},
      {"max_prediction_step_s", c.max_prediction_step_s},
      {"max_prediction_gap_s", c.max_prediction_gap_s},
      {"max_time_jump_s", c.max_time_jump_s},
  };
}

nlohmann::json DefaultsDocument() {
  return nlohmann::json::parse(ConfigDocument(FilterConfig{}).dump());
}

/// Runs a reader of configuration layers; its errors become FilterConfigErrors (same message).
template <typename Read>
std::vector<mapio::ConfigLayer> Layers(Read&& read) {
  try {
    return read();
  } catch (const mapio::ConfigOverlayError& e) {
    throw FilterConfigError(e.what());
  }
}

/// A filter from its layers (base first): each layer merged alone onto the defaults is read first,
/// so that an unknown key, a wrong type or a missing name is reported with the file that has it;
/// then all of them merged in order onto the defaults, whose values are checked (FilterConfigProblem)
/// and reported with `source`, the file that was asked for.
FilterConfig ReadLayers(const std::vector<mapio::ConfigLayer>& layers, const std::string& source) {
  const nlohmann::json defaults = DefaultsDocument();
  for (const mapio::ConfigLayer& layer : layers) {
    if (!layer.document.contains("name")) {
      throw FilterConfigError(layer.file.string() + ": name: missing key (every filter file names itself; "
                                                    "the keys it leaves out keep their default values)");
    }
    if (layers.size() == 1) break;  // read below, with the same name
    nlohmann::json alone = defaults;
    mapio::MergeOverlay(alone, layer.document);
    Reader reader(alone, layer.file.string(), "");
    (void)ReadConfig(reader);
  }
  const nlohmann::json merged = mapio::MergeLayers(defaults, layers);
  Reader root(merged, source, "");
  FilterConfig config = ReadConfig(root);
  if (const auto problem = FilterConfigProblem(config)) throw FilterConfigError(source + ": " + *problem);
  return config;
}

/// The adaptive range sigma's settings that no single-key rule covers.
std::optional<std::string> AdaptiveRangeSigmaProblem(const MapAidedConfig& a) {
  const AdaptiveRangeSigmaConfig& r = a.adaptive_range_sigma;
  if (!(r.window_echoes >= 1 && r.window_echoes <= kMaxRangeSigmaWindowEchoes)) {
    return "map_aided.adaptive_range_sigma.window_echoes must be from 1 to " + std::to_string(kMaxRangeSigmaWindowEchoes);
  }
  if (!(r.min_echoes >= 1 && r.min_echoes <= r.window_echoes)) {
    return std::string("map_aided.adaptive_range_sigma.min_echoes must be from 1 to window_echoes");
  }
  if (!(r.max_sigma_m >= a.range_sigma_m)) {
    return std::string("map_aided.adaptive_range_sigma.max_sigma_m must be >= map_aided.range_sigma_m");
  }
  return std::nullopt;
}

}  // namespace

std::string FilterConfigJson(const FilterConfig& config) { return ConfigDocument(config).dump(2) + "\n"; }

std::optional<std::string> FilterConfigProblem(const FilterConfig& config) {
  if (config.name.empty()) return std::string("name must not be empty");
  for (const Rule& rule : Rules(config)) {
    if (auto problem = RuleProblem(rule)) return problem;
  }
  if (!(config.wheels.speed_update_iterations >= 1 && config.wheels.speed_update_iterations <= kMaxSpeedUpdateIterations)) {
    return "wheels.speed_update_iterations must be from 1 to " + std::to_string(kMaxSpeedUpdateIterations);
  }
  if (!config.vio.position_m.allFinite()) return std::string("vio.position_m must be finite");
  if (const auto problem = AdaptiveRangeSigmaProblem(config.map_aided)) return problem;
  if (!(config.map_aided.cone_half_angle_rad < 0.5 * std::numbers::pi)) {
    return std::string("map_aided.cone_half_angle_rad must be < pi/2");
  }
  if (config.max_time_jump_s < config.max_prediction_gap_s) {
    return std::string("max_time_jump_s must be >= max_prediction_gap_s");
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
  return ReadLayers(Layers([&] { return std::vector{mapio::ParseStandaloneLayer(json_text, source)}; }), source);
}

FilterConfig ParseFilterConfigFile(std::string_view json_text, const std::filesystem::path& path) {
  return ReadLayers(Layers([&] { return mapio::ParseConfigLayers(json_text, path.string(), path.parent_path(),
                                                                 "filter file"); }),
                    path.string());
}

FilterConfig LoadFilterConfig(const std::filesystem::path& path) {
  return ReadLayers(Layers([&] { return mapio::ReadConfigLayers(path, "filter file"); }), path.string());
}

std::vector<std::filesystem::path> FilterConfigFiles(const std::filesystem::path& path) {
  std::vector<std::filesystem::path> files;
  for (const mapio::ConfigLayer& layer : Layers([&] { return mapio::ReadConfigLayers(path, "filter file"); })) {
    files.push_back(layer.file);
  }
  return files;
}

}  // namespace rowloc::localization
