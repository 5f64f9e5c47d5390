// Filter configuration files (filter_config.hpp): the shipped files, and clear errors that name
// the source and the key path.
#include "rowloc/localization/filter_config.hpp"

#include "test_support.hpp"

#include <gmock/gmock.h>
#include <gtest/gtest-spi.h>
#include <gtest/gtest.h>

#include <nlohmann/json.hpp>

#include <algorithm>
#include <cmath>
#include <fstream>
#include <functional>
#include <limits>
#include <numbers>
#include <set>
#include <sstream>
#include <string>
#include <utility>
#include <vector>

namespace rowloc::localization {
namespace {

using ::testing::AllOf;
using ::testing::HasSubstr;
using nlohmann::json;

std::filesystem::path FilterFile(const std::string& name) {
  return test::SourceDir() / "config" / "filters" / (name + ".json");
}

void ExpectEqualConfigs(const FilterConfig& a, const FilterConfig& b) {
  EXPECT_EQ(a.name, b.name);
  const ProcessNoise &qa = a.process_noise, &qb = b.process_noise;
  EXPECT_EQ(qa.jerk_mps3_per_sqrt_hz, qb.jerk_mps3_per_sqrt_hz);
  EXPECT_EQ(qa.yaw_acceleration_radps2_per_sqrt_hz, qb.yaw_acceleration_radps2_per_sqrt_hz);
  EXPECT_EQ(qa.velocity_mps_per_sqrt_hz, qb.velocity_mps_per_sqrt_hz);
  EXPECT_EQ(qa.steering_rate_radps_per_sqrt_hz, qb.steering_rate_radps_per_sqrt_hz);
  EXPECT_EQ(qa.gyro_bias_radps_per_sqrt_hz, qb.gyro_bias_radps_per_sqrt_hz);
  EXPECT_EQ(qa.accel_bias_mps2_per_sqrt_hz, qb.accel_bias_mps2_per_sqrt_hz);
  const SlipAwareOdometryConfig &sa = a.slip_aware_odometry, &sb = b.slip_aware_odometry;
  EXPECT_EQ(sa.enabled, sb.enabled);
  EXPECT_EQ(sa.rolling_radius_sigma_m, sb.rolling_radius_sigma_m);
  EXPECT_EQ(sa.slip_compliance_initial, sb.slip_compliance_initial);
  EXPECT_EQ(sa.slip_compliance_sigma, sb.slip_compliance_sigma);
  EXPECT_EQ(sa.max_model_slip, sb.max_model_slip);
  EXPECT_EQ(sa.rolling_radius_noise_m_per_sqrt_m, sb.rolling_radius_noise_m_per_sqrt_m);
  EXPECT_EQ(sa.slip_compliance_noise_per_sqrt_m, sb.slip_compliance_noise_per_sqrt_m);
  EXPECT_EQ(sa.slip_compliance_wheel_correlation, sb.slip_compliance_wheel_correlation);
  EXPECT_EQ(sa.rolling_radius_noise_wheel_correlation, sb.rolling_radius_noise_wheel_correlation);
  EXPECT_EQ(sa.rolling_radius_prior_wheel_correlation, sb.rolling_radius_prior_wheel_correlation);
  EXPECT_EQ(sa.carried_rolling_radius_change_sigma_m, sb.carried_rolling_radius_change_sigma_m);
  EXPECT_EQ(sa.carried_slip_compliance_change_sigma, sb.carried_slip_compliance_change_sigma);
  const TerrainChangeConfig &ta = sa.terrain_change, &tb = sb.terrain_change;
  EXPECT_EQ(ta.enabled, tb.enabled);
  EXPECT_EQ(ta.cusum_drift_sigma, tb.cusum_drift_sigma);
  EXPECT_EQ(ta.cusum_threshold_sigma, tb.cusum_threshold_sigma);
  EXPECT_EQ(ta.radius_sigma_fraction, tb.radius_sigma_fraction);
  EXPECT_EQ(ta.max_yaw_rate_radps, tb.max_yaw_rate_radps);
  EXPECT_EQ(sa.torque_sigma_nm, sb.torque_sigma_nm);
  EXPECT_EQ(sa.traction_noise_per_sqrt_s, sb.traction_noise_per_sqrt_s);
  EXPECT_EQ(sa.traction_from_acceleration, sb.traction_from_acceleration);
  EXPECT_EQ(sa.slip_with_rolling_radius, sb.slip_with_rolling_radius);
  const InitialisationConfig &ia = a.initialisation, &ib = b.initialisation;
  EXPECT_EQ(ia.heading_baseline_m, ib.heading_baseline_m);
  EXPECT_EQ(ia.heading_sigma_rad, ib.heading_sigma_rad);
  EXPECT_EQ(ia.velocity_sigma_mps, ib.velocity_sigma_mps);
  EXPECT_EQ(ia.yaw_rate_sigma_radps, ib.yaw_rate_sigma_radps);
  EXPECT_EQ(ia.acceleration_sigma_mps2, ib.acceleration_sigma_mps2);
  EXPECT_EQ(ia.gyro_bias_sigma_radps, ib.gyro_bias_sigma_radps);
  EXPECT_EQ(ia.steering_sigma_rad, ib.steering_sigma_rad);
  EXPECT_EQ(ia.accel_bias_sigma_mps2, ib.accel_bias_sigma_mps2);
  EXPECT_EQ(ia.map_heading_sigma_rad, ib.map_heading_sigma_rad);
  EXPECT_EQ(a.gps.sigma_scale, b.gps.sigma_scale);
  EXPECT_EQ(a.gps.sigma_floor_rtk_fixed_m, b.gps.sigma_floor_rtk_fixed_m);
  EXPECT_EQ(a.gps.sigma_floor_rtk_float_m, b.gps.sigma_floor_rtk_float_m);
  EXPECT_EQ(a.gps.sigma_floor_sbas_m, b.gps.sigma_floor_sbas_m);
  EXPECT_EQ(a.gps.gate_probability, b.gps.gate_probability);
  EXPECT_EQ(a.gps.reacquire_after_s, b.gps.reacquire_after_s);
  EXPECT_EQ(a.gps.estimate_bias, b.gps.estimate_bias);
  EXPECT_EQ(a.gps.bias_sigma_m, b.gps.bias_sigma_m);
  EXPECT_EQ(a.gps.bias_time_constant_s, b.gps.bias_time_constant_s);
  EXPECT_EQ(a.imu.accel_sigma_mps2, b.imu.accel_sigma_mps2);
  EXPECT_EQ(a.imu.gyro_sigma_radps, b.imu.gyro_sigma_radps);
  EXPECT_EQ(a.imu.gate_probability, b.imu.gate_probability);
  EXPECT_EQ(a.imu.estimate_accel_bias, b.imu.estimate_accel_bias);
  EXPECT_EQ(a.wheels.speed_sigma_radps, b.wheels.speed_sigma_radps);
  EXPECT_EQ(a.wheels.speed_sigma_fraction, b.wheels.speed_sigma_fraction);
  EXPECT_EQ(a.wheels.lateral_velocity_sigma_mps, b.wheels.lateral_velocity_sigma_mps);
  EXPECT_EQ(a.wheels.gate_probability, b.wheels.gate_probability);
  EXPECT_EQ(a.wheels.max_speed_radps, b.wheels.max_speed_radps);
  EXPECT_EQ(a.wheels.encoder_low_pass_time_constant_s, b.wheels.encoder_low_pass_time_constant_s);
  EXPECT_EQ(a.wheels.angle_measurement, b.wheels.angle_measurement);
  EXPECT_EQ(a.wheels.angle_sigma_rad, b.wheels.angle_sigma_rad);
  EXPECT_EQ(a.wheels.angle_rate_noise_radps_per_sqrt_hz, b.wheels.angle_rate_noise_radps_per_sqrt_hz);
  EXPECT_EQ(a.wheels.angle_max_prediction_sigma_rad, b.wheels.angle_max_prediction_sigma_rad);
  EXPECT_EQ(a.wheels.speed_update_iterations, b.wheels.speed_update_iterations);
  EXPECT_EQ(a.steering.angle_sigma_rad, b.steering.angle_sigma_rad);
  EXPECT_EQ(a.steering.gate_probability, b.steering.gate_probability);
  EXPECT_EQ(a.vio.position_m, b.vio.position_m);
  EXPECT_EQ(a.vio.sigma_scale, b.vio.sigma_scale);
  EXPECT_EQ(a.vio.gate_probability, b.vio.gate_probability);
  EXPECT_EQ(a.map_aided.method, b.map_aided.method);
  EXPECT_EQ(a.map_aided.range_sigma_m, b.map_aided.range_sigma_m);
  EXPECT_EQ(a.map_aided.cone_half_angle_rad, b.map_aided.cone_half_angle_rad);
  EXPECT_EQ(a.map_aided.max_range_m, b.map_aided.max_range_m);
  EXPECT_EQ(a.map_aided.k_sigma, b.map_aided.k_sigma);
  EXPECT_EQ(a.map_aided.row_smoothing_m, b.map_aided.row_smoothing_m);
  EXPECT_EQ(a.map_aided.gate_probability, b.map_aided.gate_probability);
  const AdaptiveRangeSigmaConfig &ra = a.map_aided.adaptive_range_sigma, &rb = b.map_aided.adaptive_range_sigma;
  EXPECT_EQ(ra.enabled, rb.enabled);
  EXPECT_EQ(ra.max_sigma_m, rb.max_sigma_m);
  EXPECT_EQ(ra.window_echoes, rb.window_echoes);
  EXPECT_EQ(ra.min_echoes, rb.min_echoes);
  EXPECT_EQ(a.max_prediction_step_s, b.max_prediction_step_s);
  EXPECT_EQ(a.max_prediction_gap_s, b.max_prediction_gap_s);
  EXPECT_EQ(a.max_time_jump_s, b.max_time_jump_s);
}

// Every key with its default value: a filter file that states them all (as every file did before
// they became overlays on the defaults, issue 29).
json DefaultJson() { return json::parse(FilterConfigJson(FilterConfig{})); }

// The error message of parsing `document` ("" if it parses).
std::string ErrorOf(const std::string& text) {
  try {
    ParseFilterConfig(text, "edited.json");
  } catch (const FilterConfigError& e) {
    return e.what();
  }
  return "";
}
std::string ErrorOf(const json& document) { return ErrorOf(document.dump()); }

// Dotted key paths ("gps.gate_probability") and JSON pointers of every leaf value of the file.
std::vector<std::pair<std::string, json::json_pointer>> Leaves(const json& object, const std::string& prefix = "",
                                                               const json::json_pointer& at = json::json_pointer()) {
  std::vector<std::pair<std::string, json::json_pointer>> leaves;
  for (const auto& item : object.items()) {
    const std::string path = prefix.empty() ? item.key() : prefix + "." + item.key();
    const json::json_pointer pointer = at / item.key();
    if (item.value().is_object()) {
      for (auto& leaf : Leaves(item.value(), path, pointer)) leaves.push_back(std::move(leaf));
    } else {
      leaves.emplace_back(path, pointer);
    }
  }
  return leaves;
}

TEST(FilterConfig, DefaultFileEqualsTheInCodeDefaults) {
  const FilterConfig loaded = LoadFilterConfig(FilterFile("default"));
  ExpectEqualConfigs(loaded, FilterConfig{});
  EXPECT_EQ(FilterConfigProblem(FilterConfig{}), std::nullopt);
}

TEST(FilterConfig, NoSlipModelFileDiffersOnlyInNameSlipSwitchAndWheelSigma) {
  // Without slip-aware odometry the wheel noise carries the terrain's slip range (filter_config.hpp).
  const FilterConfig loaded = LoadFilterConfig(FilterFile("no-slip-model"));
  FilterConfig expected;
  expected.name = "no-slip-model";
  expected.slip_aware_odometry.enabled = false;
  expected.wheels.speed_sigma_fraction = 0.1;
  ExpectEqualConfigs(loaded, expected);
  EXPECT_TRUE(FilterConfig{}.slip_aware_odometry.enabled);  // the default is slip-aware
}

TEST(FilterConfig, MethodFilesDifferFromTheDefaultInOneField) {
  FilterConfig cut;
  cut.name = "map-ellipsoid-cut";
  cut.map_aided.method = MapAidedMethod::kEllipsoidCut;
  ExpectEqualConfigs(LoadFilterConfig(FilterFile("map-ellipsoid-cut")), cut);
  FilterConfig deprior;
  deprior.name = "map-ellipsoid-cut-deprior";
  deprior.map_aided.method = MapAidedMethod::kEllipsoidCutDeprior;
  ExpectEqualConfigs(LoadFilterConfig(FilterFile("map-ellipsoid-cut-deprior")), deprior);
  EXPECT_TRUE(FilterConfig{}.imu.estimate_accel_bias);  // gravity on slopes (docs/localization-filter.md)
  EXPECT_EQ(FilterConfig{}.map_aided.method, MapAidedMethod::kRange);  // the default is consistent
}

TEST(FilterConfig, WheelAnglesFileDiffersInTheAngleSwitchTheWalksTheTorqueNoiseAndTheSlipRadius) {
  // Angles instead of speeds, one kappa for all wheels' terrain (docs/notes/2026-12-02-localization-filter.md §5.4);
  // R_w consistent there, so the slip uses it (§6); the radii drift together (§5.6).
  FilterConfig expected;
  expected.name = "wheel-angles";
  expected.wheels.angle_measurement = true;
  expected.slip_aware_odometry.slip_compliance_noise_per_sqrt_m = 0.0;
  expected.slip_aware_odometry.slip_compliance_wheel_correlation = 0.9999;
  expected.slip_aware_odometry.rolling_radius_noise_wheel_correlation = 0.99;
  expected.slip_aware_odometry.torque_sigma_nm = 0.05;  // the simulated torque sensor's noise
  expected.slip_aware_odometry.slip_with_rolling_radius = true;
  ExpectEqualConfigs(LoadFilterConfig(FilterFile("wheel-angles")), expected);
  EXPECT_FALSE(FilterConfig{}.slip_aware_odometry.slip_with_rolling_radius);  // the default: nominal radius
  EXPECT_FALSE(FilterConfig{}.wheels.angle_measurement);  // the default uses the speeds
}

TEST(FilterConfig, DifferentialFileDiffersInTheWheelSpeedSigma) {
  // The differential drive's encoder noise identified from its wheel NIS (scripts/tune-noise,
  // docs/notes/2026-12-02-localization-filter.md §5.8): 0.1 rad/s made the NIS half its expected value.
  FilterConfig expected;
  expected.name = "differential";
  expected.wheels.speed_sigma_radps = 0.06345;
  ExpectEqualConfigs(LoadFilterConfig(FilterFile("differential")), expected);
  EXPECT_EQ(FilterConfig{}.wheels.speed_sigma_radps, 0.1);  // the default, for every vehicle
}

TEST(FilterConfig, RoughCanopyFileDiffersInTheRangeSigma) {
  // The range sigma identified from the ultrasonic NIS on the rough-canopy worlds (scripts/tune-noise
  // --with-map, docs/map-aided-update.md §3.3): leaf-scale roughness the 3 mm of the echoes omit.
  FilterConfig expected;
  expected.name = "rough-canopy";
  expected.map_aided.range_sigma_m = 0.003891;
  ExpectEqualConfigs(LoadFilterConfig(FilterFile("rough-canopy")), expected);
  EXPECT_EQ(FilterConfig{}.map_aided.range_sigma_m, 0.003);  // the default: the echoes' own noise
}

TEST(FilterConfig, CanopyGnssFileDiffersInTheGnssBiasTheRadiusPriorAndTheIteratedWheels) {
  // An SBAS receiver under canopy and wheels without torque sensors (docs/notes/2026-12-02-localization-filter.md
  // §5.9): GNSS-bias states, radii that share the terrain's steady slip in their prior, and the
  // iterated wheel-speed update.
  FilterConfig expected;
  expected.name = "canopy-gnss";
  expected.gps.estimate_bias = true;
  expected.gps.bias_sigma_m = 0.2;
  expected.slip_aware_odometry.rolling_radius_prior_wheel_correlation = 0.99;
  expected.wheels.speed_update_iterations = 3;
  ExpectEqualConfigs(LoadFilterConfig(FilterFile("canopy-gnss")), expected);
  EXPECT_FALSE(FilterConfig{}.gps.estimate_bias);  // the default: every other vehicle as before
  EXPECT_EQ(FilterConfig{}.slip_aware_odometry.rolling_radius_prior_wheel_correlation, 0.0);
  EXPECT_EQ(FilterConfig{}.wheels.speed_update_iterations, 1);
}

TEST(FilterConfig, CanopyGnssFlatFileTradesTheIterationsForALowerSpeedNoiseAndAWiderRadiusPrior) {
  // canopy-gnss.json for flat ground (docs/notes/2026-12-02-localization-filter.md §5.10): no iterated update (its
  // pull on R_w is a counter-bias, §5.9 item 3); a lower velocity noise, which gives the speed
  // fewer false clues on the radius; a radius prior wide enough for the driven wheels' slip.
  FilterConfig expected = LoadFilterConfig(FilterFile("canopy-gnss"));
  expected.name = "canopy-gnss-flat";
  expected.wheels.speed_update_iterations = 1;
  expected.process_noise.velocity_mps_per_sqrt_hz = 0.002;
  expected.slip_aware_odometry.rolling_radius_sigma_m = 0.03;
  ExpectEqualConfigs(LoadFilterConfig(FilterFile("canopy-gnss-flat")), expected);
  EXPECT_EQ(FilterConfig{}.process_noise.velocity_mps_per_sqrt_hz, 0.02);
  EXPECT_EQ(FilterConfig{}.slip_aware_odometry.rolling_radius_sigma_m, 0.01);
}

TEST(FilterConfig, WhiteEncoderFileHasTheSimulatedSensorsNoises) {
  // The whiteness control (docs/notes/2026-12-02-localization-filter.md §5.11): the noises of the simulated sensors
  // where the default is conservative. The encoder wheel_encoder_white has no relative speed error,
  // the IMU profile's bias walk is 0.0004 m/s^2/sqrt(s), and the simulated vehicles hold their speed.
  FilterConfig expected;
  expected.name = "white-encoder";
  expected.wheels.speed_sigma_fraction = 0.0;
  expected.process_noise.accel_bias_mps2_per_sqrt_hz = 0.0004;
  expected.process_noise.velocity_mps_per_sqrt_hz = 0.002;
  ExpectEqualConfigs(LoadFilterConfig(FilterFile("white-encoder")), expected);
  EXPECT_EQ(FilterConfig{}.wheels.speed_sigma_fraction, 0.01);
  EXPECT_EQ(FilterConfig{}.process_noise.accel_bias_mps2_per_sqrt_hz, 0.05);
}

TEST(FilterConfig, NoSideSlipFileDiffersInTheNonHolonomicSigmaAndTheYawNoise) {
  // For wheels that do not slide sideways and smooth row following (docs/map-aided-update.md §3.1).
  FilterConfig expected;
  expected.name = "no-side-slip";
  expected.wheels.lateral_velocity_sigma_mps = 0.002;
  expected.process_noise.yaw_acceleration_radps2_per_sqrt_hz = 0.1;
  ExpectEqualConfigs(LoadFilterConfig(FilterFile("no-side-slip")), expected);
  EXPECT_EQ(FilterConfig{}.wheels.lateral_velocity_sigma_mps, 0.01);  // the default allows 1 cm/s of side slip
}

TEST(FilterConfig, EqualityHelperSeesADifference) {
  FilterConfig other;
  other.vio.gate_probability = 0.99;
  EXPECT_NONFATAL_FAILURE(ExpectEqualConfigs(FilterConfig{}, other), "gate_probability");
}

TEST(FilterConfig, EveryKeyLeftOutKeepsItsDefault) {
  const json base = DefaultJson();
  const auto leaves = Leaves(base);
  EXPECT_EQ(leaves.size(), 80u);  // every field of FilterConfig (update ExpectEqualConfigs too)
  for (const auto& [path, pointer] : leaves) {
    if (path == "name") continue;
    json edited = base;
    edited.at(pointer.parent_pointer()).erase(pointer.back());
    ASSERT_EQ(ErrorOf(edited), "") << path;
    ExpectEqualConfigs(ParseFilterConfig(edited.dump(), "edited.json"), FilterConfig{});
  }
  for (const char* section : {"process_noise", "slip_aware_odometry", "initialisation", "gps", "imu", "wheels",
                              "steering", "vio", "map_aided"}) {
    json edited = base;
    edited.erase(section);
    ExpectEqualConfigs(ParseFilterConfig(edited.dump(), "edited.json"), FilterConfig{});
  }
  EXPECT_EQ(ErrorOf(json{{"name", "only-a-name"}}), "");
}

TEST(FilterConfig, TheNameIsRequired) {
  json edited = DefaultJson();
  edited.erase("name");
  EXPECT_THAT(ErrorOf(edited), HasSubstr("edited.json: name: missing key"));
  EXPECT_THAT(ErrorOf(json::object()), HasSubstr("edited.json: name: missing key"));
  EXPECT_THAT(ErrorOf(json{{"name", ""}}), HasSubstr("edited.json: name must not be empty"));
}

TEST(FilterConfig, UnknownKeysAreNamed) {
  json edited = DefaultJson();
  edited["gps"]["sigma_scal"] = 1.0;
  EXPECT_THAT(ErrorOf(edited), HasSubstr("edited.json: gps.sigma_scal: unknown key"));
  edited = DefaultJson();
  edited["slip_aware_odometry"]["extra"] = true;
  EXPECT_THAT(ErrorOf(edited), HasSubstr("slip_aware_odometry.extra: unknown key"));
  edited = DefaultJson();
  edited["slip_aware_odometry"]["terrain_change"]["threshold"] = 5.0;
  EXPECT_THAT(ErrorOf(edited), HasSubstr("slip_aware_odometry.terrain_change.threshold: unknown key"));
  edited = DefaultJson();
  edited["lidar"] = json::object();
  EXPECT_THAT(ErrorOf(edited), HasSubstr("edited.json: lidar: unknown key"));
}

// The torque/slip gradient keys of files written before the slip compliance replaced k_s as the
// state: the error names the key and its replacement instead of only "unknown key".
TEST(FilterConfig, RetiredSlipGradientKeysNameTheirReplacement) {
  for (const char* old : {"slip_gradient_initial_nm", "slip_gradient_sigma_nm", "min_slip_gradient_nm",
                          "slip_gradient_noise_nm_per_sqrt_m"}) {
    json edited = DefaultJson();
    edited["slip_aware_odometry"][old] = 500.0;
    const std::string error = ErrorOf(edited);
    EXPECT_THAT(error, HasSubstr(std::string("slip_aware_odometry.") + old + ": was replaced")) << old;
    EXPECT_THAT(error, HasSubstr("slip_compliance_initial")) << old;
  }
}

TEST(FilterConfig, MaxModelSlipMustBeBelowOne) {
  FilterConfig config;
  config.slip_aware_odometry.max_model_slip = 1.0;
  EXPECT_EQ(FilterConfigProblem(config),
            std::optional<std::string>("slip_aware_odometry.max_model_slip must be in [0.01, 0.99], got 1"));
  config.slip_aware_odometry.max_model_slip = 0.95;
  EXPECT_FALSE(FilterConfigProblem(config).has_value());
}

TEST(FilterConfig, WrongTypesAreNamed) {
  const json base = DefaultJson();
  for (const auto& [path, pointer] : Leaves(base)) {
    json edited = base;
    edited[pointer] = json::array({"x"});  // wrong for every leaf
    const std::string error = ErrorOf(edited);
    EXPECT_THAT(error, HasSubstr("edited.json: " + path)) << path;
    EXPECT_THAT(error, HasSubstr("must be")) << path;
  }
  json edited = base;
  edited["slip_aware_odometry"]["enabled"] = 1;
  EXPECT_THAT(ErrorOf(edited), HasSubstr("slip_aware_odometry.enabled: must be true or false, got number"));
  edited = base;
  edited["wheels"]["max_speed_radps"] = "200";
  EXPECT_THAT(ErrorOf(edited), HasSubstr("wheels.max_speed_radps: must be a number, got string"));
  edited = base;
  edited["name"] = 3;
  EXPECT_THAT(ErrorOf(edited), HasSubstr("name: must be a string"));
  edited = base;
  edited["vio"]["position_m"] = json::array({0.0});
  EXPECT_THAT(ErrorOf(edited), HasSubstr("vio.position_m: must be an array of 2 numbers"));
  edited = base;
  edited["imu"] = 5;
  EXPECT_THAT(ErrorOf(edited), HasSubstr("imu: must be an object"));
  EXPECT_THAT(ErrorOf(std::string("[1, 2]")), AllOf(HasSubstr("edited.json"), HasSubstr("must be an object")));
}

TEST(FilterConfig, NonFiniteAndInvalidJsonAreRejected) {
  // JSON has no NaN or infinity literal; a number too large for a double is a parse error.
  json document = DefaultJson();
  document["imu"]["gyro_sigma_radps"] = 12345.5;  // a marker, replaced in the text
  const std::string text = document.dump();
  const std::string key = "\"gyro_sigma_radps\":12345.5";
  ASSERT_NE(text.find(key), std::string::npos);
  EXPECT_THAT(ErrorOf(std::string(text).replace(text.find(key), key.size(), "\"gyro_sigma_radps\":1e999")),
              AllOf(HasSubstr("edited.json"), HasSubstr("invalid JSON"), HasSubstr("1e999")));
  EXPECT_THAT(ErrorOf(std::string(text).replace(text.find(key), key.size(), "\"gyro_sigma_radps\":NaN")),
              AllOf(HasSubstr("edited.json"), HasSubstr("invalid JSON")));
  EXPECT_THAT(ErrorOf(std::string("{ \"name\": ")), AllOf(HasSubstr("edited.json"), HasSubstr("invalid JSON")));
}

/// Numeric keys for which 0 is valid: no encoder filter, a wheel noise without a relative part (the
/// absolute sigma keeps it positive), calibration states that do not drift, independent wheels'
/// kappas and radius walks, a carried calibration taken as it is.
const std::set<std::string> kMayBeZero = {"initialisation.map_heading_sigma_rad",  // 0: off
                                          "wheels.encoder_low_pass_time_constant_s",
                                          "wheels.speed_sigma_fraction",
                                          "slip_aware_odometry.rolling_radius_noise_m_per_sqrt_m",
                                          "slip_aware_odometry.slip_compliance_noise_per_sqrt_m",
                                          "slip_aware_odometry.slip_compliance_wheel_correlation",
                                          "slip_aware_odometry.rolling_radius_noise_wheel_correlation",
                                          "slip_aware_odometry.rolling_radius_prior_wheel_correlation",
                                          "slip_aware_odometry.torque_sigma_nm",
                                          "slip_aware_odometry.carried_rolling_radius_change_sigma_m",
                                          "slip_aware_odometry.carried_slip_compliance_change_sigma",
                                          "slip_aware_odometry.terrain_change.cusum_drift_sigma",  // 0: no allowance
                                          "slip_aware_odometry.terrain_change.max_yaw_rate_radps"};  // 0: straight only

/// Integer keys: ranges of counts, tested on their own.
const std::set<std::string> kCounts = {"wheels.speed_update_iterations", "map_aided.adaptive_range_sigma.window_echoes",
                                       "map_aided.adaptive_range_sigma.min_echoes"};

TEST(FilterConfig, NonPositiveSigmasAndBadProbabilitiesAreNamed) {
  const json base = DefaultJson();
  for (const auto& [path, pointer] : Leaves(base)) {
    if (!base[pointer].is_number()) continue;  // name, enabled, position_m
    if (kMayBeZero.contains(path)) continue;  // below
    if (kCounts.contains(path)) continue;  // counts: their own tests (SpeedUpdateIterationsAreACount, ...)
    const bool probability = path.ends_with("gate_probability");
    for (const double bad : probability ? std::vector<double>{0.0, 1.0, -0.1, 1.5} : std::vector<double>{0.0, -1.0}) {
      json edited = base;
      edited[pointer] = bad;
      EXPECT_THAT(ErrorOf(edited), AllOf(HasSubstr("edited.json: " + path),
                                         HasSubstr(probability ? "must be in (0, 1)" : "must be in [")))
          << path << " = " << bad;
    }
  }
}

// Issue 26: max_prediction_step_s = 1e-300 hung the filter (remaining -= dt made no progress), sigmas
// of 1e300 overflowed it, max_prediction_gap_s = 1e300 let a 1e6 s gap run 16 s: every number has a
// physical range, and the message names the key and the range in short numbers.
TEST(FilterConfig, EveryNumberHasAPhysicalRange) {
  const json base = DefaultJson();
  for (const auto& [path, pointer] : Leaves(base)) {
    if (!base[pointer].is_number() || kCounts.contains(path)) continue;
    const bool probability = path.ends_with("gate_probability");
    std::vector<double> bad{1e300};
    if (!kMayBeZero.contains(path)) bad.push_back(1e-300);
    for (const double value : bad) {
      json edited = base;
      edited[pointer] = value;
      const std::string error = ErrorOf(edited);
      EXPECT_THAT(error, AllOf(HasSubstr("edited.json: " + path + " must be in "), HasSubstr(probability ? "(0, 1) and at least 0.5" : "["),
                               HasSubstr(", got " + std::string(value > 1.0 ? "1e+300" : "1e-300"))))
          << path << " = " << value;
      EXPECT_LT(error.size(), 160u) << error;  // short numbers, never 309 digits
    }
  }
  json edited = base;
  edited["max_prediction_step_s"] = 1e-300;
  EXPECT_THAT(ErrorOf(edited), HasSubstr("edited.json: max_prediction_step_s must be in [0.0001, 1], got 1e-300"));
  edited = base;
  edited["max_prediction_gap_s"] = 1e300;
  EXPECT_THAT(ErrorOf(edited), HasSubstr("edited.json: max_prediction_gap_s must be in [0.0001, 3600], got 1e+300"));
  edited = base;
  edited["imu"]["gyro_sigma_radps"] = 1e300;
  EXPECT_THAT(ErrorOf(edited), HasSubstr("edited.json: imu.gyro_sigma_radps must be in [1e-09, 100], got 1e+300"));
}

TEST(FilterConfig, TimeJumpMustCoverThePredictionGap) {
  json edited = DefaultJson();
  EXPECT_EQ(ParseFilterConfig(edited.dump(), "edited.json").max_time_jump_s, 3600.0);
  edited["max_time_jump_s"] = 1.0;  // < max_prediction_gap_s = 5
  EXPECT_THAT(ErrorOf(edited), HasSubstr("edited.json: max_time_jump_s must be >= max_prediction_gap_s"));
  edited.erase("max_time_jump_s");  // the default, 3600 s
  EXPECT_EQ(ParseFilterConfig(edited.dump(), "edited.json").max_time_jump_s, 3600.0);
}

TEST(FilterConfig, AdaptiveRangeSigmaCountsAndCapAreChecked) {
  json edited = DefaultJson();
  json& adaptive = edited["map_aided"]["adaptive_range_sigma"];
  adaptive["window_echoes"] = 40;
  adaptive["min_echoes"] = 40;
  const FilterConfig parsed = ParseFilterConfig(edited.dump(), "edited.json");
  EXPECT_EQ(parsed.map_aided.adaptive_range_sigma.window_echoes, 40);
  EXPECT_EQ(parsed.map_aided.adaptive_range_sigma.min_echoes, 40);
  adaptive["min_echoes"] = 41;
  EXPECT_THAT(ErrorOf(edited), HasSubstr("map_aided.adaptive_range_sigma.min_echoes must be from 1 to window_echoes"));
  adaptive["min_echoes"] = 10;
  for (const json& bad : {json(0), json(-3), json(100001)}) {
    adaptive["window_echoes"] = bad;
    EXPECT_THAT(ErrorOf(edited), HasSubstr("map_aided.adaptive_range_sigma.window_echoes: must be in [1, 100000]")) << bad;
  }
  adaptive["window_echoes"] = 2.5;
  EXPECT_THAT(ErrorOf(edited), HasSubstr("map_aided.adaptive_range_sigma.window_echoes: must be an integer"));
  adaptive["window_echoes"] = 200;
  adaptive["max_sigma_m"] = 0.002;  // below the range sigma, 0.003
  EXPECT_THAT(ErrorOf(edited), HasSubstr("map_aided.adaptive_range_sigma.max_sigma_m must be >= map_aided.range_sigma_m"));
  FilterConfig config;
  config.map_aided.adaptive_range_sigma.min_echoes = 0;
  EXPECT_THAT(FilterConfigProblem(config).value_or(""), HasSubstr("min_echoes must be from 1 to window_echoes"));
}

TEST(FilterConfig, SpeedUpdateIterationsAreACount) {
  json edited = DefaultJson();
  edited["wheels"]["speed_update_iterations"] = 3;
  EXPECT_EQ(ParseFilterConfig(edited.dump(), "edited.json").wheels.speed_update_iterations, 3);
  for (const json& bad : {json(0), json(11), json(-1)}) {
    edited["wheels"]["speed_update_iterations"] = bad;
    EXPECT_THAT(ErrorOf(edited), HasSubstr("edited.json: wheels.speed_update_iterations: must be in [1, 10]")) << bad;
  }
  for (const json& bad : {json(2.5), json("3")}) {
    edited["wheels"]["speed_update_iterations"] = bad;
    EXPECT_THAT(ErrorOf(edited), HasSubstr("wheels.speed_update_iterations: must be an integer")) << bad;
  }
  FilterConfig config;
  for (const int bad : {0, 11}) {
    config.wheels.speed_update_iterations = bad;
    EXPECT_EQ(FilterConfigProblem(config), "wheels.speed_update_iterations must be from 1 to 10");
  }
}

TEST(FilterConfig, MapAidedMethodNamesRoundTripAndUnknownOnesAreNamed) {
  for (const MapAidedMethod m :
       {MapAidedMethod::kRange, MapAidedMethod::kEllipsoidCut, MapAidedMethod::kEllipsoidCutDeprior}) {
    EXPECT_EQ(MapAidedMethodFromName(MapAidedMethodName(m)), m);
    json edited = DefaultJson();
    edited["map_aided"]["method"] = std::string(MapAidedMethodName(m));
    EXPECT_EQ(ParseFilterConfig(edited.dump(), "edited.json").map_aided.method, m);
  }
  EXPECT_EQ(MapAidedMethodFromName("ellipsoid"), std::nullopt);
  json edited = DefaultJson();
  edited["map_aided"]["method"] = "ellipsoid";
  EXPECT_THAT(ErrorOf(edited), AllOf(HasSubstr("edited.json: map_aided.method: must be \"range\""),
                                     HasSubstr("got \"ellipsoid\"")));
}

TEST(FilterConfig, ZeroIsValidWhereItMeansNoneButNegativeIsNot) {
  for (const std::string& path : kMayBeZero) {
    std::string pointer = "/" + path;  // "a.b.c" -> "/a/b/c"
    std::replace(pointer.begin(), pointer.end(), '.', '/');
    json edited = DefaultJson();
    edited[json::json_pointer(pointer)] = 0.0;
    EXPECT_NO_THROW(ParseFilterConfig(edited.dump(), "edited.json")) << path;
    edited[json::json_pointer(pointer)] = -0.01;
    EXPECT_THAT(ErrorOf(edited), HasSubstr("edited.json: " + path)) << path;
  }
}

TEST(FilterConfig, WheelCorrelationsAreBelowOne) {
  for (const std::string key : {"slip_compliance_wheel_correlation", "rolling_radius_noise_wheel_correlation",
                                "rolling_radius_prior_wheel_correlation"}) {
    json edited = DefaultJson();
    edited["slip_aware_odometry"][key] = 0.999;
    const SlipAwareOdometryConfig parsed = ParseFilterConfig(edited.dump(), "edited.json").slip_aware_odometry;
    const double value = key == "slip_compliance_wheel_correlation"        ? parsed.slip_compliance_wheel_correlation
                         : key == "rolling_radius_noise_wheel_correlation" ? parsed.rolling_radius_noise_wheel_correlation
                                                                           : parsed.rolling_radius_prior_wheel_correlation;
    EXPECT_EQ(value, 0.999) << key;
    for (const double bad : {1.0, 1.5, -0.5}) {
      edited["slip_aware_odometry"][key] = bad;
      EXPECT_THAT(ErrorOf(edited), HasSubstr("slip_aware_odometry." + key + " must be in [0, 1)")) << key << " " << bad;
    }
  }
}

TEST(FilterConfig, EncoderLowPassTimeConstantMayBeZeroButNotNegative) {
  json edited = DefaultJson();
  for (const double tau : {0.0, 0.02}) {
    edited["wheels"]["encoder_low_pass_time_constant_s"] = tau;
    EXPECT_EQ(ParseFilterConfig(edited.dump(), "edited.json").wheels.encoder_low_pass_time_constant_s, tau);
  }
  edited["wheels"]["encoder_low_pass_time_constant_s"] = -0.01;
  EXPECT_THAT(ErrorOf(edited),
              HasSubstr("edited.json: wheels.encoder_low_pass_time_constant_s must be in [0, 10], got -0.01"));
}

TEST(FilterConfig, ConeHalfAngleMustBeBelowAQuarterTurn) {
  json edited = DefaultJson();
  edited["map_aided"]["cone_half_angle_rad"] = 1.6;  // > pi/2
  EXPECT_THAT(ErrorOf(edited), HasSubstr("edited.json: map_aided.cone_half_angle_rad must be in [1e-06, 1.5708], got 1.6"));
  edited["map_aided"]["cone_half_angle_rad"] = 0.5 * std::numbers::pi;  // inside the range, but not < pi/2
  EXPECT_THAT(ErrorOf(edited), HasSubstr("edited.json: map_aided.cone_half_angle_rad must be < pi/2"));
  edited["map_aided"]["cone_half_angle_rad"] = 1.5;
  EXPECT_EQ(ErrorOf(edited), "");
}

TEST(FilterConfig, PredictionGapMustCoverTheStep) {
  json edited = DefaultJson();
  edited["max_prediction_gap_s"] = 0.01;  // < max_prediction_step_s = 0.02
  EXPECT_THAT(ErrorOf(edited), HasSubstr("edited.json: max_prediction_gap_s must be >= max_prediction_step_s"));
  edited["max_prediction_gap_s"] = 0.02;  // equal is fine
  EXPECT_EQ(ErrorOf(edited), "");
}

TEST(FilterConfig, MissingFileIsAFilterConfigError) {
  const test::ScratchDir scratch;
  const auto missing = scratch / "absent.json";
  try {
    LoadFilterConfig(missing);
    ADD_FAILURE() << "no error for a missing file";
  } catch (const FilterConfigError& e) {
    EXPECT_THAT(e.what(), AllOf(HasSubstr("absent.json"), HasSubstr("cannot open")));
  }
}

TEST(FilterConfig, ProblemOfInCodeConfigsNamesTheField) {
  constexpr double kNaN = std::numeric_limits<double>::quiet_NaN();
  constexpr double kInf = std::numeric_limits<double>::infinity();
  using Edit = std::function<void(FilterConfig&, double)>;
  const std::vector<std::pair<std::string, Edit>> fields = {
      {"process_noise.jerk_mps3_per_sqrt_hz",
       [](FilterConfig& c, double v) { c.process_noise.jerk_mps3_per_sqrt_hz = v; }},
      {"process_noise.gyro_bias_radps_per_sqrt_hz",
       [](FilterConfig& c, double v) { c.process_noise.gyro_bias_radps_per_sqrt_hz = v; }},
      {"slip_aware_odometry.slip_compliance_initial",
       [](FilterConfig& c, double v) { c.slip_aware_odometry.slip_compliance_initial = v; }},
      {"slip_aware_odometry.rolling_radius_sigma_m",
       [](FilterConfig& c, double v) { c.slip_aware_odometry.rolling_radius_sigma_m = v; }},
      {"wheels.angle_sigma_rad", [](FilterConfig& c, double v) { c.wheels.angle_sigma_rad = v; }},
      {"initialisation.heading_baseline_m", [](FilterConfig& c, double v) { c.initialisation.heading_baseline_m = v; }},
      {"gps.sigma_floor_sbas_m", [](FilterConfig& c, double v) { c.gps.sigma_floor_sbas_m = v; }},
      {"gps.bias_sigma_m", [](FilterConfig& c, double v) { c.gps.bias_sigma_m = v; }},
      {"gps.bias_time_constant_s", [](FilterConfig& c, double v) { c.gps.bias_time_constant_s = v; }},
      {"imu.gyro_sigma_radps", [](FilterConfig& c, double v) { c.imu.gyro_sigma_radps = v; }},
      {"wheels.speed_sigma_radps", [](FilterConfig& c, double v) { c.wheels.speed_sigma_radps = v; }},
      {"wheels.lateral_velocity_sigma_mps", [](FilterConfig& c, double v) { c.wheels.lateral_velocity_sigma_mps = v; }},
      {"steering.angle_sigma_rad", [](FilterConfig& c, double v) { c.steering.angle_sigma_rad = v; }},
      {"vio.sigma_scale", [](FilterConfig& c, double v) { c.vio.sigma_scale = v; }},
      {"max_prediction_step_s", [](FilterConfig& c, double v) { c.max_prediction_step_s = v; }},
      {"gps.gate_probability", [](FilterConfig& c, double v) { c.gps.gate_probability = v; }},
      {"wheels.gate_probability", [](FilterConfig& c, double v) { c.wheels.gate_probability = v; }},
  };
  for (const auto& [key, edit] : fields) {
    for (const double bad : {0.0, -1.0, kNaN, kInf}) {
      FilterConfig config;
      edit(config, bad);
      const auto problem = FilterConfigProblem(config);
      ASSERT_TRUE(problem.has_value()) << key << " = " << bad;
      EXPECT_THAT(*problem, HasSubstr(key)) << bad;
    }
  }
  FilterConfig config;
  config.gps.gate_probability = 1.0;
  EXPECT_EQ(FilterConfigProblem(config),
            std::optional<std::string>("gps.gate_probability must be in (0, 1) and at least 0.5, got 1"));
  config = FilterConfig{};
  config.max_prediction_step_s = kInf;
  EXPECT_THAT(FilterConfigProblem(config).value_or(""), HasSubstr("max_prediction_step_s"));
  config = FilterConfig{};
  config.vio.position_m.x() = kNaN;
  EXPECT_THAT(FilterConfigProblem(config).value_or(""), HasSubstr("vio.position_m"));
  config = FilterConfig{};
  config.name.clear();
  EXPECT_THAT(FilterConfigProblem(config).value_or(""), HasSubstr("name"));
  config = FilterConfig{};
  config.max_prediction_gap_s = 0.5 * config.max_prediction_step_s;
  EXPECT_THAT(FilterConfigProblem(config).value_or(""), HasSubstr("max_prediction_gap_s"));
}

}  // namespace
}  // namespace rowloc::localization

