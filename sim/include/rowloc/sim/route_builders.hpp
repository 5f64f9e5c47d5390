// Named routes for the simulation scenarios (issue 3, "driving a route: along the rows with headland
// turns, straight runs, circles") and their JSON form. Documented in docs/simulation-routes.md.
//
// - StraightRoute: one line (Danzi 2026 ch. 7: AgriMaRo's straight runs at 1 m/s after 1 m/s^2;
//   Tazzari et al. n.d.: the tracked vehicle's constant-speed straight runs).
// - CircleRoute: `laps` full circles of signed radius R (> 0 turns left): one arc of length
//   2 pi |R| laps (Lindgren et al. 2002 Fig. 3: loops of 4 m radius; Tazzari et al. n.d.: circular runs).
// - ShuttleRoute: `legs` straight legs joined by 180-degree semicircles of radius |r| that alternate
//   in direction (Lindgren et al. 2002, results near Fig. 7: "straight line travel, with alternate right and left 180°
//   turns"). r > 0: the first turn is to the left, r < 0: to the right (as in Lindgren et al. 2002). Each turn
//   shifts the next leg by 2|r| sideways, so leg i (0-based) runs from
//   start + i 2|r| n (n the side of the first turn) in direction (-1)^i t.
// - RowsRoute: a serpentine through consecutive lanes of a RowWorld. Lane j lies midway between
//   rows j and j+1, at offset d_j = (j + 1/2) spacing to the left of the reference curve c(s);
//   on a reference piece of curvature kappa the lane is the parallel curve with curvature
//   kappa / (1 - kappa d_j) and length (1 - kappa d_j) ds (a concentric arc). Even-numbered lanes
//   of the route run from station 0 to L, odd ones back. Each lane is extended by a straight
//   headland of headland_m, tangent at station 0 (before) and at L (after), and consecutive lanes
//   are joined by a semicircle of radius spacing / 2 (left after a forward lane, right after a
//   backward one), which ends exactly on the next lane's headland line.
// Turn transitions: by default (the seven-argument builders, turn_transition_m = 0) the turns are
// semicircles joined to the lines directly, as Lindgren et al. 2002 command their paths (lines and arcs), so the
// curvature and the yaw rate jump at the joins (Route::BreakTimes lists the instants). With
// turn_transition_m = c > 0 each 180-degree turn becomes clothoid (0 -> k, length c), arc k,
// clothoid (k -> 0, length c), with k > 1/r solved so that the turn still shifts the path by exactly
// 2 r and ends level with its start (symmetric curvature): yaw rate continuous through the turn.
// The lane ends of curved rows (straight headland -> lane arc) keep their (small) curvature jump.
#pragma once

#include "rowloc/sim/route.hpp"
#include "rowloc/sim/row_world.hpp"

#include <Eigen/Core>

#include <stdexcept>
#include <string_view>

namespace rowloc::sim {

/// Error in a route description: "<source>: <key path>: <reason>".
class RouteConfigError : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

// Every builder throws std::invalid_argument for an argument out of range (naming it) and returns
// a spec with RouteSpec's defaults for the fields it does not set (max_lateral_accel_mps2 = 0.5,
// no dwell): the curve speed limit sqrt(0.5 / |kappa|) applies unless the caller raises it.

/// length_m > 0.
RouteSpec StraightRoute(Eigen::Vector2d start, double heading, double length_m, double speed_mps, double accel_mps2);
/// radius_m != 0 with |radius_m| >= 0.1 m, laps in [1, 1000].
RouteSpec CircleRoute(Eigen::Vector2d start, double heading, double radius_m, int laps, double speed, double accel);
/// leg_length_m > 0, legs in [1, 1000], |turn_radius_m| >= 0.1 m (sign: side of the first turn).
/// Semicircle turns (no transitions).
RouteSpec ShuttleRoute(Eigen::Vector2d start, double heading, double leg_length_m, int legs, double turn_radius_m,
                       double speed, double accel);
/// As above with clothoid transitions of turn_transition_m (0, or in [0.1 m, |turn_radius_m|]) in and out
/// of every turn; the turns still shift each leg by exactly 2 |turn_radius_m|.
RouteSpec ShuttleRoute(Eigen::Vector2d start, double heading, double leg_length_m, int legs, double turn_radius_m,
                       double speed, double accel, double turn_transition_m);
/// Lanes first_lane .. first_lane + lane_count - 1, each in [0, row_count - 2]; headland_m in [0, 1e4];
/// spacing / 2 >= 0.1 m (the turn radius). Semicircle turns (no transitions).
RouteSpec RowsRoute(const RowWorld& world, int first_lane, int lane_count, double headland_m, double speed,
                    double accel);
/// As above with clothoid transitions of turn_transition_m (0, or in [0.1 m, spacing / 2]) in the turns.
RouteSpec RowsRoute(const RowWorld& world, int first_lane, int lane_count, double headland_m, double speed,
                    double accel, double turn_transition_m);

/// Parses a "route" JSON object (format in docs/simulation-routes.md): types "straight", "circle",
/// "shuttle", "rows" (the builders above) and "pieces" (start, heading and the PathPieces as written,
/// each checked against RouteSpecProblem's limits by key); every key required, unknown keys
/// rejected. Errors: RouteConfigError "<source_name>: <key path>: <reason>", where key paths start
/// with key_path_prefix (e.g. "route" gives "route.speed_mps", "route.pieces[2].length_m"). A "rows"
/// route needs the world (a null world is an error naming "type").
RouteSpec ParseRouteSpec(std::string_view json_object_text, std::string_view source_name, const RowWorld* world);
RouteSpec ParseRouteSpec(std::string_view json_object_text, std::string_view source_name, const RowWorld* world,
                         std::string_view key_path_prefix);

}  // namespace rowloc::sim
