// MapAidedUpdater (map_aided_updater.hpp) on its own, without a filter: the measurement of an echo
// against a straight row (innovation, Jacobian, noise, gate), each outcome that leaves no
// measurement and its count, the map agreement's evaluation every 20 echoes, and the refusals
// (no map, no rangers, an unknown ranger, a range that is not a finite positive number).
#include "rowloc/localization/map_aided_updater.hpp"

#include "rowloc/localization/kalman_update.hpp"
#include "rowloc/mapio/vehicle_config.hpp"

#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include <cmath>
#include <limits>
#include <string>

namespace rowloc::localization {
namespace {

using ::testing::HasSubstr;

const geometry::GeoOrigin kOrigin{45.0, 7.0, 200.0};

/// One open row along x at y = 1 (0 <= x <= 50), with the given outline accuracy.
geometry::RowMap OneRow(double outline_sigma_m = 0.0) {
  geometry::RowMap map;
  map.origin = kOrigin;
  map.rows.push_back({"row-1", {{0.0, 1.0}, {50.0, 1.0}}, false, outline_sigma_m});
  return map;
}

/// Three canopies 0.5 m wide, centres y = -1.25, 1.25, 3.75 along x in [0, 50]: lanes 2.0 m free.
geometry::RowMap ThreeCanopies() {
  geometry::RowMap map;
  map.origin = kOrigin;
  for (int i = 0; i < 3; ++i) {
    const double c = -1.25 + 2.5 * i;
    map.rows.push_back({"row-" + std::to_string(i), {{0.0, c - 0.25}, {50.0, c - 0.25}, {50.0, c + 0.25}, {0.0, c + 0.25}}, true});
  }
  return map;
}

/// The measurement model's tests weight echoes with the configured range sigma (3 mm): the
/// adaptation to the canopy (range_noise_estimator.hpp) has its own tests below.
MapAidedConfig FixedSigma() {
  MapAidedConfig config;
  config.adaptive_range_sigma.enabled = false;
  return config;
}

/// The 4WS UGV's updater (rangers us_front_left (0.75, 0.5), us_rear_left, us_front_right,
/// us_rear_right; left ones look +90 degrees, right ones -90) with `map` attached.
MapAidedUpdater UpdaterWith(const geometry::RowMap& map, const MapAidedConfig& config = FixedSigma()) {
  MapAidedUpdater updater(mapio::VineyardUgv4wsConfig(), config, kOrigin);
  updater.AttachRowMap(map);
  return updater;
}

Eigen::Matrix3d Covariance(double position_sigma_m, double heading_sigma_rad) {
  const double p = position_sigma_m * position_sigma_m;
  return Eigen::Vector3d(p, p, heading_sigma_rad * heading_sigma_rad).asDiagonal();
}

formats::UltrasonicMessage Echo(const std::string& sensor, std::optional<double> range_m, std::size_t index = 0) {
  return formats::UltrasonicMessage{1.0, sensor, index, range_m};
}

TEST(MapAidedUpdater, AnEchoFromAStraightRowGivesTheRangeInnovationAndJacobian) {
  MapAidedUpdater updater = UpdaterWith(OneRow());
  // Vehicle at (10, 0.12) heading +x: the front-left ranger at (10.75, 0.62) is 0.38 m from the row.
  const Eigen::Matrix3d P = Covariance(0.1, 0.01);
  const MapAidedEcho echo = updater.Measure(Echo("us_front_left", 0.4), Eigen::Vector3d(10.0, 0.12, 0.0), P);
  ASSERT_TRUE(echo.measurement.has_value());
  const MapAidedMeasurement& m = *echo.measurement;
  ASSERT_EQ(m.innovation.size(), 1);
  EXPECT_NEAR(m.innovation(0), 0.4 - 0.38, 1e-12);
  // r = 1 - (y + 0.75 sin phi + 0.5 cos phi): dr/d(X, Y, phi) = (0, -1, -0.75) at phi = 0.
  EXPECT_NEAR((m.jacobian - Eigen::RowVector3d(0.0, -1.0, -0.75)).norm(), 0.0, 1e-9);
  // R = sigma^2 + (|l| + r)^2 sigma_phi^4 / 2 (the map exact here).
  const double curvature = std::hypot(0.75, 0.5) + 0.38;
  EXPECT_NEAR(m.noise(0, 0), 0.003 * 0.003 + 0.5 * curvature * curvature * 1e-8, 1e-15);
  EXPECT_EQ(echo.gate, ChiSquareGate(1, MapAidedConfig{}.gate_probability));
  // The trace: outcome left to the filter's update, the prior as posterior, the row and its line.
  EXPECT_EQ(echo.trace.sensor, "us_front_left");
  EXPECT_EQ(echo.trace.measured_range_m, 0.4);
  EXPECT_TRUE(echo.trace.outcome.empty());
  EXPECT_EQ(echo.trace.prior_position_m, Eigen::Vector2d(10.0, 0.12));
  const Eigen::Matrix2d prior_covariance = P.topLeftCorner<2, 2>();
  EXPECT_EQ(echo.trace.prior_covariance, prior_covariance);
  EXPECT_EQ(echo.trace.posterior_covariance, echo.trace.prior_covariance);
  ASSERT_TRUE(echo.trace.segment.has_value() && echo.trace.line.has_value());
  EXPECT_NEAR(echo.trace.line->normal.y(), -1.0, 1e-12);  // towards the sensor
  EXPECT_EQ(updater.stats().echoes, 1u);
  EXPECT_EQ(updater.stats().no_segment + updater.stats().ambiguous, 0u);
}

TEST(MapAidedUpdater, TheMapsOutlineAccuracyAddsToTheRangeNoise) {
  MapAidedUpdater exact = UpdaterWith(OneRow());
  MapAidedUpdater rough = UpdaterWith(OneRow(0.02));
  const Eigen::Vector3d pose(10.0, 0.12, 0.0);
  const double r_exact = exact.Measure(Echo("us_front_left", 0.4), pose, Covariance(0.1, 0.01)).measurement->noise(0, 0);
  const double r_rough = rough.Measure(Echo("us_front_left", 0.4), pose, Covariance(0.1, 0.01)).measurement->noise(0, 0);
  EXPECT_NEAR(r_rough - r_exact, 0.02 * 0.02, 1e-15);
}

TEST(MapAidedUpdater, TheCutMethodGivesAPositionMeasurementWithTheTwoDimensionalGate) {
  MapAidedConfig config = FixedSigma();
  config.method = MapAidedMethod::kEllipsoidCut;
  MapAidedUpdater updater = UpdaterWith(OneRow(), config);
  const MapAidedEcho echo =
      updater.Measure(Echo("us_front_left", 0.4), Eigen::Vector3d(10.0, 0.12, 0.0), Covariance(0.1, 0.01));
  ASSERT_TRUE(echo.measurement.has_value());
  EXPECT_EQ(echo.measurement->innovation.size(), 2);
  EXPECT_EQ(echo.gate, ChiSquareGate(2, config.gate_probability));
}

TEST(MapAidedUpdater, EchoesWithoutACertainAssociationAreCountedAndGiveNoMeasurement) {
  struct Case {
    const char* outcome;
    geometry::RowMap map;
    const char* sensor;
    Eigen::Vector3d pose;
    Eigen::Matrix3d covariance;
    double range_m;
    std::size_t MapAidedStats::*count;
  };
  const Case cases[] = {
      // k sigma_phi = 3 x 0.045 rad above the cone's half aperture 0.1309 rad.
      {"heading_uncertain", OneRow(), "us_front_left", {10.0, 0.12, 0.0}, Covariance(0.05, 0.045), 0.38,
       &MapAidedStats::heading_uncertain},
      // The right ranger looks away from the only row.
      {"no_segment", OneRow(), "us_front_right", {10.0, 0.12, 0.0}, Covariance(0.05, 0.01), 0.4,
       &MapAidedStats::no_segment},
      // Vehicle at y = 0.6: the left ranger at y = 1.1 is inside the canopy [1.0, 1.5].
      {"inside_outline", ThreeCanopies(), "us_front_left", {20.0, 0.6, 0.0}, Covariance(0.05, 0.01), 0.45,
       &MapAidedStats::inside_outline},
      // 3 sigma_r = 1.08 m above half the 2.0 m lane.
      {"lane_ambiguous", ThreeCanopies(), "us_front_left", {20.0, 0.0, 0.0}, Covariance(0.36, 0.005), 0.5,
       &MapAidedStats::lane_ambiguous},
  };
  for (const Case& c : cases) {
    MapAidedUpdater updater = UpdaterWith(c.map);
    const MapAidedEcho echo = updater.Measure(Echo(c.sensor, c.range_m), c.pose, c.covariance);
    EXPECT_EQ(echo.trace.outcome, c.outcome);
    EXPECT_FALSE(echo.measurement.has_value()) << c.outcome;
    EXPECT_EQ(updater.stats().echoes, 1u) << c.outcome;
    EXPECT_EQ(updater.stats().*c.count, 1u) << c.outcome;
    EXPECT_EQ(echo.trace.posterior_position_m, c.pose.head<2>()) << c.outcome;
  }
  // On either side of the thresholds the same echoes are measured.
  EXPECT_TRUE(UpdaterWith(OneRow()).Measure(Echo("us_front_left", 0.38), {10.0, 0.12, 0.0}, Covariance(0.05, 0.042)).measurement.has_value());
  EXPECT_TRUE(UpdaterWith(ThreeCanopies()).Measure(Echo("us_front_left", 0.1), {20.0, 0.4, 0.0}, Covariance(0.05, 0.01)).measurement.has_value());
  EXPECT_TRUE(UpdaterWith(ThreeCanopies()).Measure(Echo("us_front_left", 0.5), {20.0, 0.0, 0.0}, Covariance(0.32, 0.005)).measurement.has_value());
}

TEST(MapAidedUpdater, CutsThatDoNotUpdateAreCountedAsContradictingOrUninformative) {
  MapAidedConfig config = FixedSigma();
  config.method = MapAidedMethod::kEllipsoidCutDeprior;
  MapAidedUpdater updater = UpdaterWith(OneRow(), config);
  const Eigen::Vector3d pose(10.0, 0.12, 0.0);
  // Prior sigma 1 cm, range 0.5 m against 0.38 m predicted: the slab misses the 3-sigma ellipse.
  const MapAidedEcho contradicting = updater.Measure(Echo("us_front_left", 0.5), pose, Covariance(0.01, 0.001));
  EXPECT_EQ(contradicting.trace.outcome, "contradicting");
  EXPECT_FALSE(contradicting.measurement.has_value());
  // Prior sigma 1 mm inside a slab of +-9 mm: nothing to update.
  const MapAidedEcho uninformative = updater.Measure(Echo("us_front_left", 0.38), pose, Covariance(0.001, 0.0001));
  EXPECT_EQ(uninformative.trace.outcome, "uninformative");
  EXPECT_EQ(updater.stats().contradicting, 1u);
  EXPECT_EQ(updater.stats().uninformative, 1u);
  EXPECT_EQ(updater.stats().echoes, 2u);
}

TEST(MapAidedUpdater, TheMapAgreementIsEvaluatedEveryTwentyEchoes) {
  MapAidedUpdater updater = UpdaterWith(OneRow());
  const Eigen::Vector3d pose(10.0, 0.12, 0.0);
  // 100 echoes of the right ranger, which finds no row where it looks: the map of another place.
  for (std::size_t i = 1; i <= 100; ++i) {
    const MapAidedEcho echo = updater.Measure(Echo("us_front_right", 0.4, 2), pose, Covariance(0.05, 0.01));
    ASSERT_EQ(echo.agreement_checked, i % MapAidedUpdater::kAgreementEveryEchoes == 0) << i;
    // A finding once the monitor's window (100 echoes) is full, none before.
    ASSERT_EQ(echo.map_problem.has_value(), i == 100) << i;
  }
  EXPECT_EQ(updater.stats().no_segment, 100u);
}

TEST(MapAidedUpdater, TheRangerIsFoundByNameAndAnUnknownOneIsRefused) {
  MapAidedUpdater updater = UpdaterWith(OneRow());
  EXPECT_EQ(updater.RangerIndex("us_front_right", 2), 2u);
  EXPECT_EQ(updater.RangerIndex("us_front_right", 0), 2u);  // the hint is only tried first
  EXPECT_EQ(updater.RangerIndex("us_front_right", 9), 2u);
  EXPECT_FALSE(updater.RangerIndex("us_roof", 0).has_value());
  try {
    updater.Measure(Echo("us_roof", 0.8), Eigen::Vector3d(10.0, 0.12, 0.0), Covariance(0.05, 0.01));
    ADD_FAILURE() << "an unknown ranger was accepted";
  } catch (const std::invalid_argument& e) {
    EXPECT_THAT(e.what(), HasSubstr("'us_roof' is not an ultrasonic sensor of the vehicle"));
  }
  EXPECT_EQ(updater.stats().echoes, 0u);
}

TEST(MapAidedUpdater, ARangeThatIsNotAFinitePositiveNumberIsRefusedAndNotCounted) {
  MapAidedUpdater updater = UpdaterWith(OneRow());
  const Eigen::Vector3d pose(10.0, 0.12, 0.0);
  for (const std::optional<double> range :
       {std::optional<double>(std::nan("")), std::optional<double>(std::numeric_limits<double>::infinity()),
        std::optional<double>(-0.2), std::optional<double>(0.0), std::optional<double>()}) {
    EXPECT_THROW(updater.Measure(Echo("us_front_left", range), pose, Covariance(0.05, 0.01)), std::invalid_argument);
  }
  EXPECT_EQ(updater.stats().echoes, 0u);
}

TEST(MapAidedUpdater, MapsAreCheckedAndNeededAndAVehicleWithoutRangersCannotUseOne) {
  MapAidedUpdater updater(mapio::VineyardUgv4wsConfig(), MapAidedConfig{}, kOrigin);
  EXPECT_FALSE(updater.has_row_map());
  EXPECT_THROW(updater.Measure(Echo("us_front_left", 0.4), Eigen::Vector3d::Zero(), Covariance(0.05, 0.01)),
               std::logic_error);
  geometry::RowMap empty;
  empty.origin = kOrigin;
  EXPECT_THROW(updater.AttachRowMap(empty), std::invalid_argument);
  EXPECT_FALSE(updater.has_row_map());
  updater.AttachRowMap(OneRow());
  EXPECT_TRUE(updater.has_row_map());

  mapio::VehicleConfig bare = mapio::VineyardUgv4wsConfig();
  bare.ultrasonic.clear();
  MapAidedUpdater no_rangers(bare, MapAidedConfig{}, kOrigin);
  try {
    no_rangers.AttachRowMap(OneRow());
    ADD_FAILURE() << "a vehicle without rangers took a map";
  } catch (const std::invalid_argument& e) {
    EXPECT_THAT(e.what(), HasSubstr("has no ultrasonic sensor"));
  }
}

TEST(MapAidedUpdater, ABadConfigIsRefused) {
  MapAidedConfig config;
  config.k_sigma = 0.0;
  EXPECT_THROW(MapAidedUpdater(mapio::VineyardUgv4wsConfig(), config, kOrigin), FilterConfigError);
}

}  // namespace
}  // namespace rowloc::localization
