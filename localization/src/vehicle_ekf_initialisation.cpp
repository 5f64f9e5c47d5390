// VehicleEkf: the initialisation from a consensus of GNSS fixes (vehicle_ekf.hpp;
// docs/localization-filter.md §2).
//
// The heading is not observable from one fix: the filter takes the course of the antenna's
// displacement between an anchor fix a and the current fix c, once |c - a| reaches the heading
// baseline. A single outlier taken as the anchor (a fix 111 m off) used to become the initial
// heading, with a covariance that then gated every good fix out. So the anchor and the current fix
// must agree by consensus (a RANSAC-like minimal check; Fischler & Bolles 1981): some pending fix m
// between them must agree with both, and every pair must agree with each other within their sigmas
// and with the odometry rolled between them (or, without wheel speeds, with a ground speed no
// robot exceeds). A fix that agrees with no other is never used; the notice counts the fixes
// discarded.
#include "rowloc/localization/vehicle_ekf.hpp"

#include <algorithm>
#include <cmath>
#include <numbers>
#include <sstream>

namespace rowloc::localization {

using L = StateLayout;

namespace {

/// Minimum GNSS baseline for the initial heading, in fix sigmas.
constexpr double kBaselineSigmas = 10.0;
/// Fixes kept while waiting; when full, every second one is dropped (the oldest and newest stay), so
/// the fixes span the whole wait at a bounded cost (the consensus search is quadratic in them).
constexpr std::size_t kMaxPendingFixes = 32;
/// Agreement of two fixes: |displacement| within [kMinChordFraction s - tol, kMaxChordFraction s + tol]
/// for an odometry distance s (the chord of a curve is shorter than its arc; wheels slip, a radius
/// may be off by tens of percent), tol = 3 sigma of the difference + kAgreementMarginM.
constexpr double kMinChordFraction = 0.5;
constexpr double kMaxChordFraction = 1.5;
constexpr double kAgreementMarginM = 0.2;
/// Without wheel speeds: no field robot moves faster than this, m/s.
constexpr double kMaxGroundSpeedMps = 30.0;

}  // namespace

bool VehicleEkf::FixesAgree(const PendingFix& a, const PendingFix& b) const {
  const double chord = (b.antenna_enu - a.antenna_enu).norm();
  const double tolerance = 3.0 * std::hypot(a.sigma_m, b.sigma_m) + kAgreementMarginM;
  if (odometry_time_s_) {
    const double rolled = std::abs(b.travelled_m - a.travelled_m);
    return chord <= kMaxChordFraction * rolled + tolerance && chord >= kMinChordFraction * rolled - tolerance;
  }
  return chord <= kMaxGroundSpeedMps * std::abs(b.time_s - a.time_s) + tolerance;
}

void VehicleEkf::AccumulateOdometry(double time_s) {
  if (odometry_time_s_ && !last_speed_radps_.empty()) {
    const double dt = time_s - *odometry_time_s_;
    double speed = 0.0;  // mean wheel-centre speed from the nominal radii
    for (std::size_t i = 0; i < last_speed_radps_.size(); ++i) {
      speed += last_speed_radps_[i] * vehicle_.wheels[i].nominal_radius_m;
    }
    speed /= static_cast<double>(last_speed_radps_.size());
    if (dt > 0.0 && dt <= config_.max_prediction_gap_s) travelled_m_ += std::abs(speed) * dt;
  }
  odometry_time_s_ = time_s;
}

std::optional<std::string> VehicleEkf::TryInitialise(const formats::GpsMessage& gps, const Eigen::Vector2d& antenna) {
  // The course of the baseline has an error of about sqrt(2) sigma / |baseline| rad: the baseline
  // must also be long against the fix noise (10 sigma: 0.14 rad, inside heading_sigma_rad's default).
  const double fix_sigma = GpsSigma(config_.gps, gps.fix, gps.position->sigma_horizontal_m);
  const PendingFix current{gps.time_s, antenna, fix_sigma, travelled_m_};
  const double baseline = std::max(config_.initialisation.heading_baseline_m, kBaselineSigmas * fix_sigma);
  const PendingFix* anchor = nullptr;
  for (std::size_t a = 0; a < pending_fixes_.size() && !anchor; ++a) {
    const PendingFix& candidate = pending_fixes_[a];
    if ((antenna - candidate.antenna_enu).norm() < baseline || !FixesAgree(candidate, current)) continue;
    for (std::size_t m = a + 1; m < pending_fixes_.size(); ++m) {
      if (FixesAgree(candidate, pending_fixes_[m]) && FixesAgree(pending_fixes_[m], current)) {
        anchor = &candidate;
        break;
      }
    }
  }
  if (!anchor) {
    if (pending_fixes_.size() == kMaxPendingFixes) {
      std::vector<PendingFix> kept;
      for (std::size_t i = 0; i < pending_fixes_.size(); i += 2) kept.push_back(pending_fixes_[i]);
      pending_fixes_ = std::move(kept);
    }
    pending_fixes_.push_back(current);
    return std::nullopt;
  }
  const Eigen::Vector2d moved = antenna - anchor->antenna_enu;
  const auto discarded = static_cast<std::size_t>(std::count_if(
      pending_fixes_.begin(), pending_fixes_.end(),
      [&](const PendingFix& f) { return !FixesAgree(f, current); }));
  const std::size_t waited = pending_fixes_.size() + 1;
  // Course over ground -> heading: reversed when the wheels turn backwards, minus the mean steering
  // angle (a crabbing swerve robot moves at delta to its heading).
  double mean_speed = 0.0, mean_steering = 0.0;
  for (const double w : last_speed_radps_) mean_speed += w / static_cast<double>(last_speed_radps_.size());
  int steered = 0;
  for (const auto& angle : last_steering_rad_) {
    if (angle) mean_steering += *angle, ++steered;
  }
  if (steered > 0) mean_steering /= steered;
  double heading = std::atan2(moved.y(), moved.x()) - mean_steering;
  if (mean_speed < 0.0) heading += std::numbers::pi;
  heading = WrapAngle(heading);
  const double c = std::cos(heading), s = std::sin(heading);
  const Eigen::Vector2d& l = vehicle_.gnss_antenna.position_m.head<2>();
  const Eigen::Vector2d reference = antenna - Eigen::Vector2d(c * l.x() - s * l.y(), s * l.x() + c * l.y());
  const double sigma = fix_sigma;
  Eigen::Matrix3d covariance = Eigen::Vector3d(sigma * sigma, sigma * sigma,
                                               std::pow(config_.initialisation.heading_sigma_rad, 2)).asDiagonal();
  InitialiseState(gps.time_s, Eigen::Vector3d(reference.x(), reference.y(), heading), covariance, true);
  // Initial speed from the encoders (mean wheel-centre speed), along the mean steering direction.
  double speed = 0.0;
  for (std::size_t i = 0; i < last_speed_radps_.size(); ++i) {
    speed += last_speed_radps_[i] * vehicle_.wheels[i].nominal_radius_m / static_cast<double>(last_speed_radps_.size());
  }
  x_(L::kVx) = speed * std::cos(mean_steering);
  x_(L::kVy) = speed * std::sin(mean_steering);
  std::ostringstream notice;
  notice << "initialised at t=" << gps.time_s << " s: heading " << heading << " rad from a GNSS baseline of "
         << moved.norm() << " m (consensus of " << waited << " fixes, " << discarded
         << " disagreeing with the others or the odometry discarded)";
  return notice.str();
}

}  // namespace rowloc::localization
