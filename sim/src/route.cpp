#include "rowloc/sim/route.hpp"

#include <algorithm>
#include <array>
#include <cmath>
#include <numbers>
#include <stdexcept>

namespace rowloc::sim {
namespace {

constexpr double kMaxAbsCurvature_per_m = 10.0;
constexpr double kMinPieceLength_m = 1e-6;
constexpr double kMaxPieceLength_m = 1e5;
constexpr double kMaxTotalLength_m = 1e6;
constexpr std::size_t kMaxPieces = 100000;
constexpr double kMaxSpeedOrAccel = 100.0;
constexpr double kMaxDwell_s = 1e6;
/// Clothoid sub-intervals: |kappa| h and |kappa'| h^2 at most this (heading change <= 0.15 rad), so
/// that 4-point Gauss-Legendre (error ~ 3e-7 (h max|phi'|)^8 h) is exact to ~1e-15 m per sub-interval.
constexpr double kQuadratureTurn_rad = 0.1;
/// Longest table sub-interval of a clothoid, and the speed-profile segment length on clothoids.
constexpr double kMaxClothoidStep_m = 1.0;
constexpr double kClothoidSegment_m = 0.05;
constexpr int kMaxSegmentsPerPiece = 4096;
/// Most clothoid table nodes plus speed segments over the whole route (bounds memory to ~1 GB).
constexpr double kMaxSubdivisions = 1e7;

/// 4-point Gauss-Legendre nodes and weights on [-1, 1] (positive half; symmetric).
constexpr std::array<double, 2> kGaussNodes = {0.3399810435848563, 0.8611363115940526};
constexpr std::array<double, 2> kGaussWeights = {0.6521451548625461, 0.3478548451374538};

double WrapAngle(double angle_rad) {
  const double wrapped = std::remainder(angle_rad, 2.0 * std::numbers::pi);
  return wrapped <= -std::numbers::pi ? std::numbers::pi : wrapped;
}

bool InRange(double value, double low, double high) { return std::isfinite(value) && value >= low && value <= high; }

double CurvatureRate(const PathPiece& piece) {
  return (piece.end_curvature_per_m - piece.start_curvature_per_m) / piece.length_m;
}

/// Number of table sub-intervals of a piece: 1 for lines and arcs; for clothoids enough that
/// |kappa| h <= kQuadratureTurn, |kappa'| h^2 <= kQuadratureTurn and h <= kMaxClothoidStep.
double SubIntervalCount(const PathPiece& piece) {
  const double rate = CurvatureRate(piece);
  if (rate == 0.0) return 1.0;
  const double max_abs_kappa = std::max(std::abs(piece.start_curvature_per_m), std::abs(piece.end_curvature_per_m));
  const double step_m = std::min({kMaxClothoidStep_m, kQuadratureTurn_rad / std::max(max_abs_kappa, 1e-12),
                                  std::sqrt(kQuadratureTurn_rad / std::abs(rate))});
  return std::max(1.0, std::ceil(piece.length_m / step_m - 1e-9));
}

/// Number of speed-profile segments of a piece (one for lines and arcs).
int SegmentCount(const PathPiece& piece) {
  if (CurvatureRate(piece) == 0.0) return 1;
  return static_cast<int>(std::clamp(std::ceil(piece.length_m / kClothoidSegment_m), 1.0,
                                     static_cast<double>(kMaxSegmentsPerPiece)));
}

std::optional<std::string> PiecesProblem(const std::vector<PathPiece>& pieces) {
  if (pieces.empty()) return "pieces: the route needs at least one piece";
  if (pieces.size() > kMaxPieces) return "pieces: more than 100000 pieces";
  double total_m = 0.0, subdivisions = 0.0;
  for (std::size_t i = 0; i < pieces.size(); ++i) {
    const PathPiece& p = pieces[i];
    const std::string where = "pieces[" + std::to_string(i) + "]";
    if (!InRange(p.length_m, kMinPieceLength_m, kMaxPieceLength_m))
      return where + ".length_m must be in [1e-6, 1e5] m";
    if (!InRange(std::abs(p.start_curvature_per_m), 0.0, kMaxAbsCurvature_per_m) ||
        !InRange(std::abs(p.end_curvature_per_m), 0.0, kMaxAbsCurvature_per_m))
      return where + ": curvatures must be finite with |kappa| <= 10 /m";
    total_m += p.length_m;
    subdivisions += SubIntervalCount(p) + SegmentCount(p);
  }
  if (total_m > kMaxTotalLength_m) return "pieces: total length must be <= 1e6 m";
  if (subdivisions > kMaxSubdivisions)
    return "pieces: the clothoids need more than 1e7 sub-intervals (shorter clothoids or smaller curvature rates)";
  return std::nullopt;
}

std::optional<std::string> StartProblem(const Eigen::Vector2d& position_m, double heading_rad) {
  if (!position_m.allFinite()) return "start_position_m must be finite";
  if (!std::isfinite(heading_rad)) return "start_heading_rad must be finite";
  return std::nullopt;
}

void ThrowIf(const std::optional<std::string>& problem) {
  if (problem) throw std::invalid_argument("RouteSpec: " + *problem);
}

const RouteSpec& Validated(const RouteSpec& spec) {
  ThrowIf(RouteSpecProblem(spec));
  return spec;
}

/// A stretch of path with one speed cap (v_lim over the stretch).
struct Segment {
  double start_m, length_m, cap_mps;
};

double CurvatureCap(double abs_curvature_per_m, const RouteSpec& spec) {
  if (abs_curvature_per_m <= 0.0) return spec.cruise_speed_mps;
  return std::min(spec.cruise_speed_mps, std::sqrt(spec.max_lateral_accel_mps2 / abs_curvature_per_m));
}

std::vector<Segment> SpeedSegments(const RouteSpec& spec) {
  std::vector<Segment> segments;
  double station_m = 0.0;
  for (const PathPiece& piece : spec.pieces) {
    const double rate = CurvatureRate(piece);
    const int count = SegmentCount(piece);
    const double step_m = piece.length_m / count;
    for (int i = 0; i < count; ++i) {
      const double k0 = piece.start_curvature_per_m + rate * step_m * i;
      const double k1 = i + 1 == count ? piece.end_curvature_per_m : k0 + rate * step_m;
      segments.push_back({station_m + step_m * i, step_m, CurvatureCap(std::max(std::abs(k0), std::abs(k1)), spec)});
    }
    station_m += piece.length_m;
  }
  return segments;
}

/// Node speeds: limited by both neighbouring caps, 0 at the ends, then forward/backward passes.
std::vector<double> NodeSpeeds(const std::vector<Segment>& segments, double accel_mps2) {
  const std::size_t n = segments.size();
  std::vector<double> speed(n + 1, 0.0);
  for (std::size_t i = 1; i < n; ++i) speed[i] = std::min(segments[i - 1].cap_mps, segments[i].cap_mps);
  for (std::size_t i = 1; i <= n; ++i)
    speed[i] = std::min(speed[i], std::sqrt(speed[i - 1] * speed[i - 1] + 2 * accel_mps2 * segments[i - 1].length_m));
  for (std::size_t i = n; i-- > 0;)
    speed[i] = std::min(speed[i], std::sqrt(speed[i + 1] * speed[i + 1] + 2 * accel_mps2 * segments[i].length_m));
  return speed;
}

}  // namespace

std::optional<std::string> RouteSpecProblem(const RouteSpec& spec) {
  if (auto problem = StartProblem(spec.start_position_m, spec.start_heading_rad)) return problem;
  if (auto problem = PiecesProblem(spec.pieces)) return problem;
  if (!InRange(spec.cruise_speed_mps, 0.0, kMaxSpeedOrAccel) || spec.cruise_speed_mps == 0.0)
    return "cruise_speed_mps must be in (0, 100] m/s";
  if (!InRange(spec.max_accel_mps2, 0.0, kMaxSpeedOrAccel) || spec.max_accel_mps2 == 0.0)
    return "max_accel_mps2 must be in (0, 100] m/s^2";
  if (!InRange(spec.max_lateral_accel_mps2, 0.0, kMaxSpeedOrAccel) || spec.max_lateral_accel_mps2 == 0.0)
    return "max_lateral_accel_mps2 must be in (0, 100] m/s^2";
  if (!InRange(spec.start_dwell_s, 0.0, kMaxDwell_s)) return "start_dwell_s must be in [0, 1e6] s";
  if (!InRange(spec.end_dwell_s, 0.0, kMaxDwell_s)) return "end_dwell_s must be in [0, 1e6] s";
  return std::nullopt;
}

// ---------------------------------------------------------------------------------------------
// PathGeometry

PathGeometry::PathGeometry(const Eigen::Vector2d& start_position_m, double start_heading_rad,
                           const std::vector<PathPiece>& pieces) {
  ThrowIf(StartProblem(start_position_m, start_heading_rad));
  ThrowIf(PiecesProblem(pieces));
  Node node{0.0, 0.0, 0.0, start_heading_rad, 0.0, 0.0, start_position_m, true};
  for (const PathPiece& piece : pieces) {
    const double rate = CurvatureRate(piece);
    const int count = static_cast<int>(SubIntervalCount(piece));
    const double sub_m = piece.length_m / count;
    const double piece_start_m = node.station_m;
    nodes_.reserve(nodes_.size() + static_cast<std::size_t>(count));
    for (int i = 0; i < count; ++i) {
      node.piece_start = i == 0;
      node.station_m = piece_start_m + sub_m * i;
      node.curvature_per_m = piece.start_curvature_per_m + rate * sub_m * i;
      node.curvature_rate_per_m2 = rate;
      node.cos_heading = std::cos(node.heading_rad);
      node.sin_heading = std::sin(node.heading_rad);
      nodes_.push_back(node);
      node.position_m = node.position_m + Advance(node, sub_m);
      node.heading_rad += node.curvature_per_m * sub_m + 0.5 * rate * sub_m * sub_m;
    }
    node.station_m = piece_start_m + piece.length_m;
  }
  length_m_ = node.station_m;
}

Eigen::Vector2d PathGeometry::Advance(const Node& node, double delta_m) {
  const double k = node.curvature_per_m;
  const double rate = node.curvature_rate_per_m2;
  // Displacement in the node's tangent frame, then rotated by the node heading.
  Eigen::Vector2d local;
  if (rate == 0.0) {
    const double turn = k * delta_m;
    if (turn == 0.0) {
      local = {delta_m, 0.0};
    } else {  // chord of the arc: (sin(k d), 1 - cos(k d)) / k = 2 sin(k d / 2) (cos(k d / 2), sin(k d / 2)) / k
      const double half_sin = std::sin(0.5 * turn);
      const double half_cos = std::cos(0.5 * turn);
      local = (2.0 * half_sin / k) * Eigen::Vector2d(half_cos, half_sin);
    }
  } else {
    local.setZero();
    const double half = 0.5 * delta_m;
    for (std::size_t i = 0; i < kGaussNodes.size(); ++i) {
      for (const double sign : {-1.0, 1.0}) {
        const double x = half + sign * half * kGaussNodes[i];
        const double phi = k * x + 0.5 * rate * x * x;
        local += kGaussWeights[i] * Eigen::Vector2d(std::cos(phi), std::sin(phi));
      }
    }
    local *= half;
  }
  const double c = node.cos_heading;
  const double s = node.sin_heading;
  return {c * local.x() - s * local.y(), s * local.x() + c * local.y()};
}

PathGeometry::Pose PathGeometry::At(double station_m) const {
  const double s = std::clamp(station_m, 0.0, length_m_);
  auto it = std::upper_bound(nodes_.begin(), nodes_.end(), s,
                             [](double value, const Node& n) { return value < n.station_m; });
  const Node& node = *std::prev(it == nodes_.begin() ? std::next(it) : it);
  const double delta_m = s - node.station_m;
  Pose pose;
  pose.position_m = node.position_m + Advance(node, delta_m);
  pose.heading_rad =
      node.heading_rad + node.curvature_per_m * delta_m + 0.5 * node.curvature_rate_per_m2 * delta_m * delta_m;
  pose.curvature_per_m = node.curvature_per_m + node.curvature_rate_per_m2 * delta_m;
  pose.curvature_rate_per_m2 = node.curvature_rate_per_m2;
  return pose;
}

std::vector<double> PathGeometry::PieceStarts() const {
  std::vector<double> starts;
  for (const Node& node : nodes_)
    if (node.piece_start) starts.push_back(node.station_m);
  return starts;
}

// ---------------------------------------------------------------------------------------------
// Route

Route::Route(RouteSpec spec)
    : spec_(Validated(spec)), geometry_(spec_.start_position_m, spec_.start_heading_rad, spec_.pieces) {
  BuildPhases();
}

void Route::BuildPhases() {
  const std::vector<Segment> segments = SpeedSegments(spec_);
  const std::vector<double> speed = NodeSpeeds(segments, spec_.max_accel_mps2);
  const double a = spec_.max_accel_mps2;
  double time_s = spec_.start_dwell_s;
  auto add = [&](double station_m, double v0, double accel, double duration_s) {
    if (!(duration_s > 0.0)) return;
    phases_.push_back({time_s, station_m, v0, accel, duration_s});
    time_s += duration_s;
  };
  for (std::size_t i = 0; i < segments.size(); ++i) {
    const Segment& seg = segments[i];
    const double va = speed[i], vb = speed[i + 1], cap = seg.cap_mps;
    // v^2(s) = min(cap^2, va^2 + 2 a x, vb^2 + 2 a (l - x)): accelerate, cruise, decelerate.
    const double meet_m = std::clamp((vb * vb - va * va + 2 * a * seg.length_m) / (4 * a), 0.0, seg.length_m);
    double accel_m = meet_m, decel_m = seg.length_m - meet_m, cruise_m = 0.0;
    if (va * va + 2 * a * meet_m > cap * cap) {
      accel_m = std::clamp((cap * cap - va * va) / (2 * a), 0.0, seg.length_m);
      decel_m = std::clamp((cap * cap - vb * vb) / (2 * a), 0.0, seg.length_m - accel_m);
      cruise_m = seg.length_m - accel_m - decel_m;
    }
    const double peak = std::sqrt(va * va + 2 * a * accel_m);
    const double end = std::min(peak, vb);  // = sqrt(peak^2 - 2 a decel) exactly, without the cancellation
    add(seg.start_m, va, a, (peak - va) / a);
    if (cruise_m > 0.0) add(seg.start_m + accel_m, peak, 0.0, cruise_m / peak);
    add(seg.start_m + accel_m + cruise_m, peak, -a, (peak - end) / a);
  }
}

double Route::duration_s() const {
  const double motion_end_s = phases_.empty() ? spec_.start_dwell_s
                                              : phases_.back().start_time_s + phases_.back().duration_s;
  return motion_end_s + spec_.end_dwell_s;
}

const Route::Phase& Route::PhaseAt(double time_s) const {
  auto it = std::upper_bound(phases_.begin(), phases_.end(), time_s,
                             [](double t, const Phase& p) { return t < p.start_time_s; });
  return it == phases_.begin() ? *it : *std::prev(it);
}

RoutePoint Route::At(double time_s) const {
  if (std::isnan(time_s)) throw std::invalid_argument("Route::At: time is NaN");
  RoutePoint point;
  point.time_s = std::clamp(time_s, 0.0, duration_s());
  double station_m = 0.0;
  const Phase& last = phases_.back();
  if (point.time_s >= last.start_time_s + last.duration_s) {
    station_m = length_m();  // stopped at the end
  } else if (point.time_s >= spec_.start_dwell_s) {
    const Phase& phase = PhaseAt(point.time_s);
    const double tau = std::clamp(point.time_s - phase.start_time_s, 0.0, phase.duration_s);
    station_m = phase.start_station_m + phase.start_speed_mps * tau + 0.5 * phase.accel_mps2 * tau * tau;
    point.speed_mps = std::max(0.0, phase.start_speed_mps + phase.accel_mps2 * tau);
    point.accel_mps2 = phase.accel_mps2;
  }
  point.station_m = std::clamp(station_m, 0.0, length_m());
  const PathGeometry::Pose pose = geometry_.At(point.station_m);
  point.position_m = pose.position_m;
  point.heading_rad = WrapAngle(pose.heading_rad);
  point.curvature_per_m = pose.curvature_per_m;
  point.yaw_rate_radps = pose.curvature_per_m * point.speed_mps;
  point.yaw_accel_radps2 =
      pose.curvature_rate_per_m2 * point.speed_mps * point.speed_mps + pose.curvature_per_m * point.accel_mps2;
  return point;
}

double Route::TimeAtStation(double station_m) const {
  if (std::isnan(station_m)) throw std::invalid_argument("Route::TimeAtStation: station is NaN");
  const double s = std::clamp(station_m, 0.0, length_m());
  if (s <= 0.0) return 0.0;
  auto it = std::lower_bound(phases_.begin(), phases_.end(), s,
                             [](const Phase& p, double value) { return p.start_station_m < value; });
  const Phase& phase = *std::prev(it == phases_.begin() ? std::next(it) : it);
  // Solve s0 + v0 tau + a tau^2 / 2 = s for the first tau >= 0 (stable form of the root).
  const double ds = s - phase.start_station_m;
  const double v0 = phase.start_speed_mps, acc = phase.accel_mps2;
  const double disc = std::sqrt(std::max(0.0, v0 * v0 + 2 * acc * ds));
  const double tau = v0 + disc > 0.0 ? 2 * ds / (v0 + disc) : 0.0;
  return phase.start_time_s + std::clamp(tau, 0.0, phase.duration_s);
}

std::vector<double> Route::BreakTimes() const {
  std::vector<double> times;
  for (const Phase& phase : phases_) times.push_back(phase.start_time_s);
  times.push_back(phases_.back().start_time_s + phases_.back().duration_s);
  for (const double station_m : geometry_.PieceStarts()) times.push_back(TimeAtStation(station_m));
  std::sort(times.begin(), times.end());
  times.erase(std::unique(times.begin(), times.end()), times.end());
  return times;
}

double Route::PeakSpeed_mps() const {
  double peak = 0.0;
  for (const Phase& phase : phases_)
    peak = std::max({peak, phase.start_speed_mps, phase.start_speed_mps + phase.accel_mps2 * phase.duration_s});
  return peak;
}

}  // namespace rowloc::sim
