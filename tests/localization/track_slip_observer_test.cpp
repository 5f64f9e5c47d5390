#include "rowloc/localization/track_slip_observer.hpp"

#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <limits>
#include <numbers>
#include <random>
#include <string>
#include <vector>

namespace rowloc::localization {
namespace {

using ::testing::HasSubstr;
constexpr double kPi = std::numbers::pi;
constexpr double kTrackWidthM = 1.1;  // config/vehicles/tracked.json: tracks at y = +-0.55 m

// Constant track speeds and slip (Tazzari et al. n.d. Assumption 1), driven from pose (2, -1, 0.3).
struct Motion {
  double eta_right, eta_left, v_right_mps, v_left_mps;
};

// Pose at time t: closed-form integral of eq. (5) (an arc; a line when the yaw rate is 0).
Eigen::Vector3d ExactPose(const Motion& m, double t) {
  const double speed = 0.5 * (m.eta_right * m.v_right_mps + m.eta_left * m.v_left_mps);
  const double yaw_rate = (m.eta_right * m.v_right_mps - m.eta_left * m.v_left_mps) / kTrackWidthM;
  const double half = 0.5 * yaw_rate * t;
  const double chord = speed * t * (std::abs(half) < 1e-9 ? 1.0 : std::sin(half) / half);
  const double mid = 0.3 + half;
  return {2.0 + chord * std::cos(mid), -1.0 + chord * std::sin(mid), 0.3 + yaw_rate * t};
}

TrackSlipInput ExactInput(const Motion& m, double t) {
  const Eigen::Vector3d pose = ExactPose(m, t);
  return {t, pose.x(), pose.y(), std::remainder(pose.z(), 2 * kPi), m.v_right_mps, m.v_left_mps};
}

double RelativeError(const TrackSlipObserver& observer, const Motion& m) {
  return std::max(std::abs(observer.eta_right() / m.eta_right - 1.0),
                  std::abs(observer.eta_left() / m.eta_left - 1.0));
}

// Feeds exact data at `rate_hz` for `duration_s`; returns the settling time: the last time at
// which the relative error of either estimate was above 1 %.
double RunExact(TrackSlipObserver& observer, const Motion& m, double rate_hz, double duration_s) {
  double settled_s = 0.0;
  const auto steps = static_cast<int>(std::lround(duration_s * rate_hz));
  for (int k = 0; k <= steps; ++k) {
    const double t = k / rate_hz;
    observer.Update(ExactInput(m, t));
    if (RelativeError(observer, m) > 0.01) settled_s = t;
  }
  return settled_s;
}

// Random slip pairs in (0.6, 1.0) and a right track speed in (0.6, 1.2) m/s.
std::vector<Motion> RandomMotions(bool straight, std::uint32_t seed) {
  std::mt19937 rng(seed);
  std::uniform_real_distribution<double> eta(0.6, 1.0), speed(0.6, 1.2), ratio(0.5, 0.8);
  std::vector<Motion> motions;
  for (int i = 0; i < 5; ++i) {
    Motion m{eta(rng), eta(rng), speed(rng), 0.0};
    // Straight: eta_R v_R = eta_L v_L; circle: the left track slower (a left turn of radius ~1-4 m).
    m.v_left_mps = straight ? m.eta_right * m.v_right_mps / m.eta_left : ratio(rng) * m.v_right_mps;
    motions.push_back(m);
  }
  return motions;
}

// `action` must throw std::invalid_argument with `text` in its message.
template <typename Action>
void ExpectInvalidArgument(Action action, const std::string& text) {
  try {
    action();
    ADD_FAILURE() << "no std::invalid_argument, expected \"" << text << "\"";
  } catch (const std::invalid_argument& error) {
    EXPECT_THAT(error.what(), HasSubstr(text));
  }
}

TEST(TrackSlipObserverConfig, DefaultIsValidAndEachBadFieldIsNamed) {
  EXPECT_FALSE(TrackSlipObserverConfigProblem({}).has_value());
  const auto expect_problem = [](auto mutate, const char* field) {
    TrackSlipObserverConfig config;
    mutate(config);
    const auto problem = TrackSlipObserverConfigProblem(config);
    ASSERT_TRUE(problem.has_value()) << field;
    EXPECT_THAT(*problem, HasSubstr(field));
    ExpectInvalidArgument([&] { TrackSlipObserver observer(config); }, *problem);
  };
  const double nan = std::numeric_limits<double>::quiet_NaN();
  expect_problem([](auto& c) { c.track_width_m = 0.0; }, "track_width_m");
  expect_problem([&](auto& c) { c.track_width_m = nan; }, "track_width_m");
  expect_problem([](auto& c) { c.injection_gains_per_s[2] = -1.0; }, "injection_gains_per_s[2]");
  expect_problem([](auto& c) { c.adaptation_gains[0] = 0.0; }, "adaptation_gains[0]");
  expect_problem([](auto& c) { c.eta_min = -0.1; }, "eta_min");
  expect_problem([](auto& c) { c.eta_max = 2.5; }, "eta_max");
  expect_problem([](auto& c) { c.eta_min = 1.2; c.eta_max = 1.1; }, "eta_min");
  expect_problem([](auto& c) { c.eta_max = 0.9; }, "initial_eta_right");
  expect_problem([](auto& c) { c.initial_eta_left = 2.0; c.eta_max = 1.5; }, "initial_eta_left");
  expect_problem([](auto& c) { c.max_step_s = 0.0; }, "max_step_s");
  expect_problem([](auto& c) { c.max_step_s = std::numeric_limits<double>::infinity(); }, "max_step_s");
}

TEST(TrackSlipObserver, FirstUpdateInitialisesFromTheMeasurementAndResetForgets) {
  TrackSlipObserverConfig config;
  config.initial_eta_right = 0.9;
  TrackSlipObserver observer(config);
  EXPECT_FALSE(observer.initialised());
  EXPECT_FALSE(observer.last_time_s().has_value());
  EXPECT_EQ(observer.Update({5.0, 1.0, 2.0, 3.5, 1.0, 1.0}), TrackSlipStep::kInitialised);
  EXPECT_TRUE(observer.initialised());
  EXPECT_EQ(observer.last_time_s(), 5.0);
  EXPECT_TRUE(observer.state().isApprox(Eigen::Vector3d(1.0, 2.0, 3.5 - 2 * kPi)));
  EXPECT_EQ(observer.observation_error(), Eigen::Vector3d::Zero());
  EXPECT_EQ(observer.eta_right(), 0.9);
  EXPECT_EQ(observer.Update({5.0, 9.0, 9.0, 0.0, 1.0, 1.0}), TrackSlipStep::kSameTime);
  EXPECT_EQ(observer.state().x(), 1.0);  // equal time: a no-op
  EXPECT_EQ(observer.Update({5.5, 1.5, 2.0, 3.5, 1.0, 1.0}), TrackSlipStep::kIntegrated);
  EXPECT_NE(observer.eta_right(), 0.9);
  observer.Reset();
  EXPECT_FALSE(observer.initialised());
  EXPECT_EQ(observer.eta_right(), 0.9);
  EXPECT_EQ(observer.eta_left(), 1.0);
}

TEST(TrackSlipObserver, EveryBadInputThrowsNamingTheFieldAndLeavesTheStateUnchanged) {
  TrackSlipObserver observer;
  observer.Update({0.0, 0.0, 0.0, 0.0, 1.0, 0.8});
  observer.Update({0.1, 0.09, 0.0, 0.01, 1.0, 0.8});
  const Eigen::Vector3d state = observer.state();
  const double eta_right = observer.eta_right();
  const TrackSlipInput good{0.2, 0.18, 0.0, 0.02, 1.0, 0.8};
  const double bad_values[] = {std::numeric_limits<double>::quiet_NaN(), std::numeric_limits<double>::infinity(),
                               -std::numeric_limits<double>::infinity()};
  const std::pair<double TrackSlipInput::*, const char*> fields[] = {
      {&TrackSlipInput::time_s, "time_s"},         {&TrackSlipInput::x_m, "x_m"},
      {&TrackSlipInput::y_m, "y_m"},               {&TrackSlipInput::theta_rad, "theta_rad"},
      {&TrackSlipInput::v_right_mps, "v_right_mps"}, {&TrackSlipInput::v_left_mps, "v_left_mps"}};
  for (const auto& [member, name] : fields) {
    for (const double bad : bad_values) {
      TrackSlipInput input = good;
      input.*member = bad;
      ExpectInvalidArgument([&] { observer.Update(input); }, std::string(name) + " must be finite");
    }
  }
  const auto expect_message = [&](const TrackSlipInput& input, const char* text) {
    ExpectInvalidArgument([&] { observer.Update(input); }, text);
  };
  expect_message({0.05, 0.18, 0.0, 0.02, 1.0, 0.8}, "time_s 0.05 is before the previous time_s 0.1");
  expect_message({0.2, 0.18, 0.0, 0.02, 1.0, -150.0}, "v_left_mps -150 is beyond +-100 m/s");
  expect_message({0.2, -1e308, 0.0, 0.02, 1.0, 0.8}, "overflowed");
  EXPECT_EQ(observer.state(), state);
  EXPECT_EQ(observer.eta_right(), eta_right);
  EXPECT_EQ(observer.last_time_s(), 0.1);
  EXPECT_EQ(observer.Update(good), TrackSlipStep::kIntegrated);  // still usable
}

TEST(TrackSlipObserver, ExactDataGeneratorIntegratesEquation5) {
  // The closed-form arc against RK4 of eq. (5) with 1 ms steps.
  const Motion m{0.8, 0.9, 1.2, 0.7};
  Eigen::Vector3d pose(2.0, -1.0, 0.3);
  const auto rate = [&](const Eigen::Vector3d& p) {
    const double speed = 0.5 * (m.eta_right * m.v_right_mps + m.eta_left * m.v_left_mps);
    return Eigen::Vector3d(speed * std::cos(p.z()), speed * std::sin(p.z()),
                           (m.eta_right * m.v_right_mps - m.eta_left * m.v_left_mps) / kTrackWidthM);
  };
  const double h = 1e-3;
  for (int k = 0; k < 20000; ++k) {
    const Eigen::Vector3d k1 = rate(pose), k2 = rate(pose + 0.5 * h * k1);
    const Eigen::Vector3d k3 = rate(pose + 0.5 * h * k2), k4 = rate(pose + h * k3);
    pose += h / 6.0 * (k1 + 2 * k2 + 2 * k3 + k4);
  }
  EXPECT_LT((pose - ExactPose(m, 20.0)).norm(), 1e-9);
}

// Both eta are identified from (1, 1) on a circle and on a straight line (det Psi^T Psi =
// v_R^2 v_L^2 / (4 d^2) > 0), at every sensor rate, for random slip pairs.
class TrackSlipConvergence : public ::testing::TestWithParam<std::tuple<bool, double>> {};

TEST_P(TrackSlipConvergence, ExactDataConvergesFromUnitEstimates) {
  const auto [straight, rate_hz] = GetParam();
  for (const Motion& m : RandomMotions(straight, 7)) {
    TrackSlipObserver observer;
    const double settled_s = RunExact(observer, m, rate_hz, 150.0);
    EXPECT_LE(settled_s, 40.0) << "eta " << m.eta_right << ", " << m.eta_left;
    EXPECT_LT(RelativeError(observer, m), 1e-8);
    EXPECT_LT(observer.observation_error().norm(), 1e-8);
  }
}

INSTANTIATE_TEST_SUITE_P(CircleAndLine, TrackSlipConvergence,
                         ::testing::Combine(::testing::Bool(), ::testing::Values(1.0, 10.0, 50.0, 200.0)));

TEST(TrackSlipObserver, DrivingBackwardsIsIdentifiedToo) {
  TrackSlipObserver observer;
  const Motion m{0.75, 0.95, -0.9, -0.6};
  RunExact(observer, m, 20.0, 150.0);
  EXPECT_LT(RelativeError(observer, m), 1e-8);
}

// V = 1/2 (e^T e + eta~^T Lambda^-1 eta~) never grows on exact data, for any rate, non-identity
// gains, and with the projection active (estimates start on the bound of a narrow box).
TEST(TrackSlipObserver, LyapunovFunctionNeverIncreasesOnExactData) {
  TrackSlipObserverConfig config;
  config.injection_gains_per_s = {0.5, 3.0, 2.0};
  config.adaptation_gains = {2.0, 0.8};
  config.eta_min = 0.5;
  config.eta_max = 1.5;
  config.initial_eta_right = 1.5;
  config.initial_eta_left = 0.5;
  config.max_step_s = std::nullopt;
  for (const double rate_hz : {0.2, 1.0, 10.0, 200.0}) {
    for (const Motion& m : RandomMotions(false, 3)) {
      TrackSlipObserver observer(config);
      observer.Update(ExactInput(m, 0.0));
      const double initial = observer.Lyapunov(m.eta_right, m.eta_left);
      double previous = initial;
      for (int k = 1; k <= static_cast<int>(200.0 * rate_hz); ++k) {
        observer.Update(ExactInput(m, k / rate_hz));
        const double v = observer.Lyapunov(m.eta_right, m.eta_left);
        ASSERT_LE(v, previous * (1.0 + 1e-10) + 1e-18) << "rate " << rate_hz << " step " << k;
        previous = v;
      }
      EXPECT_LT(previous, 1e-6 * initial) << "rate " << rate_hz;
    }
  }
}

// Tazzari et al. n.d. write V with e^T L^-1 e; its cross terms only cancel for L = I, and for L = 0.2 I that
// V grows on exact data although the observer converges (the erratum in the header comment).
TEST(TrackSlipObserver, PaperLyapunovWithLInverseIsNotMonotoneForNonIdentityL) {
  TrackSlipObserverConfig config;
  config.injection_gains_per_s = Eigen::Vector3d::Constant(0.2);
  TrackSlipObserver observer(config);
  const Motion m{0.7, 0.9, 1.0, 0.6};
  int increases = 0;
  double previous = std::numeric_limits<double>::infinity();
  for (int k = 0; k <= 2000; ++k) {
    observer.Update(ExactInput(m, k / 50.0));
    const Eigen::Vector2d eta_error(observer.eta_right() - m.eta_right, observer.eta_left() - m.eta_left);
    const double paper_v = 0.5 * (observer.observation_error().squaredNorm() / 0.2 + eta_error.squaredNorm());
    increases += paper_v > previous * (1.0 + 1e-9) ? 1 : 0;
    previous = paper_v;
  }
  EXPECT_GT(increases, 100);
  EXPECT_LT(RelativeError(observer, m), 0.01);
}

// Large steps (1 s, 5 s, random gaps up to 8 s) with stiff gains (an explicit Euler step would
// diverge for l h > 2): no blow-up, estimates in the box, and still convergence on exact data.
TEST(TrackSlipObserver, LargeStepsAndStiffGainsStayStable) {
  TrackSlipObserverConfig config;
  config.injection_gains_per_s = {50.0, 50.0, 50.0};
  config.adaptation_gains = {50.0, 50.0};
  config.max_step_s = std::nullopt;
  std::mt19937 rng(5);
  std::uniform_real_distribution<double> gap(0.005, 8.0);
  for (const Motion& m : RandomMotions(false, 11)) {
    TrackSlipObserver observer(config);
    double t = 0.0;
    for (int k = 0; k < 300; ++k, t += (k % 3 == 0 ? 1.0 : k % 3 == 1 ? 5.0 : gap(rng))) {
      observer.Update(ExactInput(m, t));
      ASSERT_TRUE(observer.state().allFinite());
      ASSERT_GE(std::min(observer.eta_right(), observer.eta_left()), config.eta_min);
      ASSERT_LE(std::max(observer.eta_right(), observer.eta_left()), config.eta_max);
    }
    EXPECT_LT(RelativeError(observer, m), 1e-6);
    observer.Update(ExactInput(m, t + 1e4));  // a 3-hour step: still exact, still finite
    EXPECT_LT(RelativeError(observer, m), 1e-6);
  }
}

TEST(TrackSlipObserver, GapLongerThanMaxStepRestartsThePoseAndKeepsEta) {
  TrackSlipObserver observer;  // max_step_s = 2 s
  const Motion m{0.7, 0.9, 1.0, 0.6};
  RunExact(observer, m, 10.0, 100.0);
  const double eta_right = observer.eta_right();
  const TrackSlipInput after_gap{105.0, 50.0, 50.0, 1.0, 0.0, 0.0};  // somewhere else, stopped
  EXPECT_EQ(observer.Update(after_gap), TrackSlipStep::kGapRestarted);
  EXPECT_EQ(observer.eta_right(), eta_right);
  EXPECT_TRUE(observer.state().isApprox(Eigen::Vector3d(50.0, 50.0, 1.0)));
  EXPECT_EQ(observer.observation_error(), Eigen::Vector3d::Zero());
}

// A pivot-like turn sampled every 3 s turns 4.5 rad per step (more than pi): the heading branch
// predicted from eta^ keeps it unaliased, and 2 pi offsets of the measured heading do not matter.
TEST(TrackSlipObserver, HeadingIsUnwrappedByThePredictionAndWrapped) {
  TrackSlipObserverConfig config;
  config.max_step_s = std::nullopt;
  const Motion m{0.8, 0.85, 1.2, -0.8};  // yaw rate 1.49 rad/s
  TrackSlipObserver observer(config), shifted(config);
  RunExact(observer, m, 50.0, 100.0);
  RunExact(shifted, m, 50.0, 100.0);
  for (double t = 103.0; t < 200.0; t += 3.0) {
    TrackSlipInput input = ExactInput(m, t);
    observer.Update(input);
    input.theta_rad += 2 * kPi * std::round(std::sin(t) * 5.0);
    shifted.Update(input);
    EXPECT_GT(observer.state().z(), -kPi);
    EXPECT_LE(observer.state().z(), kPi);
  }
  EXPECT_LT(RelativeError(observer, m), 1e-8);
  EXPECT_NEAR(shifted.eta_right(), observer.eta_right(), 1e-9);
  EXPECT_NEAR(shifted.eta_left(), observer.eta_left(), 1e-9);
}

// Gaussian noise: pose 2 cm and 0.5 deg, track speeds 1 %. The mean estimate over the last third
// of a 300 s circle is within 1 % of the truth at every rate.
TEST(TrackSlipObserver, NoisyMeasurementsStillConvergeWithinOnePercent) {
  std::mt19937 rng(42);
  std::normal_distribution<double> unit(0.0, 1.0);
  for (const double rate_hz : {1.0, 10.0, 50.0, 200.0}) {
    for (const Motion& m : RandomMotions(false, 13)) {
      TrackSlipObserver observer;
      const int steps = static_cast<int>(300.0 * rate_hz);
      Eigen::Vector2d sum = Eigen::Vector2d::Zero();
      int count = 0;
      for (int k = 0; k <= steps; ++k) {
        TrackSlipInput input = ExactInput(m, k / rate_hz);
        input.x_m += 0.02 * unit(rng);
        input.y_m += 0.02 * unit(rng);
        input.theta_rad += 0.5 * kPi / 180.0 * unit(rng);
        input.v_right_mps *= 1.0 + 0.01 * unit(rng);
        input.v_left_mps *= 1.0 + 0.01 * unit(rng);
        observer.Update(input);
        if (3 * k >= 2 * steps) {
          sum += Eigen::Vector2d(observer.eta_right(), observer.eta_left());
          ++count;
        }
      }
      const Eigen::Vector2d mean = sum / count;
      EXPECT_NEAR(mean.x() / m.eta_right, 1.0, 0.01) << "rate " << rate_hz;
      EXPECT_NEAR(mean.y() / m.eta_left, 1.0, 0.01) << "rate " << rate_hz;
    }
  }
}

}  // namespace
}  // namespace rowloc::localization
