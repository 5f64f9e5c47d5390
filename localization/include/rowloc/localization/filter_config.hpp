// Configuration of the vehicle EKF as data (issue 4, "Configuration ... from a file, with clear
// errors"). Vehicle geometry comes from the vehicle file (rowloc/mapio/vehicle_config.hpp);
// this file holds the noise figures, process noise, gates and options of the filter.
//
// Units and meaning (all 1-sigma; "per sqrt(Hz)" is a continuous white-noise spectral density q,
// discretized as q^2 dt; docs/localization-filter.md explains each choice):
//   process_noise.jerk_mps3_per_sqrt_hz            drives a_Bx, a_By (random walk)
//   process_noise.yaw_acceleration_radps2_per_sqrt_hz drives phi_dot
//   process_noise.velocity_mps_per_sqrt_hz         small direct velocity noise (unmodelled forces)
//   process_noise.steering_rate_radps_per_sqrt_hz  drives each delta
//   process_noise.gyro_bias_radps_per_sqrt_hz      drives b_g (the IMU's bias random walk)
//   process_noise.accel_bias_mps2_per_sqrt_hz      drives b_ax, b_ay (imu.estimate_accel_bias: the
//                                                  bias and gravity on a slope that changes as the
//                                                  vehicle drives)
//   slip_aware_odometry.*_per_sqrt_m               Lindgren et al. 2002: R_w and kappa random walks whose variance
//                                                  grows with the distance the wheel rolled
// Gates are probabilities p: a measurement of dimension m is rejected when its NIS exceeds the
// chi-square quantile Q(m, p) (the design's "chi-square gating of outliers").
//
// File format (config/filters/*.json; docs/localization-filter.md §3): an overlay on the in-code
// defaults below (the struct initialisers are the single source of every default). A file lists
// "name" and only the keys it changes; they are merged key by key onto the defaults
// (mapio/config_overlay.hpp: objects merge, any other value replaces). A file may name a base
// filter file with "extends" (a path relative to the file): the base is merged onto the defaults
// first. Unknown keys are refused, also in an overlay and in its bases (a typo must not fall back
// silently to a default); errors name the file, the key path and the reason (the same strict reader
// as the simulator's files). Every number has a physical domain [min, max] (filter_config.cpp,
// Rules; docs/localization-filter.md §3): a sign check alone let a prediction step of 1e-300 s
// hang the filter and a sigma of 1e300 overflow its covariance.
#pragma once

#include "rowloc/formats/gnss_fix_quality.hpp"
#include "rowloc/localization/terrain_change_detector.hpp"

#include <Eigen/Core>

#include <filesystem>
#include <optional>
#include <stdexcept>
#include <string>
#include <string_view>
#include <vector>

