// Track slip of a skid-steer / tracked vehicle from measured pose and track speeds: the adaptive
// identity observer of Tazzari, Azzollini and Marconi (n.d.), eq. (8): the third slip model.
// Derivation, discretization and measurements: docs/localization-track-slip.md.
//
// Model, Tazzari et al. n.d. eq. (3)-(5): with the track (sprocket) speeds v_R = r omega_R, v_L = r omega_L and
// the slip coefficients eta = 1 - i of eq. (4) (i = 1 - V_t/(omega r), eq. (6)),
//   [x', y', theta']^T = Psi(theta, v) [eta_R, eta_L]^T,
//   Psi = [ cos(theta) v_R/2,  cos(theta) v_L/2 ;  sin(theta) v_R/2,  sin(theta) v_L/2 ;
//           v_R/(2d),         -v_L/(2d) ],
// where 2d is the track width: the distance between the track centre lines (Tazzari et al. n.d. §II: "d is
// half the distance between the center lines"). rowloc body frame: x forward, y left, right track
// at y = -d, so a positive yaw rate (left turn) needs eta_R v_R > eta_L v_L.
// Observer, eq. (8), with the observation error e = (x - x^, y - y^, wrap(theta - theta^)) of eq. (9):
//   [x^, y^, theta^]' = Psi(theta, v) eta^ + L e,     eta^' = Lambda Psi(theta, v)^T e,
// L = diag(l1, l2, l3) > 0, Lambda = diag(lambda_R, lambda_L) > 0. The regressor uses the
// *measured* theta, so the error system (10) is linear:  e' = -L e - Psi eta~,  eta~' = Lambda Psi^T e
// (eta~ = eta^ - eta). Lyapunov function: V = 1/2 (e^T e + eta~^T Lambda^-1 eta~), V' = -e^T L e.
// (Tazzari et al. n.d. write e^T L^-1 e: its cross terms only cancel for L = I; with L = I both agree. Its
// eq. (11) also has the sign of the first two entries of the second row flipped; the matrix
// Phi Phi^T printed after eq. (14) is that of the corrected regressor. det(Psi^T Psi) =
// v_R^2 v_L^2 / (4 d^2): both eta are identifiable whenever both tracks move, on a straight line too.)
//
// Discretization (exact for any step, hence unconditionally stable): between two measurements at
// t_k and t_k+1 = t_k + h the track speeds are held at their mean and the heading is taken to change
// at a constant rate (Assumption 1: constant speeds and slip => an arc). Psi is replaced by its
// mean over the arc (cos and sin of the mid heading times sinc(dtheta/2)), which makes the chord
// exact: x_k+1 - x_k = h Psi_mean eta on exact data. Measured pose is interpolated linearly along
// the chord, so z = (e, eta^) obeys the constant linear system z' = A z + b with
//   A = [ -L, -Psi_mean ; Lambda Psi_mean^T, 0 ],   b = ((x_k+1 - x_k)/h, 0),
// which is integrated exactly by the matrix exponential of [A h, b h; 0, 0] (6 x 6). Along the
// exact flow V cannot grow for any h (V' = -e^T L e), so V is non-increasing at the sample times
// on exact arc data whatever the rate, and errors are never amplified (the homogeneous part is
// non-expansive in the V-norm). The heading change dtheta is the 2 pi branch of the measured one
// nearest to the change predicted by eta^, moved into the range reachable with eta in the box when
// a branch lies there; it is unique when h (eta_max - eta_min)(|v_R| + |v_L|) / (2d) < 2 pi (default
// box, 1 m/s tracks, 2d = 1.1 m: h < 1.7 s), beyond that a turn of more than pi per step relies on
// eta^ predicting it to within pi.
// Projection: eta^ is clamped into [eta_min, eta_max] after every step; for the diagonal Lambda^-1
// norm that is the Euclidean projection onto the box, so it cannot increase V when the true eta
// lies in the box. Steps longer than max_step_s are gaps: the pose state restarts at the
// measurement and eta^ is kept (one chord over a long gap is a guess, not a measurement).
#pragma once

#include <Eigen/Core>

#include <optional>
#include <string>