namespace rowloc::localization {
namespace {

TEST(GpsSigma, FloorOfTheFixQualityBoundsTheReceiversClaim) {
  const GpsNoise noise;  // floors 5 mm (RTK fixed), 5 cm (float), 0.3 m (SBAS), scale 1
  EXPECT_DOUBLE_EQ(GpsSigma(noise, formats::GnssFixQuality::kRtkFixed, 0.001), 0.005);
  EXPECT_DOUBLE_EQ(GpsSigma(noise, formats::GnssFixQuality::kRtkFixed, 0.02), 0.02);
  EXPECT_DOUBLE_EQ(GpsSigma(noise, formats::GnssFixQuality::kRtkFloat, 0.01), 0.05);
  EXPECT_DOUBLE_EQ(GpsSigma(noise, formats::GnssFixQuality::kSbas, 0.1), 0.3);
  EXPECT_DOUBLE_EQ(GpsSigma(noise, formats::GnssFixQuality::kSbas, 0.8), 0.8);
  GpsNoise scaled = noise;
  scaled.sigma_scale = 2.0;
  EXPECT_DOUBLE_EQ(GpsSigma(scaled, formats::GnssFixQuality::kRtkFixed, 0.01), 0.02);
  EXPECT_THROW(GpsSigma(noise, formats::GnssFixQuality::kNone, 0.01), std::invalid_argument);
}

}  // namespace
}  // namespace rowloc::localization
