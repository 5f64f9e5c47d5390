// SmoothingRecorder (smoothing_recorder.hpp) on its own: the angle states it hands the smoother,
// every hook a no-op while disabled, enabling and finishing, and small recorded passes whose
// smoothed states are known: a later measurement reaches back through an identity transition and
// through rows added with a scale, and not through a state set anew (rows_reset).
#include "rowloc/localization/smoothing_recorder.hpp"

#include "rowloc/mapio/vehicle_config.hpp"

#include <gtest/gtest.h>

#include <stdexcept>
#include <vector>

namespace rowloc::localization {
namespace {

using L = StateLayout;

/// A differential-drive layout: the 9 base states, the heading the only angle.
StateLayout Plain() { return StateLayout::For(mapio::DifferentialDriveConfig(), false); }

/// The scalar update of state i by z with variance r (the filter's update, written out).
void UpdateState(Eigen::VectorXd& x, Eigen::MatrixXd& p, int i, double z, double r) {
  const double s = p(i, i) + r;
  const Eigen::VectorXd k = p.col(i) / s;
  x += k * (z - x(i));
  p -= k * k.transpose() * s;
}

struct Pass {
  StateLayout layout = Plain();
  SmoothingRecorder recorder{layout};
  Eigen::VectorXd x = Eigen::VectorXd::Zero(layout.size);
  Eigen::MatrixXd p = Eigen::MatrixXd::Identity(layout.size, layout.size);
  Pass() {
    recorder.Enable(/*check_transitions=*/true);
    recorder.Start(x, p);
    EXPECT_EQ(recorder.Mark(0.0, x, p), 0u);
  }
};

TEST(SmoothingRecorder, TheAnglesAreTheHeadingAndTheSteeringStates) {
  const mapio::VehicleConfig swerve = mapio::AgrimaroSwerveConfig();
  const StateLayout layout = StateLayout::For(swerve, {.slip_aware_odometry = true, .wheel_angles = true});
  const SmoothingRecorder recorder(layout);
  std::vector<int> expected{L::kPhi};
  for (const int d : layout.steering) {
    if (d >= 0) expected.push_back(d);
  }
  ASSERT_EQ(expected.size(), 4u);  // three steered modules
  EXPECT_EQ(recorder.angle_states(), expected);  // not the wheel angles (cumulative)
  EXPECT_EQ(SmoothingRecorder(Plain()).angle_states(), std::vector<int>{L::kPhi});
}

TEST(SmoothingRecorder, DisabledEveryHookDoesNothingAndMarkingIsRefused) {
  const StateLayout layout = Plain();
  SmoothingRecorder recorder(layout);
  const Eigen::VectorXd x = Eigen::VectorXd::Zero(layout.size);
  const Eigen::MatrixXd p = Eigen::MatrixXd::Identity(layout.size, layout.size);
  EXPECT_FALSE(recorder.enabled());
  EXPECT_EQ(recorder.smoother(), nullptr);
  recorder.Start(x, p);
  recorder.BeginTransition(x, p, {L::kX});
  recorder.TransitionBlock(0, Eigen::MatrixXd::Identity(2, 2));
  recorder.TransitionAddRows({L::kY}, 0.1, Eigen::MatrixXd::Ones(1, layout.size));
  recorder.BeginUpdate(x, p);
  recorder.End(x, p);
  EXPECT_EQ(recorder.smoother(), nullptr);
  EXPECT_THROW(recorder.Mark(0.0, x, p), std::logic_error);
  EXPECT_THROW(recorder.Finish(x, p), std::logic_error);
}

TEST(SmoothingRecorder, EnabledOnceAndFinishingDisables) {
  Pass pass;
  ASSERT_TRUE(pass.recorder.enabled());
  ASSERT_NE(pass.recorder.smoother(), nullptr);
  EXPECT_TRUE(pass.recorder.smoother()->recording());
  EXPECT_EQ(pass.recorder.smoother()->marks(), 1u);
  EXPECT_THROW(pass.recorder.Enable(false), std::logic_error);
  const std::vector<SmoothedState> smoothed = pass.recorder.Finish(pass.x, pass.p);
  EXPECT_FALSE(pass.recorder.enabled());
  EXPECT_EQ(pass.recorder.smoother(), nullptr);
  ASSERT_EQ(smoothed.size(), 1u);
  EXPECT_EQ(smoothed[0].state, pass.x);  // nothing after the mark: the filtered state
  pass.recorder.Enable(false);  // may be enabled again
  EXPECT_TRUE(pass.recorder.enabled());
}

TEST(SmoothingRecorder, ALaterMeasurementReachesBackThroughAnIdentityTransition) {
  Pass pass;
  pass.recorder.BeginTransition(pass.x, pass.p);
  pass.recorder.TransitionBlock(0, Eigen::MatrixXd::Identity(L::kBaseSize, L::kBaseSize));  // no noise
  pass.recorder.BeginUpdate(pass.x, pass.p);
  UpdateState(pass.x, pass.p, L::kX, 2.0, 1.0);  // x: 0 -> 1, variance 1 -> 0.5
  EXPECT_EQ(pass.recorder.Mark(1.0, pass.x, pass.p), 1u);
  EXPECT_GT(pass.recorder.smoother()->min_relative_process_noise(), -1e-12);
  const std::vector<SmoothedState> smoothed = pass.recorder.Finish(pass.x, pass.p);
  ASSERT_EQ(smoothed.size(), 2u);
  EXPECT_EQ(smoothed[0].time_s, 0.0);
  EXPECT_NEAR(smoothed[0].state(L::kX), 1.0, 1e-12);  // filtered: 0
  EXPECT_NEAR(smoothed[0].covariance(L::kX, L::kX), 0.5, 1e-12);  // filtered: 1
  EXPECT_NEAR(smoothed[1].state(L::kX), 1.0, 1e-12);
}

TEST(SmoothingRecorder, AddedRowsCarryTheirScale) {
  // y <- y + 0.5 x, then y measured at 1 (nearly exactly): x = 0.4, y = 1 after the step, so
  // before it, with no process noise, x = 0.4 and y = 1 - 0.5 x = 0.8.
  Pass pass;
  pass.recorder.BeginTransition(pass.x, pass.p);
  Eigen::MatrixXd m = Eigen::MatrixXd::Zero(1, pass.layout.size);
  m(0, L::kX) = 1.0;
  pass.recorder.TransitionAddRows({L::kY}, 0.5, m);
  Eigen::MatrixXd f = Eigen::MatrixXd::Identity(pass.layout.size, pass.layout.size);
  f(L::kY, L::kX) = 0.5;
  pass.x = f * pass.x;
  pass.p = f * pass.p * f.transpose();
  pass.recorder.BeginUpdate(pass.x, pass.p);
  UpdateState(pass.x, pass.p, L::kY, 1.0, 1e-9);
  EXPECT_GT(pass.recorder.smoother()->min_relative_process_noise(), -1e-9);
  const std::vector<SmoothedState> smoothed = pass.recorder.Finish(pass.x, pass.p);
  ASSERT_EQ(smoothed.size(), 1u);
  EXPECT_NEAR(smoothed[0].state(L::kX), 0.4, 1e-6);
  EXPECT_NEAR(smoothed[0].state(L::kY), 0.8, 1e-6);
}

TEST(SmoothingRecorder, AStateSetAnewCutsTheSmoothingOfThatState) {
  Pass pass;
  pass.recorder.BeginTransition(pass.x, pass.p, {L::kX});  // x re-anchored to 5 with variance 0.1
  pass.p.row(L::kX).setZero();
  pass.p.col(L::kX).setZero();
  pass.p(L::kX, L::kX) = 0.1;
  pass.x(L::kX) = 5.0;
  pass.recorder.BeginUpdate(pass.x, pass.p);
  UpdateState(pass.x, pass.p, L::kX, 7.0, 0.1);  // x: 5 -> 6
  UpdateState(pass.x, pass.p, L::kY, 3.0, 1.0);  // y: 0 -> 1.5, a state carried through
  EXPECT_GT(pass.recorder.smoother()->min_relative_process_noise(), -1e-12);
  const std::vector<SmoothedState> smoothed = pass.recorder.Finish(pass.x, pass.p);
  ASSERT_EQ(smoothed.size(), 1u);
  EXPECT_NEAR(smoothed[0].state(L::kX), 0.0, 1e-12);  // the measurement of the new x says nothing of the old
  EXPECT_NEAR(smoothed[0].covariance(L::kX, L::kX), 1.0, 1e-12);
  EXPECT_NEAR(smoothed[0].state(L::kY), 1.5, 1e-12);
}

}  // namespace
}  // namespace rowloc::localization