namespace rowloc::localization {

/// Parameters of TrackSlipObserver; TrackSlipObserverConfigProblem() checks them.
struct TrackSlipObserverConfig {
  double track_width_m = 1.1;  ///< 2d: distance between the track centre lines (> 0)
  /// diag(L) = (l1, l2, l3) for (x, y, theta) errors, 1/s, > 0. Tazzari et al. n.d. §V used the identity.
  Eigen::Vector3d injection_gains_per_s = Eigen::Vector3d::Ones();
  /// diag(Lambda) = (lambda_R, lambda_L), > 0 (units 1/m^2 against the position errors).
  Eigen::Vector2d adaptation_gains = Eigen::Vector2d::Ones();
  double eta_min = 0.0;  ///< projection box [eta_min, eta_max] of eta^, within eq. (4)'s [0, 2]
  double eta_max = 2.0;
  double initial_eta_right = 1.0;  ///< eta^ at start and after Reset(), inside the box
  double initial_eta_left = 1.0;
  /// Longest step integrated (> 0); longer steps are gaps (pose restarts, eta^ kept). nullopt:
  /// integrate any step (still stable, but one chord then dominates eta^).
  std::optional<double> max_step_s = 2.0;
};

/// Why the config is unusable (names the field), or nullopt.
std::optional<std::string> TrackSlipObserverConfigProblem(const TrackSlipObserverConfig& config);

/// Track speeds beyond this are rejected as corrupt (no tracked vehicle is that fast).
inline constexpr double kMaxTrackSpeedMps = 100.0;

/// One measurement: planar pose of the reference point (midway between the tracks) in the world
/// frame and the two track speeds r omega (sprocket speed times sprocket radius, signed).
struct TrackSlipInput {
  double time_s = 0.0;
  double x_m = 0.0;
  double y_m = 0.0;
  double theta_rad = 0.0;  ///< heading from +x (East), counter-clockwise; any finite value
  double v_right_mps = 0.0;  ///< |v| <= kMaxTrackSpeedMps
  double v_left_mps = 0.0;
};

/// What Update() did with a measurement.
enum class TrackSlipStep {
  kInitialised,   ///< first measurement (or first after Reset): pose state set to it
  kIntegrated,    ///< observer integrated from the previous time to this one
  kSameTime,      ///< time equal to the previous one: ignored (no-op)
  kGapRestarted,  ///< step longer than max_step_s: pose state restarted, eta^ kept
};

class TrackSlipObserver {
 public:
  /// Throws std::invalid_argument with TrackSlipObserverConfigProblem()'s reason.
  explicit TrackSlipObserver(const TrackSlipObserverConfig& config = {});

  /// Integrates the observer to input.time_s. Throws std::invalid_argument naming the field for a
  /// non-finite value, a track speed beyond kMaxTrackSpeedMps or a time before the previous one
  /// (and for a step whose numbers overflow, e.g. positions near 1e308); the state is then unchanged.
  TrackSlipStep Update(const TrackSlipInput& input);

  /// Back to the uninitialised state with eta^ = the configured initial values.
  void Reset();

  bool initialised() const { return initialised_; }
  double eta_right() const { return eta_hat_.x(); }
  double eta_left() const { return eta_hat_.y(); }
  /// Track slip i = 1 - eta (Tazzari et al. n.d. eq. (4)); the sim's truth `slip` for tracks.
  double slip_right() const { return 1.0 - eta_hat_.x(); }
  double slip_left() const { return 1.0 - eta_hat_.y(); }
  /// Observer state (x^_m, y^_m, theta^_rad), theta^ wrapped to (-pi, pi]; zero before the first update.
  const Eigen::Vector3d& state() const { return pose_hat_; }
  /// e of eq. (9) at the last time (e_theta wrapped to (-pi, pi]); zero after initialisation.
  const Eigen::Vector3d& observation_error() const { return error_; }
  /// Time of the last accepted measurement, nullopt before the first.
  std::optional<double> last_time_s() const;
  const TrackSlipObserverConfig& config() const { return config_; }

  /// V = 1/2 (e^T e + eta~^T Lambda^-1 eta~) for a given true eta (diagnostics and tests).
  double Lyapunov(double true_eta_right, double true_eta_left) const;

 private:
  void Initialise(const TrackSlipInput& input);
  void Integrate(const TrackSlipInput& input, double step_s);
  double TurnOverStep(const TrackSlipInput& input, double step_s, double v_right, double v_left) const;

  TrackSlipObserverConfig config_;
  bool initialised_ = false;
  TrackSlipInput last_input_;
  Eigen::Vector3d pose_hat_ = Eigen::Vector3d::Zero();
  Eigen::Vector3d error_ = Eigen::Vector3d::Zero();
  Eigen::Vector2d eta_hat_;
};

}  // namespace rowloc::localization