namespace rowloc::localization {

struct ProcessNoise {
  double jerk_mps3_per_sqrt_hz = 2.0;
  double yaw_acceleration_radps2_per_sqrt_hz = 0.3;
  double velocity_mps_per_sqrt_hz = 0.02;
  double steering_rate_radps_per_sqrt_hz = 0.5;
  double gyro_bias_radps_per_sqrt_hz = 2e-5;
  double accel_bias_mps2_per_sqrt_hz = 0.05;
};

/// Lindgren et al. 2002: rolling radius R_w and the torque/slip relation of every wheel as EKF states. The
/// relation is held as the slip compliance kappa = N r / k_s (slip per unit traction coefficient,
/// dimensionless; k_s Lindgren et al.'s torque/slip gradient, N r the wheel's static load times its nominal
/// radius), not as k_s: see measurement_models.hpp and docs/notes/2026-12-02-localization-filter.md §5.2.
struct SlipAwareOdometryConfig {
  bool enabled = true;
  double rolling_radius_sigma_m = 0.01;             ///< initial sigma of R_w around the nominal radius
  double slip_compliance_initial = 1.0;             ///< initial kappa (slip per unit traction), > 0
  double slip_compliance_sigma = 1.0;               ///< its initial sigma
  double max_model_slip = 0.9;                      ///< kappa is clamped so that kappa mu <= this, in (0, 1)
  double rolling_radius_noise_m_per_sqrt_m = 1e-5;  ///< R_w random walk per sqrt(metre rolled)
  double slip_compliance_noise_per_sqrt_m = 0.003;  ///< kappa random walk per sqrt(metre rolled)
  /// Correlation rho in [0, 1) of the kappas of two wheels, in their initial covariance and in
  /// their random walk (wheels of one vehicle roll on one terrain): the difference of two wheels'
  /// kappas has (1 - rho) times the variance of independent ones (docs/notes/2026-12-02-localization-filter.md §5.4).
  double slip_compliance_wheel_correlation = 0.0;
  /// Correlation rho in [0, 1) of the random walks of two wheels' R_w (their initial sigmas stay
  /// independent). What changes a radius during a drive (tyre temperature and pressure, load, the
  /// terrain's sinkage) changes every wheel's alike; only the difference of two radii turns the
  /// vehicle, and it has (1 - rho) times the walk of independent ones
  /// (docs/notes/2026-12-02-localization-filter.md §5.6).
  double rolling_radius_noise_wheel_correlation = 0.0;
  /// Correlation rho in [0, 1) of two wheels' R_w in their initial covariance. With independent
  /// priors the wheel speeds pin the radii's differences at once and leave their common part with
  /// sigma / sqrt(wheels): a common error of the prior (the steady slip of the terrain, which R_w
  /// absorbs without a torque sensor) is then several sigma off (docs/notes/2026-12-02-localization-filter.md §5.9).
  double rolling_radius_prior_wheel_correlation = 0.0;
  /// Wheels messages without torques: the traction coefficient from the acceleration state
  /// (measurement_models.hpp) instead of 0.
  bool traction_from_acceleration = true;
  /// The torque sensor's noise, N m (>= 0). 0: the measured torques are taken as exact. > 0: one
  /// traction-coefficient state mu per wheel, which the torques measure (sigma T / (N r)); a torque
  /// step beyond the gate re-anchors it (docs/notes/2026-12-02-localization-filter.md §5.5).
  double torque_sigma_nm = 0.0;
  /// Random walk of the traction states between torque steps, 1/sqrt(s).
  double traction_noise_per_sqrt_s = 1e-4;
  /// The SAE slip (wheel_slip_estimate.hpp) with each wheel's R_w state instead of its nominal
  /// radius. Worth it only where R_w is consistent (the traction states separate it from kappa,
  /// docs/notes/2026-12-02-localization-filter.md §5.5), and above all on the smoothed stream (§6).
  bool slip_with_rolling_radius = false;
  /// How much R_w (m) and kappa may change between two drives (tyre pressure, temperature and
  /// wear; another terrain): added in quadrature to the sigmas of a calibration carried from a
  /// previous drive (VehicleEkf::SetWheelCalibrationPrior), whose posterior says nothing about
  /// what changed since. Unused without a carried calibration (docs/localization-filter.md §6.2:
  /// sized so that a change of terrain, R_w up to 3 % and kappa 0.25 to 1.25 between the simulated
  /// ones, lies within 2.5 sigma).
  double carried_rolling_radius_change_sigma_m = 2e-3;
  double carried_slip_compliance_change_sigma = 0.5;
  /// A change of terrain under a wheel detected from its speed innovations, and R_w's variance
  /// widened there (terrain_change_detector.hpp). On by default.
  TerrainChangeConfig terrain_change;
};

/// Initial uncertainty and the heading alignment from GNSS (docs/localization-filter.md §2).
struct InitialisationConfig {
  double heading_baseline_m = 2.0;   ///< GNSS displacement that fixes the initial heading, > 0
  double heading_sigma_rad = 0.2;
  double velocity_sigma_mps = 0.3;
  double yaw_rate_sigma_radps = 0.1;
  double acceleration_sigma_mps2 = 0.5;
  double gyro_bias_sigma_radps = 0.005;
  double steering_sigma_rad = 0.05;
  double accel_bias_sigma_mps2 = 0.5;  ///< with imu.estimate_accel_bias
  /// With a row map attached, > 0: the map-aided initialisation (vehicle_ekf_initialisation.cpp):
  /// once the GNSS course over a shorter baseline shows which way the vehicle drives, and the
  /// vehicle is in a lane of the map, the heading is the lane's direction with this sigma, rad
  /// (below the cone's half aperture / k_sigma, the echoes are used at once). 0: off.
  double map_heading_sigma_rad = 0.0;
};

/// Fix quality -> covariance: sigma = max(floor of the fix quality, sigma_scale x the receiver's
/// sigma_horizontal_m) per horizontal axis (a receiver's claims for float and SBAS fixes are often
/// optimistic; the floors bound them).
struct GpsNoise {
  double sigma_scale = 1.0;             ///< multiplies the receiver's sigma_horizontal_m, > 0
  double sigma_floor_rtk_fixed_m = 0.005;
  double sigma_floor_rtk_float_m = 0.05;
  double sigma_floor_sbas_m = 0.3;
  double gate_probability = 0.9999;
  /// When every fix for longer than this (s) was gated out, the filter has drifted (not the receiver):
  /// the next fix re-acquires, P's position block is inflated by y y^T and the fix applied ungated.
  double reacquire_after_s = 10.0;
  /// Estimate the slowly varying part of the fix error (multipath under canopy) as two states, a
  /// first-order Gauss-Markov process per axis: b' = -b / tau + w, stationary sigma bias_sigma_m,
  /// correlation exp(-|dt| / tau) (process_model.hpp). Off: the fix error is taken as white, which a
  /// multipath offset held for seconds is not (the filter becomes overconfident under canopy).
  bool estimate_bias = false;
  double bias_sigma_m = 0.4;          ///< stationary 1-sigma per horizontal axis, > 0
  double bias_time_constant_s = 5.0;  ///< tau, > 0
};

struct ImuNoise {
  double accel_sigma_mps2 = 0.03;  ///< per axis, per sample (white noise + unmodelled bias)
  double gyro_sigma_radps = 0.002;
  double gate_probability = 0.9999;
  /// Estimate an accelerometer bias (b_ax, b_ay states): what the flat-ground model cannot explain,
  /// chiefly gravity on slopes (g sin(slope): 0.4 m/s^2 at 4 %), which otherwise reads as acceleration.
  bool estimate_accel_bias = true;
};

struct WheelNoise {
  double speed_sigma_radps = 0.1;  ///< per wheel, per sample (quantization, noise)
  /// Relative part, >= 0: sigma_i^2 = speed_sigma_radps^2 + (speed_sigma_fraction omega_i)^2 (slip that
  /// the model does not capture: use the slip range of the terrain without slip-aware odometry).
  double speed_sigma_fraction = 0.01;
  /// Side-slip sigma of the non-holonomic constraint (lateral wheel-centre velocity = 0), m/s; it
  /// is applied with every wheels message as a separate update named "nonholonomic".
  double lateral_velocity_sigma_mps = 0.01;
  double gate_probability = 0.9999;
  double max_speed_radps = 200.0;  ///< larger |omega| is rejected as out of range
  /// Time constant of the encoder's first-order low-pass speed filter, s (0: none): the encoder
  /// reports omega(t - tau) to first order, which lags by tau d omega / dt when the vehicle brakes
  /// or accelerates (WheelSpeedModel). The simulated encoders (config/sensors.json) use 0.02 s.
  double encoder_low_pass_time_constant_s = 0.0;
  /// Use the encoders' cumulative angles (wheels message `angle_rad`) instead of their speeds:
  /// one wheel-angle state per wheel (wheel_angle_model.hpp; docs/notes/2026-12-02-localization-filter.md §5.4).
  /// A wheels message without angles is still used as speeds.
  bool angle_measurement = false;
  /// Per wheel, per sample: the tick angle over sqrt(12) (uniform quantization); 1024 ticks per
  /// revolution: 2 pi / 1024 / sqrt(12) = 1.77e-3 rad.
  double angle_sigma_rad = 1.77e-3;
  /// White noise on theta' = omega(x): the wheel-rate model's error, rad/s/sqrt(Hz).
  double angle_rate_noise_radps_per_sqrt_hz = 1e-3;
  /// The angles update the filter only when every wheel's predicted angle sigma is at most this,
  /// rad (default: one tick at 1024 ticks per revolution). Otherwise (after initialisation, until
  /// the wheel rates are known to about a tick per sample) the message's speeds are used and the
  /// angles re-anchored: precise angles linearized far from the truth can drive the filter away
  /// (docs/notes/2026-12-02-localization-filter.md §5.7).
  double angle_max_prediction_sigma_rad = 6.14e-3;
  /// Gauss-Newton iterations of the wheel-speed update, 1 to 10 (1: the EKF update). Each further
  /// iteration re-linearizes at the updated state (the iterated EKF, Bell & Cathey 1993; Särkkä
  /// 2013 §5.4), whose fixed point is the mode of the update's posterior. For the ratio
  /// omega = v / (R_w (1 - kappa mu)) that mode lies towards smaller (v, R_w): the iterations pull
  /// R_w down, against the walk up that the speed's process noise causes without fixes. A
  /// counter-bias, not a cure (docs/notes/2026-12-02-localization-filter.md §5.9 item 3).
  int speed_update_iterations = 1;
};

struct SteeringNoise {
  double angle_sigma_rad = 0.001;
  double gate_probability = 0.9999;
};

struct VioNoise {
  Eigen::Vector2d position_m = Eigen::Vector2d::Zero();  ///< camera lever arm, body frame
  double sigma_scale = 1.0;
  double gate_probability = 0.9999;
};

/// How an ultrasonic echo updates the filter against the row map (map_aided_ranging.hpp; issue 5;
/// docs/map-aided-update.md).
enum class MapAidedMethod {
  kRange,               ///< "range": EKF update of the measured range against the row line (consistent)
  kEllipsoidCut,        ///< "ellipsoid_cut": Donati 2021: the cut ellipse as a position measurement
                        ///< (built from the prior, so it counts the prior twice: overconfident)
  kEllipsoidCutDeprior  ///< "ellipsoid_cut_deprior": the cut's information along the row normal
                        ///< minus the prior's, as a scalar measurement (the prior counted once)
};
/// "range", "ellipsoid_cut" or "ellipsoid_cut_deprior".
std::string_view MapAidedMethodName(MapAidedMethod method);
/// Inverse of MapAidedMethodName; nullopt for an unknown name.
std::optional<MapAidedMethod> MapAidedMethodFromName(std::string_view name);

/// The range sigma of the echoes estimated online from their innovations (the canopy's leaf
/// roughness; range_noise_estimator.hpp): map_aided.range_sigma_m is then the floor.
struct AdaptiveRangeSigmaConfig {
  bool enabled = true;
  /// The cap of the estimate, and the sigma used until min_echoes echoes are counted, m.
  double max_sigma_m = 0.05;
  int window_echoes = 200;  ///< echoes the estimate is the median of
  int min_echoes = 50;      ///< echoes counted before the first estimate (<= window_echoes)
};

/// Ultrasonic ranges against the row map (used only when a row map is attached to the filter).
/// The mounts (lever arm, beam direction) are the vehicle file's `ultrasonic` entries, by name.
struct MapAidedConfig {
  MapAidedMethod method = MapAidedMethod::kRange;
  /// 1-sigma of a range against the map: echo noise plus the map's own error (canopy roughness,
  /// polygon approximation of the outline), m.
  double range_sigma_m = 0.003;
  double cone_half_angle_rad = 0.1308996938995747;  ///< half aperture of the sound cone, in (0, pi/2)
  double max_range_m = 4.0;                         ///< the sensor's range limit, m
  double k_sigma = 3.0;  ///< slab d_m +- k sigma and k-sigma ellipse of the cut methods; candidate window
  /// Arc length over which a row outline's direction is averaged for the range model, > 0 (below the
  /// segment length: each segment's own direction), m; map_aided_ranging.hpp explains why.
  double row_smoothing_m = 2.0;
  double gate_probability = 0.9999;
  AdaptiveRangeSigmaConfig adaptive_range_sigma;
};

struct FilterConfig {
  std::string name = "default";
  ProcessNoise process_noise;
  SlipAwareOdometryConfig slip_aware_odometry;
  InitialisationConfig initialisation;
  GpsNoise gps;
  ImuNoise imu;
  WheelNoise wheels;
  SteeringNoise steering;
  VioNoise vio;
  MapAidedConfig map_aided;
  double max_prediction_step_s = 0.02;  ///< longer predictions are split into steps of at most this
  double max_prediction_gap_s = 5.0;    ///< a longer gap between messages re-initialises the filter
  /// A message more than this ahead of the filter's time is refused as a clock fault (one sensor's
  /// stamps offset), not predicted to; >= max_prediction_gap_s. Only a run of such messages with no
  /// message in between at the filter's time moves the filter to the new time base (VehicleEkf).
  double max_time_jump_s = 3600.0;
};

/// The horizontal 1-sigma (m) used for a fix of the given quality (kNone: not a fix; throws
/// std::invalid_argument).
double GpsSigma(const GpsNoise& noise, formats::GnssFixQuality fix, double receiver_sigma_horizontal_m);

class FilterConfigError : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

/// Why the configuration is unusable (naming the field), or nullopt.
std::optional<std::string> FilterConfigProblem(const FilterConfig& config);

/// Parses a filter document's text (no file: e.g. a configuration sent to the service inline) onto
/// the defaults; source_name appears in the messages. "extends" is refused (nothing to resolve it
/// against). Throws FilterConfigError.
FilterConfig ParseFilterConfig(std::string_view json_text, std::string_view source_name);
/// Parses the text of the filter file at `path` (already read by the caller), its "extends"
/// resolved against the file's directory. Throws FilterConfigError.
FilterConfig ParseFilterConfigFile(std::string_view json_text, const std::filesystem::path& path);
/// Reads and parses a filter file. Throws FilterConfigError (including for a missing file).
FilterConfig LoadFilterConfig(const std::filesystem::path& path);
/// The files a filter file is read from: its "extends" chain, base first, the file itself last.
/// Throws FilterConfigError.
std::vector<std::filesystem::path> FilterConfigFiles(const std::filesystem::path& path);

/// Every value of `config` as a complete filter file: canonical JSON (the file format's keys in
/// its order, two-space indent, numbers in their shortest round-trip form, a final newline).
/// Parsing it gives `config` back exactly. `rowloc config show` prints it; the service records
/// it in a session's journal metadata.
std::string FilterConfigJson(const FilterConfig& config);

}  // namespace rowloc::localization
