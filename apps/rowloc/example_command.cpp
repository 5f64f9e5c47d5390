// `rowloc example`: a worked example of the map-aided ultrasonic measurement on a row map.
//
// A vehicle (the four-wheel-steer vineyard UGV of Donati 2021: L = 1.5 m, T = 1 m, four ultrasonic
// sensors at the corners looking sideways) stands in a corridor of the map. Its predicted
// position is a k-sigma ellipse (P = k^2 S) around a point that is off by a known error from the
// true position. Each sensor's echo is simulated by a cone cast from the *true* pose against the
// map; the filter side then picks the row segment from the *predicted* pose (R-tree cone cast),
// turns the range into a slab (localization::MakeRangeSlab) and parallel-cuts the ellipse
// (geometry::ParallelCut), one sensor after the other, as in Donati 2021 ch. 4.
// Heading is taken as known here; the filter (issue 5) accounts for its uncertainty. --plot DIR
// draws the rows, the truth, the slabs and the ellipse before and after each cut (example_plot.hpp).
#include "commands.hpp"
#include "option_checks.hpp"
#include "ellipse_report.hpp"
#include "example_plot.hpp"

#include "rowloc/geometry/cone_cast.hpp"
#include "rowloc/geometry/ellipsoid.hpp"
#include "rowloc/geometry/ellipsoid_cuts.hpp"
#include "rowloc/geometry/segment_index.hpp"
#include "rowloc/localization/range_slab.hpp"
#include "rowloc/mapio/row_map_geojson.hpp"

#include <Eigen/Geometry>
#include <fmt/format.h>

#include <array>
#include <cmath>
#include <filesystem>
#include <numbers>
#include <stdexcept>
#include <string>
#include <vector>

