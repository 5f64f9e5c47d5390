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
//
// Map-aided initialisation (initialisation.map_heading_sigma_rad > 0 and a row map attached): in a
// lane the vehicle drives along the rows, so the GNSS need only tell which of the lane's two
// directions it drives in. When the mean of the pending fixes lies in a lane of the map
// (RowMapRanging::LaneDirectionAt: rows on both sides within kLaneHalfWidthM, parallel within
// kLaneTurnRad) with unit direction t, the fixes' coordinates along t are regressed on the distance
// the wheels rolled (least squares, slope d): |d| must be at least kDirectionSigmas of its standard
// error (sigma_fix / sqrt(sum (rolled - mean)^2)) and between kMinChordFraction and
// kMaxChordFraction (the vehicle moves along the lane), and the slope across the lane below
// kMaxAcrossSlope. The heading is then t or -t (by d's sign; reversed when the wheels turn
// backwards), with sigma map_heading_sigma_rad. With 5 fixes a second and 0.8 m sigma this needs
// about 3-4 m of driving instead of the 10-sigma (8 m) baseline. When the baseline comes first and
// its end is in a lane, its course (0.14 rad) is snapped to the lane's direction within
// kMaxCourseOffsetRad, with the same sigma.
#include "rowloc/localization/vehicle_ekf.hpp"

#include <algorithm>
#include <cmath>
#include <numbers>
#include <sstream>
#include <vector>

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
/// Map-aided initialisation: the slope along the lane in its standard errors; the lane's rows within
/// this on each side, m; their directions within this of each other, rad; the slope across the lane
/// at most this; fixes at least this many.
constexpr double kDirectionSigmas = 6.0;
constexpr double kLaneHalfWidthM = 5.0;
constexpr double kLaneTurnRad = 0.35;
constexpr double kMaxAcrossSlope = 0.3;
/// The long baseline's course snaps to the lane's direction when within this of it, rad.
constexpr double kMaxCourseOffsetRad = 0.35;
constexpr std::size_t kMinLaneFixes = 5;

/// The wheels turn backwards: their mean speed (rad/s, any order) is negative. A course over
/// ground is then the heading reversed.
bool RollingBackwards(const std::vector<double>& wheel_speeds_radps) {
  double mean_speed = 0.0;
  for (const double w : wheel_speeds_radps) mean_speed += w / static_cast<double>(wheel_speeds_radps.size());
  return mean_speed < 0.0;
}

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

const VehicleEkf::PendingFix* VehicleEkf::FindAnchor(const PendingFix& current, double baseline_m) const {
  for (std::size_t a = 0; a < pending_fixes_.size(); ++a) {
    const PendingFix& candidate = pending_fixes_[a];
    if ((current.antenna_enu - candidate.antenna_enu).norm() < baseline_m || !FixesAgree(candidate, current)) continue;
    for (std::size_t m = a + 1; m < pending_fixes_.size(); ++m) {
      if (FixesAgree(candidate, pending_fixes_[m]) && FixesAgree(pending_fixes_[m], current)) return &candidate;
    }
  }
  return nullptr;
}

double VehicleEkf::MeanSteering() const {
  double mean = 0.0;
  int steered = 0;
  for (const auto& angle : last_steering_rad_) {
    if (angle) mean += *angle, ++steered;
  }
  return steered > 0 ? mean / steered : 0.0;
}

double VehicleEkf::CourseToHeading(const Eigen::Vector2d& moved) const {
  // Course over ground -> heading: reversed when the wheels turn backwards, minus the mean steering
  // angle (a crabbing swerve robot moves at delta to its heading).
  double heading = std::atan2(moved.y(), moved.x()) - MeanSteering();
  if (RollingBackwards(last_speed_radps_)) heading += std::numbers::pi;
  return WrapAngle(heading);
}

