// Route: the time-parameterized path a simulated vehicle drives (issue 3, "Vehicles and motion").
// The ground truth of every run is derived from it, so position, heading, speed, yaw rate
// and their derivatives are exact and mutually consistent. Documented in docs/simulation-routes.md.
//
// Geometry (SI units, world ENU frame, heading from +East counter-clockwise):
// - The path is a chain of pieces whose curvature is linear in arc length u in [0, l]:
//   kappa(u) = kappa0 + kappa' u, kappa' = (kappa1 - kappa0) / l (line, circular arc, clothoid;
//   Lindgren et al. 2002 §2.3 "Path Formulation" composes its commanded paths of lines and arcs).
// - Heading theta(u) = theta0 + kappa0 u + kappa' u^2 / 2 (exact).
// - Position p(u) = p0 + int_0^u (cos theta, sin theta) du: closed form for lines and arcs,
//   4-point Gauss-Legendre quadrature on sub-intervals with |kappa| h <= 0.1 and |kappa'| h^2 <= 0.1
//   for clothoids (quadrature error far below 1e-12 m per sub-interval). Pieces are joined with
//   continuous position and heading; the curvature may jump at a join (then the yaw rate jumps).
//
// Timing (speed profile over the whole path):
// - Speed limit v_lim(s) = min(v_cruise, sqrt(a_lat / |kappa(s)|)); on a clothoid the limit of each
//   short segment is taken at its larger |kappa| end, so the speed never exceeds the true limit.
// - Forward/backward passes with |dv/dt| <= a_max from v = 0 at s = 0 to v = 0 at s = L give the node
//   speeds; within each segment v^2(s) = min(v_lim^2, v_a^2 + 2 a_max (s - s_a), v_b^2 + 2 a_max (s_b - s)),
//   i.e. phases of constant acceleration +a_max, 0 or -a_max with exact times
//   (t = (v1 - v0)/a, or ds / v when cruising): s(t) = s0 + v0 tau + a tau^2 / 2.
// - Dwell phases at standstill before and after the motion.
// Truth: yaw rate = kappa v, yaw acceleration = kappa' v^2 + kappa a (d/dt of kappa(s(t)) v(t)).
#pragma once

#include <Eigen/Core>

#include <optional>
#include <string>
#include <vector>

namespace rowloc::sim {

/// A piece of path whose signed curvature varies linearly with arc length (line, arc, clothoid).
struct PathPiece {
  double length_m = 0.0;               ///< l > 0
  double start_curvature_per_m = 0.0;  ///< kappa0, |kappa0| <= 10 /m, > 0 turns left
  double end_curvature_per_m = 0.0;    ///< kappa1, |kappa1| <= 10 /m
  bool operator==(const PathPiece&) const = default;
};

struct RouteSpec {
  Eigen::Vector2d start_position_m{0, 0};  ///< world ENU
  double start_heading_rad = 0;            ///< from +East, ccw
  std::vector<PathPiece> pieces;
  double cruise_speed_mps = 1.0;           ///< in (0, 100]
  double max_accel_mps2 = 1.0;             ///< in (0, 100]: start-up acceleration and stopping deceleration
  double max_lateral_accel_mps2 = 0.5;     ///< in (0, 100]: v <= sqrt(a_lat / |kappa|) in curves
  double start_dwell_s = 0.0;              ///< >= 0, standing still before moving
  double end_dwell_s = 0.0;                ///< >= 0, standing still after stopping
  bool operator==(const RouteSpec&) const = default;
};

/// The exact state on the route at one time.
struct RoutePoint {
  double time_s = 0, station_m = 0;        ///< station: arc length travelled
  Eigen::Vector2d position_m{0, 0};
  double heading_rad = 0;                  ///< wrapped to (-pi, pi]
  double speed_mps = 0, accel_mps2 = 0;    ///< ds/dt, d2s/dt2 (tangential)
  double curvature_per_m = 0, yaw_rate_radps = 0, yaw_accel_radps2 = 0;
};

/// Why the spec is unusable (naming the field), or nullopt. Limits: 1 to 100000 pieces, each
/// 1e-6 m to 1e5 m long, total length <= 1e6 m, |kappa| <= 10 /m, every value finite, speed,
/// accelerations in (0, 100], dwells in [0, 1e6] s.
std::optional<std::string> RouteSpecProblem(const RouteSpec& spec);

/// The pose along a path of pieces as a function of station (no timing).
class PathGeometry {
 public:
  struct Pose {
    Eigen::Vector2d position_m{0, 0};
    double heading_rad = 0;            ///< continuous (not wrapped)
    double curvature_per_m = 0;
    double curvature_rate_per_m2 = 0;  ///< d kappa / ds on the piece
  };

  /// Throws std::invalid_argument if RouteSpecProblem finds a problem with the pieces or start.
  PathGeometry(const Eigen::Vector2d& start_position_m, double start_heading_rad,
               const std::vector<PathPiece>& pieces);

  double length_m() const { return length_m_; }
  /// Pose at station s, clamped to [0, length]. At a join the later piece is used.
  Pose At(double station_m) const;
  /// Stations where a piece begins (first is 0), in increasing order.
  std::vector<double> PieceStarts() const;

 private:
  /// A table node: a piece start, or a sub-interval start inside a clothoid.
  struct Node {
    double station_m, curvature_per_m, curvature_rate_per_m2, heading_rad, cos_heading, sin_heading;
    Eigen::Vector2d position_m;
    bool piece_start;
  };
  static Eigen::Vector2d Advance(const Node& node, double delta_m);

  std::vector<Node> nodes_;
  double length_m_ = 0.0;
};

class Route {
 public:
  /// Throws std::invalid_argument naming the problem (RouteSpecProblem).
  explicit Route(RouteSpec spec);

  double duration_s() const;
  double length_m() const { return geometry_.length_m(); }
  /// The state at time t, clamped to [0, duration] (NaN: std::invalid_argument). Costs two binary
  /// searches and closed forms.
  RoutePoint At(double time_s) const;
  const RouteSpec& spec() const { return spec_; }
  const PathGeometry& geometry() const { return geometry_; }

  /// Time at which station s is first reached (s clamped to [0, length]; NaN: std::invalid_argument).
  double TimeAtStation(double station_m) const;
  /// Times where the acceleration or the curvature may jump (phase changes and piece joins),
  /// sorted; At is right-continuous there. Useful to step a vehicle simulation across them.
  std::vector<double> BreakTimes() const;
  /// The largest speed on the route.
  double PeakSpeed_mps() const;

 private:
  /// Constant acceleration from (t0, s0, v0) for duration.
  struct Phase {
    double start_time_s, start_station_m, start_speed_mps, accel_mps2, duration_s;
  };
  void BuildPhases();
  const Phase& PhaseAt(double time_s) const;

  RouteSpec spec_;
  PathGeometry geometry_;
  std::vector<Phase> phases_;  ///< the motion, from t = start_dwell to the stop
};

}  // namespace rowloc::sim