namespace rowloc::apps {
namespace {

struct ExampleOptions {
  std::string map_path;
  int corridor = 4;              // between rows `corridor` and `corridor + 1` (1-based, map order)
  double along_m = 0.0;          // shift along the corridor from its middle, m
  double error_across_m = 0.25;  // prediction error across the corridor (towards the left), m
  double error_along_m = 0.40;   // prediction error along the corridor (forward), m
  double sigma_m = 0.3;          // predicted position standard deviation (each axis), m
  double k_sigma = 3.0;          // ellipse scale k: P = k^2 S
  double range_sigma_m = 0.003;  // ultrasonic range standard deviation (Donati 2021), m
  double max_range_m = 4.0;
  std::string plot_dir;          // --plot: directory of the picture (empty: none)
};

struct Sensor {
  const char* name;
  localization::RangeSensorMount mount;
};

constexpr double kHalfPi = std::numbers::pi / 2;
constexpr double kConeHalfAngleRad = 7.5 * std::numbers::pi / 180.0;  // 15 degree cone
const std::array<Sensor, 4> kSensors = {{
    {"front-left", {{0.75, 0.5}, kHalfPi, kConeHalfAngleRad}},
    {"front-right", {{0.75, -0.5}, -kHalfPi, kConeHalfAngleRad}},
    {"rear-left", {{-0.75, 0.5}, kHalfPi, kConeHalfAngleRad}},
    {"rear-right", {{-0.75, -0.5}, -kHalfPi, kConeHalfAngleRad}},
}};

struct Pose2 {
  Eigen::Vector2d position_m;
  double heading_rad;
};

geometry::Cone2 SensorCone(const Pose2& pose, const Sensor& s, const ExampleOptions& o) {
  const double beam = pose.heading_rad + s.mount.beam_angle_rad;
  return geometry::Cone2{pose.position_m + Eigen::Rotation2Dd(pose.heading_rad) * s.mount.lever_arm_m,
                         Eigen::Vector2d(std::cos(beam), std::sin(beam)),
                         s.mount.cone_half_angle_rad, o.max_range_m};
}

Eigen::Vector2d Centroid(const geometry::Row& row) {
  Eigen::Vector2d sum = Eigen::Vector2d::Zero();
  for (const auto& p : row.points_m) sum += p;
  return sum / static_cast<double>(row.points_m.size());
}

// The true pose: start between the two rows' centroids, take the heading of the nearest row
// segment, then centre the point across the corridor with a ray cast to each side.
Pose2 TruePose(const geometry::RowMap& map, const geometry::SegmentIndex& index,
               const ExampleOptions& o) {
  const int rows = static_cast<int>(map.rows.size());
  if (o.corridor < 1 || o.corridor >= rows) {
    throw std::invalid_argument(fmt::format("--corridor must be in [1, {}] for this map", rows - 1));
  }
  Eigen::Vector2d p = 0.5 * (Centroid(map.rows[static_cast<std::size_t>(o.corridor - 1)]) +
                             Centroid(map.rows[static_cast<std::size_t>(o.corridor)]));
  for (int pass = 0; pass < 3; ++pass) {  // shift along, then re-centre on the local rows
    const auto nearest = index.Nearest(p, 1);
    if (nearest.empty()) throw std::runtime_error("the map has no segments");
    const geometry::Segment2& seg = index.entries()[nearest.front().second].segment;
    Eigen::Vector2d along = (seg.b - seg.a).normalized();
    if (along.x() < 0.0) along = -along;  // drive in the +East half-plane, whatever the ring order
    const Eigen::Vector2d left(-along.y(), along.x());
    if (pass == 0) p += o.along_m * along;
    const auto hit_left = index.RayCast(p, left, 50.0);
    const auto hit_right = index.RayCast(p, -left, 50.0);
    if (!hit_left || !hit_right) throw std::runtime_error("the chosen point is not between two rows");
    p += 0.5 * (hit_left->hit.range_m - hit_right->hit.range_m) * left;
    if (pass == 2) return Pose2{p, std::atan2(along.y(), along.x())};
  }
  return {};  // unreachable
}

void PrintSlabAndCut(const Sensor& sensor, double range_m, const localization::RangeSlab& slab,
                     const geometry::CutResult<2>& cut) {
  fmt::print("  {:<11} range {:.4f} m -> slab {:.4f} <= ({:+.4f}, {:+.4f})^T p <= {:.4f} m"
             "  (cos gamma {:.4f})\n",
             sensor.name, range_m, slab.lower_m, slab.normal.x(), slab.normal.y(), slab.upper_m,
             slab.incidence_cos);
  fmt::print("              cut: {}, alpha {:+.4f}, alpha_hat {:+.4f}\n", geometry::ToString(cut.status),
             cut.alpha, cut.alpha_hat);
  fmt::print("              -> {}\n", FormatEllipse(Summarize(cut.ellipsoid.center(), cut.ellipsoid.shape())));
}

int RunExample(const ExampleOptions& o) {
  if (!o.plot_dir.empty()) {
    const std::filesystem::path dir(o.plot_dir);
    std::vector<NamedPath> outputs;
    for (const char* name : {"rows.dat", "ellipses.dat", "slabs.dat", "points.dat", "cuts.gp", "cuts.svg"}) {
      outputs.push_back({"--plot", (dir / name).string()});
    }
    CheckCommandFiles({{"--map", o.map_path}}, outputs);
  }
  const geometry::RowMap map = mapio::ReadRowMapGeoJson(o.map_path);
  const geometry::SegmentIndex index = geometry::SegmentIndex::FromRowMap(map);
  const Pose2 truth = TruePose(map, index, o);
  const Eigen::Rotation2Dd rot(truth.heading_rad);
  const Eigen::Vector2d predicted =
      truth.position_m + rot * Eigen::Vector2d(o.error_along_m, o.error_across_m);
  const Pose2 prior{predicted, truth.heading_rad};

  fmt::print("map {}: {} rows, {} segments, origin {:.6f} N {:.6f} E\n", o.map_path, map.rows.size(),
             index.size(), map.origin.latitude_deg, map.origin.longitude_deg);
  fmt::print("true position ({:.4f}, {:.4f}) m, heading {:.2f} deg\n", truth.position_m.x(),
             truth.position_m.y(), truth.heading_rad * 180.0 / std::numbers::pi);
  geometry::Ellipsoid<2> ellipse = geometry::Ellipsoid<2>::FromCovariance(
      predicted, Eigen::Matrix2d::Identity() * o.sigma_m * o.sigma_m, o.k_sigma);
  const geometry::Ellipsoid<2> predicted_ellipse = ellipse;
  std::vector<ExampleCutStep> steps;
  fmt::print("predicted ({:.0f}-sigma): {}\n", o.k_sigma,
             FormatEllipse(Summarize(ellipse.center(), ellipse.shape())));

  for (const Sensor& sensor : kSensors) {
    const auto echo = index.ConeCast(SensorCone(truth, sensor, o));      // the world answers
    const auto expected = index.ConeCast(SensorCone(prior, sensor, o));  // the filter's row choice
    if (!echo || !expected) {
      fmt::print("  {:<11} no echo within {:.1f} m: no measurement\n", sensor.name, o.max_range_m);
      continue;
    }
    const geometry::Segment2& seg = index.entries()[expected->entry].segment;
    const geometry::Line2 line = geometry::Line2::Through(seg.a, seg.b);
    const auto slab = localization::MakeRangeSlab({line.normal, line.offset}, sensor.mount,
                                                  prior.heading_rad, echo->hit.range_m,
                                                  o.range_sigma_m, o.k_sigma);
    if (!slab) {
      fmt::print("  {:<11} beam grazes the row: no measurement\n", sensor.name);
      continue;
    }
    const auto cut = geometry::ParallelCut(ellipse, slab->normal, slab->lower_m, slab->upper_m);
    PrintSlabAndCut(sensor, echo->hit.range_m, *slab, cut);
    if (cut.status == geometry::CutStatus::kUpdated) ellipse = cut.ellipsoid;
    steps.push_back({sensor.name, *slab, ellipse});
  }

  const Eigen::Vector2d error = ellipse.center() - truth.position_m;
  fmt::print("result: {}\n", FormatEllipse(Summarize(ellipse.center(), ellipse.shape())));
  fmt::print("error of the centre: across {:+.4f} m, along {:+.4f} m (before: across {:+.4f}, along {:+.4f});"
             " truth inside the ellipse: {}\n",
             (rot.inverse() * error).y(), (rot.inverse() * error).x(), o.error_across_m, o.error_along_m,
             ellipse.Contains(truth.position_m) ? "yes" : "NO");
  if (!o.plot_dir.empty()) {
    fmt::print("{}\n", WriteExamplePlot(o.plot_dir, map, truth.position_m, predicted_ellipse, steps));
  }
  return ellipse.Contains(truth.position_m) ? 0 : 1;
}

}  // namespace

void RegisterExampleCommand(CLI::App& app) {
  auto options = std::make_shared<ExampleOptions>();
  CLI::App* cmd = app.add_subcommand(
      "example", "Worked example: predicted ellipse + 4 ultrasonic ranges -> slabs -> parallel cuts");
  cmd->add_option("--map", options->map_path, "Row map (GeoJSON)")->required()->check(CLI::ExistingFile);
  cmd->add_option("--corridor", options->corridor, "Corridor between rows N and N+1 (1-based)");
  cmd->add_option("--along", options->along_m, "Shift along the corridor from its middle [m]");
  cmd->add_option("--error-across", options->error_across_m, "Prediction error across the rows [m]");
  cmd->add_option("--error-along", options->error_along_m, "Prediction error along the rows [m]");
  cmd->add_option("--sigma", options->sigma_m, "Predicted position standard deviation [m]")
      ->check(PositiveNumber());
  cmd->add_option("--k-sigma", options->k_sigma, "Ellipse scale k (P = k^2 S)")->check(PositiveNumber());
  cmd->add_option("--range-sigma", options->range_sigma_m, "Ultrasonic range standard deviation [m]")
      ->check(PositiveNumber());
  cmd->add_option("--plot", options->plot_dir,
                  "Directory for the picture: rows, truth, slabs, ellipse before and after each cut (cuts.svg)");
  cmd->callback([options] {
    int code = 0;
    RunReportingInputErrors("example", [&] { code = RunExample(*options); });
    if (code != 0) throw CLI::RuntimeError(code);  // the truth outside the updated ellipse: a result
  });
}

}  // namespace rowloc::apps