std::optional<double> VehicleEkf::LaneHeading(const PendingFix& current) const {
  if (pending_fixes_.size() + 1 < kMinLaneFixes || !odometry_time_s_) return std::nullopt;
  std::vector<const PendingFix*> fixes;
  for (const PendingFix& f : pending_fixes_) fixes.push_back(&f);
  fixes.push_back(&current);
  Eigen::Vector2d mean_position = Eigen::Vector2d::Zero();
  double mean_rolled = 0.0, sigma = 0.0;
  for (const PendingFix* f : fixes) {
    mean_position += f->antenna_enu / static_cast<double>(fixes.size());
    mean_rolled += f->travelled_m / static_cast<double>(fixes.size());
    sigma = std::max(sigma, f->sigma_m);
  }
  const RowMapRanging& ranging = *map_aided_.ranging();
  const auto lane = ranging.LaneDirectionAt(mean_position, kLaneHalfWidthM, kLaneTurnRad);
  if (!lane || !ranging.LaneDirectionAt(current.antenna_enu, kLaneHalfWidthM, kLaneTurnRad)) return std::nullopt;
  const Eigen::Vector2d along(std::cos(*lane), std::sin(*lane));
  const Eigen::Vector2d across(-along.y(), along.x());
  // Least-squares slopes of the along- and across-lane coordinates on the distance rolled.
  double spread = 0.0, along_slope = 0.0, across_slope = 0.0;
  for (const PendingFix* f : fixes) {
    const double r = f->travelled_m - mean_rolled;
    const Eigen::Vector2d p = f->antenna_enu - mean_position;
    spread += r * r;
    along_slope += r * along.dot(p);
    across_slope += r * across.dot(p);
  }
  if (!(spread > 0.0)) return std::nullopt;
  along_slope /= spread;
  across_slope /= spread;
  const double slope_sigma = sigma / std::sqrt(spread);
  const double speed = std::abs(along_slope);
  if (speed < kDirectionSigmas * slope_sigma || speed < kMinChordFraction || speed > kMaxChordFraction ||
      std::abs(across_slope) > kMaxAcrossSlope) {
    return std::nullopt;
  }
  double heading = along_slope > 0.0 ? *lane : *lane + std::numbers::pi;
  if (RollingBackwards(last_speed_radps_)) heading += std::numbers::pi;
  return WrapAngle(heading);
}

std::optional<std::string> VehicleEkf::TryInitialise(const formats::GpsMessage& gps, const Eigen::Vector2d& antenna) {
  // The course of the baseline has an error of about sqrt(2) sigma / |baseline| rad: the baseline
  // must also be long against the fix noise (10 sigma: 0.14 rad, inside heading_sigma_rad's default).
  const double fix_sigma = GpsSigma(config_.gps, gps.fix, gps.position->sigma_horizontal_m);
  const PendingFix current{gps.time_s, antenna, fix_sigma, travelled_m_};
  const double map_sigma = config_.initialisation.map_heading_sigma_rad;
  std::optional<double> lane_heading;
  if (map_sigma > 0.0 && map_aided_.ranging() != nullptr) lane_heading = LaneHeading(current);
  const double baseline = std::max(config_.initialisation.heading_baseline_m, kBaselineSigmas * fix_sigma);
  const PendingFix* anchor = lane_heading ? &pending_fixes_.front() : FindAnchor(current, baseline);
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
  double heading = lane_heading ? *lane_heading : CourseToHeading(moved);
  bool snapped = false;  // the long baseline's course in a lane: the lane's direction instead
  if (!lane_heading && map_sigma > 0.0 && map_aided_.ranging() != nullptr) {
    const auto lane = map_aided_.ranging()->LaneDirectionAt(antenna, kLaneHalfWidthM, kLaneTurnRad);
    if (lane) {
      const double along =
          std::abs(WrapAngle(heading - *lane)) < 0.5 * std::numbers::pi ? *lane : WrapAngle(*lane + std::numbers::pi);
      if (std::abs(WrapAngle(heading - along)) < kMaxCourseOffsetRad) heading = along, snapped = true;
    }
  }
  const double mean_steering = MeanSteering();
  const double c = std::cos(heading), s = std::sin(heading);
  const Eigen::Vector2d& l = vehicle_.gnss_antenna.position_m.head<2>();
  const Eigen::Vector2d reference = antenna - Eigen::Vector2d(c * l.x() - s * l.y(), s * l.x() + c * l.y());
  const double sigma = fix_sigma;
  const double heading_sigma = lane_heading || snapped ? map_sigma : config_.initialisation.heading_sigma_rad;
  Eigen::Matrix3d covariance = Eigen::Vector3d(sigma * sigma, sigma * sigma, heading_sigma * heading_sigma).asDiagonal();
  InitialiseState(gps.time_s, Eigen::Vector3d(reference.x(), reference.y(), heading), covariance, true);
  // Initial speed from the encoders (mean wheel-centre speed), along the mean steering direction.
  double speed = 0.0;
  for (std::size_t i = 0; i < last_speed_radps_.size(); ++i) {
    speed += last_speed_radps_[i] * vehicle_.wheels[i].nominal_radius_m / static_cast<double>(last_speed_radps_.size());
  }
  x_(L::kVx) = speed * std::cos(mean_steering);
  x_(L::kVy) = speed * std::sin(mean_steering);
  std::ostringstream notice;
  notice << "initialised at t=" << gps.time_s << " s: heading " << heading << " rad from ";
  if (lane_heading) {
    notice << "the lane of the row map, its direction from " << waited << " fixes over "
           << current.travelled_m - pending_fixes_.front().travelled_m << " m of driving";
    return notice.str();
  }
  if (snapped) notice << "the lane of the row map along the course of ";
  notice << "a GNSS baseline of " << moved.norm() << " m (consensus of " << waited << " fixes, " << discarded
         << " disagreeing with the others or the odometry discarded)";
  return notice.str();
}

}  // namespace rowloc::localization
