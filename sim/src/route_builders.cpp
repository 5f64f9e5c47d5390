#include "rowloc/sim/route_builders.hpp"

#include "rowloc/mapio/detail/json_object_reader.hpp"

#include <algorithm>
#include <cmath>
#include <numbers>
#include <stdexcept>
#include <string>

namespace rowloc::sim {
namespace {

constexpr double kPi = std::numbers::pi;
constexpr double kMinTurnRadius_m = 0.1;
constexpr int kMaxRepeats = 1000;
// RouteSpecProblem's limits (route.hpp), checked per key when a route is read from JSON.
constexpr double kMaxTurnCurvature_per_m = 10.0;
constexpr double kMinPieceLength_m = 1e-6;
constexpr double kMaxPieceLength_m = 1e5;
constexpr std::size_t kMaxPieces = 100000;

void Require(bool condition, const std::string& what) {
  if (!condition) throw std::invalid_argument(what);
}

RouteSpec BaseSpec(const Eigen::Vector2d& start, double heading, double speed, double accel) {
  Require(start.allFinite(), "start must be finite");
  Require(std::isfinite(heading), "heading must be finite");
  RouteSpec spec;
  spec.start_position_m = start;
  spec.start_heading_rad = heading;
  spec.cruise_speed_mps = speed;
  spec.max_accel_mps2 = accel;
  return spec;
}

/// Validates the finished spec (speed, acceleration, lengths) with RouteSpecProblem.
RouteSpec Checked(RouteSpec spec) {
  if (const auto problem = RouteSpecProblem(spec)) throw std::invalid_argument(*problem);
  return spec;
}

PathPiece Line(double length_m) { return {length_m, 0.0, 0.0}; }
PathPiece Arc(double length_m, double curvature_per_m) { return {length_m, curvature_per_m, curvature_per_m}; }

/// Lateral offset of the symmetric turn clothoid(0 -> k, length c), arc k, clothoid(k -> 0, c) turning
/// left by pi in total. By symmetry (kappa(u) = kappa(T - u)) it ends level with its start.
double TurnOffset(double curvature, double transition_m) {
  const double arc_m = (kPi - curvature * transition_m) / curvature;
  std::vector<PathPiece> pieces = {{transition_m, 0.0, curvature}, {transition_m, curvature, 0.0}};
  if (arc_m >= 1e-6) pieces.insert(pieces.begin() + 1, Arc(arc_m, curvature));
  const PathGeometry geometry({0.0, 0.0}, 0.0, pieces);
  return geometry.At(geometry.length_m()).position_m.y();
}

/// A 180-degree turn to the left (+1) or right (-1) that shifts the path sideways by 2 r: a semicircle
/// of radius r, or with clothoid transitions of length c in [0.1, r]: the peak curvature k solves
/// TurnOffset(k, c) = 2 r by bisection on [1/r, pi/c] (the offset falls from > 2 r at k = 1/r to
/// 2 S(1) c <= 0.88 r at k = pi/c, S the Fresnel integral).
std::vector<PathPiece> UTurn(double radius_m, double side, double transition_m) {
  if (transition_m == 0.0) return {Arc(kPi * radius_m, side / radius_m)};
  double low = 1.0 / radius_m, high = std::min(kPi / transition_m, kMaxTurnCurvature_per_m);
  Require(TurnOffset(high, transition_m) <= 2.0 * radius_m,
          "turn_transition_m is too long for this turn radius: the turn would need a curvature above 10 /m");
  for (int i = 0; i < 200 && high - low > 1e-15 * high; ++i) {
    const double mid = 0.5 * (low + high);
    (TurnOffset(mid, transition_m) > 2.0 * radius_m ? low : high) = mid;
  }
  const double k = 0.5 * (low + high);
  const double arc_m = (kPi - k * transition_m) / k;
  std::vector<PathPiece> pieces = {{transition_m, 0.0, side * k}, {transition_m, side * k, 0.0}};
  if (arc_m >= 1e-6) pieces.insert(pieces.begin() + 1, Arc(arc_m, side * k));
  return pieces;
}

void RequireTransition(double transition_m, double radius_m) {
  Require(std::isfinite(transition_m) && (transition_m == 0.0 || (transition_m >= 0.1 && transition_m <= radius_m)),
          "turn_transition_m must be 0 or in [0.1 m, turn radius]");
}

void AppendUTurn(double radius_m, double side, double transition_m, std::vector<PathPiece>& pieces) {
  const std::vector<PathPiece> turn = UTurn(radius_m, side, transition_m);
  pieces.insert(pieces.end(), turn.begin(), turn.end());
}

/// The pieces of the reference curve c(s) of a world: (station length, curvature) per piece,
/// following RowWorld's definition (straight; one arc; S-curve switching at L / 2).
std::vector<PathPiece> ReferencePieces(const RowWorld& world) {
  const RowWorldParams& p = world.params();
  const double length_m = p.row_length_m;
  if (p.curvature == RowCurvature::kSCurve) {
    const double half_m = 0.5 * length_m;
    return {Arc(half_m, world.CurvatureAt(0.5 * half_m)), Arc(half_m, world.CurvatureAt(1.5 * half_m))};
  }
  return {Arc(length_m, world.CurvatureAt(0.5 * length_m))};
}

/// Appends lane offset_m, forward (station 0 -> L) or backward, to `pieces`.
void AppendLane(const std::vector<PathPiece>& reference, double offset_m, bool forward, double headland_m,
                std::vector<PathPiece>& pieces) {
  if (headland_m > 0.0) pieces.push_back(Line(headland_m));
  std::vector<PathPiece> lane;
  for (const PathPiece& piece : reference) {
    const double kappa = piece.start_curvature_per_m;
    const double stretch = 1.0 - kappa * offset_m;  // > 0: RowWorld bounds |kappa| (count - 1) spacing < 0.9
    const double lane_kappa = kappa / stretch;
    lane.push_back(Arc(piece.length_m * stretch, forward ? lane_kappa : -lane_kappa));
  }
  if (!forward) std::reverse(lane.begin(), lane.end());
  pieces.insert(pieces.end(), lane.begin(), lane.end());
  if (headland_m > 0.0) pieces.push_back(Line(headland_m));
}

}  // namespace

RouteSpec StraightRoute(Eigen::Vector2d start, double heading, double length_m, double speed_mps, double accel_mps2) {
  Require(std::isfinite(length_m) && length_m > 0.0, "length_m must be finite and > 0");
  RouteSpec spec = BaseSpec(start, heading, speed_mps, accel_mps2);
  spec.pieces = {Line(length_m)};
  return Checked(std::move(spec));
}

RouteSpec CircleRoute(Eigen::Vector2d start, double heading, double radius_m, int laps, double speed, double accel) {
  Require(std::isfinite(radius_m) && std::abs(radius_m) >= kMinTurnRadius_m,
          "radius_m must be finite with |radius| >= 0.1 m");
  Require(laps >= 1 && laps <= kMaxRepeats, "laps must be in [1, 1000]");
  RouteSpec spec = BaseSpec(start, heading, speed, accel);
  spec.pieces = {Arc(2.0 * kPi * std::abs(radius_m) * laps, 1.0 / radius_m)};
  return Checked(std::move(spec));
}

RouteSpec ShuttleRoute(Eigen::Vector2d start, double heading, double leg_length_m, int legs, double turn_radius_m,
                       double speed, double accel) {
  return ShuttleRoute(start, heading, leg_length_m, legs, turn_radius_m, speed, accel, 0.0);
}

RouteSpec ShuttleRoute(Eigen::Vector2d start, double heading, double leg_length_m, int legs, double turn_radius_m,
                       double speed, double accel, double turn_transition_m) {
  Require(std::isfinite(leg_length_m) && leg_length_m > 0.0, "leg_length_m must be finite and > 0");
  Require(legs >= 1 && legs <= kMaxRepeats, "legs must be in [1, 1000]");
  Require(std::isfinite(turn_radius_m) && std::abs(turn_radius_m) >= kMinTurnRadius_m,
          "turn_radius_m must be finite with |turn_radius| >= 0.1 m");
  RequireTransition(turn_transition_m, std::abs(turn_radius_m));
  RouteSpec spec = BaseSpec(start, heading, speed, accel);
  const double radius_m = std::abs(turn_radius_m);
  double side = turn_radius_m > 0.0 ? 1.0 : -1.0;
  for (int leg = 0; leg < legs; ++leg) {
    if (leg > 0) {
      AppendUTurn(radius_m, side, turn_transition_m, spec.pieces);
      side = -side;
    }
    spec.pieces.push_back(Line(leg_length_m));
  }
  return Checked(std::move(spec));
}

RouteSpec RowsRoute(const RowWorld& world, int first_lane, int lane_count, double headland_m, double speed,
                    double accel) {
  return RowsRoute(world, first_lane, lane_count, headland_m, speed, accel, 0.0);
}

RouteSpec RowsRoute(const RowWorld& world, int first_lane, int lane_count, double headland_m, double speed,
                    double accel, double turn_transition_m) {
  const int row_count = world.params().row_count;
  Require(row_count >= 2, "the world needs at least 2 rows to have a lane");
  Require(first_lane >= 0 && first_lane <= row_count - 2, "first_lane must be in [0, row_count - 2]");
  Require(lane_count >= 1 && lane_count <= row_count - 1 - first_lane,
          "lane_count must be in [1, row_count - 1 - first_lane]");
  Require(std::isfinite(headland_m) && headland_m >= 0.0 && headland_m <= 1e4, "headland_m must be in [0, 1e4] m");
  const double spacing_m = world.params().row_spacing_m;
  Require(0.5 * spacing_m >= kMinTurnRadius_m, "row spacing / 2 (the headland turn radius) must be >= 0.1 m");
  RequireTransition(turn_transition_m, 0.5 * spacing_m);

  const std::vector<PathPiece> reference = ReferencePieces(world);
  const double first_offset_m = (first_lane + 0.5) * spacing_m;
  const Eigen::Vector2d normal = world.ReferenceNormal(0.0);
  const Eigen::Vector2d tangent(normal.y(), -normal.x());
  RouteSpec spec = BaseSpec(world.ReferencePoint(0.0) + first_offset_m * normal - headland_m * tangent,
                            world.params().heading_rad, speed, accel);
  for (int i = 0; i < lane_count; ++i) {
    const bool forward = i % 2 == 0;
    if (i > 0) AppendUTurn(0.5 * spacing_m, forward ? -1.0 : 1.0, turn_transition_m, spec.pieces);
    AppendLane(reference, (first_lane + i + 0.5) * spacing_m, forward, headland_m, spec.pieces);
  }
  return Checked(std::move(spec));
}

// ---------------------------------------------------------------------------------------------
// JSON

namespace {

using Reader = mapio::detail::JsonObjectReader<RouteConfigError>;

struct Motion {
  double speed_mps, accel_mps2, lateral_mps2, start_dwell_s, end_dwell_s;
};

Motion ReadMotion(Reader& reader) {
  Motion m{};
  m.speed_mps = reader.NumberIn("speed_mps", 1e-3, 100.0);
  m.accel_mps2 = reader.NumberIn("accel_mps2", 1e-3, 100.0);
  m.lateral_mps2 = reader.NumberIn("max_lateral_accel_mps2", 1e-3, 100.0);
  m.start_dwell_s = reader.NumberIn("start_dwell_s", 0.0, 1e6);
  m.end_dwell_s = reader.NumberIn("end_dwell_s", 0.0, 1e6);
  return m;
}

int ReadCount(Reader& reader, const std::string& key, int low, int high) {
  return static_cast<int>(reader.Integer(key, low, high));
}

/// One element of "pieces": {"length_m", "start_curvature_per_m", "end_curvature_per_m"}.
PathPiece ReadPiece(Reader& reader) {
  constexpr double kMaxK = kMaxTurnCurvature_per_m;
  PathPiece piece;
  piece.length_m = reader.NumberIn("length_m", kMinPieceLength_m, kMaxPieceLength_m);
  piece.start_curvature_per_m = reader.NumberIn("start_curvature_per_m", -kMaxK, kMaxK);
  piece.end_curvature_per_m = reader.NumberIn("end_curvature_per_m", -kMaxK, kMaxK);
  reader.RejectUnknownKeys();
  return piece;
}

RouteSpec BuildFromType(Reader& reader, const std::string& type, const RowWorld* world, const Motion& m) {
  if (type == "rows") {
    if (world == nullptr) reader.Fail(reader.Key("type"), "a \"rows\" route needs a world with rows");
    const int first = ReadCount(reader, "first_lane", 0, kMaxRepeats);
    const int count = ReadCount(reader, "lane_count", 1, kMaxRepeats);
    const double headland_m = reader.NumberIn("headland_m", 0.0, 1e4);
    const double transition_m = reader.NumberIn("turn_transition_m", 0.0, 1e4);
    return RowsRoute(*world, first, count, headland_m, m.speed_mps, m.accel_mps2, transition_m);
  }
  const Eigen::Vector2d start = reader.Vector<2>("start");
  const double heading = reader.Number("heading_rad");
  if (type == "straight") {
    return StraightRoute(start, heading, reader.NumberIn("length_m", 1e-3, 1e5), m.speed_mps, m.accel_mps2);
  }
  if (type == "circle") {
    const double radius_m = reader.Number("radius_m");
    return CircleRoute(start, heading, radius_m, ReadCount(reader, "laps", 1, kMaxRepeats), m.speed_mps,
                       m.accel_mps2);
  }
  if (type == "shuttle") {
    const double leg_m = reader.NumberIn("leg_length_m", 1e-3, 1e5);
    const int legs = ReadCount(reader, "legs", 1, kMaxRepeats);
    const double radius_m = reader.Number("turn_radius_m");
    const double transition_m = reader.NumberIn("turn_transition_m", 0.0, 1e4);
    return ShuttleRoute(start, heading, leg_m, legs, radius_m, m.speed_mps, m.accel_mps2, transition_m);
  }
  if (type == "pieces") {
    RouteSpec spec = BaseSpec(start, heading, m.speed_mps, m.accel_mps2);
    spec.pieces = reader.ObjectArray("pieces", ReadPiece, 1, kMaxPieces);
    return Checked(std::move(spec));  // the total length and the clothoid subdivisions
  }
  reader.Fail(reader.Key("type"), "unknown route type \"" + type + "\" (straight, circle, shuttle, rows, pieces)");
}

}  // namespace

RouteSpec ParseRouteSpec(std::string_view json_object_text, std::string_view source_name, const RowWorld* world) {
  return ParseRouteSpec(json_object_text, source_name, world, "");
}

RouteSpec ParseRouteSpec(std::string_view json_object_text, std::string_view source_name, const RowWorld* world,
                         std::string_view key_path_prefix) {
  const std::string source(source_name);
  const nlohmann::json json = mapio::detail::ParseJsonText<RouteConfigError>(json_object_text, source);
  Reader reader(json, source, std::string(key_path_prefix));
  const std::string type = reader.String("type");
  const Motion motion = ReadMotion(reader);
  RouteSpec spec;
  try {
    spec = BuildFromType(reader, type, world, motion);
  } catch (const std::invalid_argument& error) {  // builder ranges not checked per key above
    reader.Fail(reader.path(), error.what());
  }
  reader.RejectUnknownKeys();
  spec.max_lateral_accel_mps2 = motion.lateral_mps2;
  spec.start_dwell_s = motion.start_dwell_s;
  spec.end_dwell_s = motion.end_dwell_s;
  if (const auto problem = RouteSpecProblem(spec)) reader.Fail(reader.path(), *problem);
  return spec;
}

}  // namespace rowloc::sim
