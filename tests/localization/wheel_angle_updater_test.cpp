// WheelAngleUpdater (wheel_angle_updater.hpp) on its own: when a wheels message's angles anchor the
// wheel-angle states, update them, or leave the wheels to the speeds (at rest; rates not yet known),
// the update's innovation, Jacobian, noise and gate, and the refusals.
#include "rowloc/localization/wheel_angle_updater.hpp"

#include "rowloc/localization/kalman_update.hpp"
#include "rowloc/mapio/vehicle_config.hpp"

#include <gtest/gtest.h>

#include <stdexcept>
#include <vector>

namespace rowloc::localization {
namespace {

struct Swerve {
  mapio::VehicleConfig v = mapio::AgrimaroSwerveConfig();  // wheels left_front, left_rear, right
  StateLayout layout = StateLayout::For(v, {.wheel_angles = true});
  WheelNoise config;  // angle_sigma_rad 1.77e-3, angle_max_prediction_sigma_rad 6.14e-3
  WheelAngleUpdater angles{config, layout};
  /// A message listing the wheels as right, left_front, left_rear.
  const std::vector<std::size_t> permuted{2, 0, 1};
  /// The angles' variances: `sigma_rad` squared on every angle state.
  Eigen::MatrixXd Covariance(double sigma_rad) const {
    Eigen::MatrixXd p = Eigen::MatrixXd::Identity(layout.size, layout.size);
    for (const int k : layout.wheel_angle) p(k, k) = sigma_rad * sigma_rad;
    return p;
  }
  WheelAngleStep Plan(std::vector<double> angles_rad, double sigma_rad = 1e-3) {
    return angles.Plan({1.0, {0.0, 0.0, 0.0}, std::nullopt, std::move(angles_rad)}, permuted, Covariance(sigma_rad));
  }
};

TEST(WheelAngleUpdater, TheFirstAnglesAnchorTheStatesInVehicleOrder) {
  Swerve s;
  EXPECT_FALSE(s.angles.anchored());
  EXPECT_EQ(s.Plan({3.0, 1.0, 2.0}), WheelAngleStep::kAnchor);
  EXPECT_EQ(s.angles.measured(), Eigen::Vector3d(1.0, 2.0, 3.0));
  EXPECT_DOUBLE_EQ(s.angles.anchor_variance(), 1.77e-3 * 1.77e-3);
  // Until the filter reports the anchoring, the same angles anchor again.
  EXPECT_EQ(s.Plan({3.0, 1.0, 2.0}), WheelAngleStep::kAnchor);
  s.angles.MarkAnchored();
  EXPECT_TRUE(s.angles.anchored());
}

TEST(WheelAngleUpdater, AnchoredTheAnglesUpdateUnlessAtRestOrTheRatesAreUnknown) {
  Swerve s;
  s.Plan({3.0, 1.0, 2.0});
  s.angles.MarkAnchored();
  // No wheel ticked: the speeds are used, the angles kept.
  EXPECT_EQ(s.Plan({3.0, 1.0, 2.0}), WheelAngleStep::kUseSpeeds);
  // One wheel ticked, every predicted sigma within one tick (6.14e-3 rad): the update.
  EXPECT_EQ(s.Plan({3.01, 1.0, 2.0}, 6.0e-3), WheelAngleStep::kUpdate);
  EXPECT_EQ(s.angles.measured(), Eigen::Vector3d(1.0, 2.0, 3.01));
  // A predicted sigma above it: re-anchor and use the speeds.
  EXPECT_EQ(s.Plan({3.02, 1.0, 2.0}, 6.3e-3), WheelAngleStep::kAnchorAndUseSpeeds);
  EXPECT_EQ(s.angles.measured(), Eigen::Vector3d(1.0, 2.0, 3.02));
  // After a re-initialisation the states hold nothing: anchored again, even at rest.
  s.angles.Unanchor();
  EXPECT_EQ(s.Plan({3.02, 1.0, 2.0}), WheelAngleStep::kAnchor);
}

TEST(WheelAngleUpdater, TheUpdateMeasuresTheAngleStates) {
  Swerve s;
  s.Plan({3.0, 1.0, 2.0});
  s.angles.MarkAnchored();
  ASSERT_EQ(s.Plan({3.5, 1.25, 2.0}), WheelAngleStep::kUpdate);
  Eigen::VectorXd x = Eigen::VectorXd::Zero(s.layout.size);
  const Eigen::Vector3d theta(1.2, 2.1, 3.4);  // vehicle order
  for (std::size_t i = 0; i < 3; ++i) x(s.layout.wheel_angle[i]) = theta(static_cast<Eigen::Index>(i));
  const WheelAngleMeasurement& m = s.angles.Measure(x);
  ASSERT_EQ(m.innovation.size(), 3);
  EXPECT_NEAR((m.innovation - (Eigen::Vector3d(1.25, 2.0, 3.5) - theta)).norm(), 0.0, 1e-12);
  for (Eigen::Index row = 0; row < 3; ++row) {
    for (Eigen::Index c = 0; c < x.size(); ++c) {
      EXPECT_EQ(m.model.jacobian(row, c), c == s.layout.wheel_angle[static_cast<std::size_t>(row)] ? 1.0 : 0.0);
    }
  }
  EXPECT_EQ(m.noise, Eigen::Matrix3d(Eigen::Vector3d::Constant(1.77e-3 * 1.77e-3).asDiagonal()));
  EXPECT_EQ(m.gate, ChiSquareGate(3, s.config.gate_probability));
}

TEST(WheelAngleUpdater, PlanningNeedsAngleStatesAndAngles) {
  Swerve s;
  const formats::WheelsMessage no_angles{1.0, {0.0, 0.0, 0.0}, std::nullopt, std::nullopt};
  EXPECT_THROW(s.angles.Plan(no_angles, s.permuted, s.Covariance(1e-3)), std::logic_error);
  const StateLayout plain = StateLayout::For(s.v, {});
  WheelAngleUpdater without(s.config, plain);
  const formats::WheelsMessage with_angles{1.0, {0.0, 0.0, 0.0}, std::nullopt, std::vector<double>{0.0, 0.0, 0.0}};
  EXPECT_THROW(without.Plan(with_angles, s.permuted, Eigen::MatrixXd::Identity(plain.size, plain.size)),
               std::logic_error);
}

}  // namespace
}  // namespace rowloc::localization
