// Validation metrics: hand-computed cases for each metric, and statistical properties (NEES of
// estimates drawn from their own covariance, whiteness of white noise) with fixed seeds.
#include "rowloc/sim/metrics.hpp"

#include "statistical_tests.hpp"

#include <Eigen/Cholesky>
#include <boost/math/distributions/chi_squared.hpp>
#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include <cmath>
#include <numbers>
#include <random>

namespace rowloc::sim {
namespace {

using ::testing::HasSubstr;
constexpr double kPi = std::numbers::pi;

formats::TruthSample Truth(double t, double x, double y, double phi, bool gnss = true) {
  formats::TruthSample s;
  s.t_s = t;
  s.position_m = {x, y};
  s.phi_rad = phi;
  s.gnss_available = gnss;
  return s;
}

formats::EstimateSample Estimate(double t, double x, double y, std::optional<double> phi = std::nullopt) {
  formats::EstimateSample e;
  e.t_s = t;
  e.position_m = {x, y};
  e.phi_rad = phi;
  return e;
}

/// Straight run along +x at 1 m/s, y = 0, heading 0, samples every second in [0, n - 1].
formats::TruthStream StraightTruth(int n) {
  formats::TruthStream t;
  t.source_name = "truth";
  for (int i = 0; i < n; ++i) t.samples.push_back(Truth(i, i, 0.0, 0.0));
  return t;
}

TEST(WrapAngle, WrapsIntoHalfOpenInterval) {
  EXPECT_DOUBLE_EQ(WrapAngle(0.5), 0.5);
  EXPECT_DOUBLE_EQ(WrapAngle(kPi), kPi);
  EXPECT_DOUBLE_EQ(WrapAngle(-kPi), kPi);
  EXPECT_NEAR(WrapAngle(3.0 * kPi / 2.0), -kPi / 2.0, 1e-12);
  EXPECT_NEAR(WrapAngle(-7.0), -7.0 + 2.0 * kPi, 1e-12);
  std::mt19937_64 rng(7);
  std::uniform_real_distribution<double> angle(-50.0, 50.0);
  for (int i = 0; i < 1000; ++i) {
    const double a = angle(rng);
    const double w = WrapAngle(a);
    EXPECT_GT(w, -kPi);
    EXPECT_LE(w, kPi);
    EXPECT_NEAR(std::remainder(a - w, 2.0 * kPi), 0.0, 1e-9);
  }
}

TEST(Summarize, HandComputed) {
  const ErrorStatistics s = Summarize({1.0, -2.0, 3.0});
  EXPECT_EQ(s.count, 3u);
  EXPECT_DOUBLE_EQ(s.mean, 2.0 / 3.0);
  EXPECT_DOUBLE_EQ(s.rms, std::sqrt(14.0 / 3.0));
  EXPECT_DOUBLE_EQ(s.std, std::sqrt(14.0 / 3.0 - 4.0 / 9.0));  // population: E[x^2] - mean^2
  EXPECT_DOUBLE_EQ(s.max_abs, 3.0);
  const ErrorStatistics empty = Summarize({});
  EXPECT_EQ(empty.count, 0u);
  EXPECT_EQ(empty.rms, 0.0);
}

TEST(InterpolateTruth, IsLinearAndHeadingTakesTheShortWayRound) {
  formats::TruthStream t;
  t.samples = {Truth(0.0, 0.0, 0.0, 3.1), Truth(2.0, 4.0, -2.0, -3.1)};
  t.samples[0].wheel_slip = {{"left", 0.1}, {"right", 0.2}};
  t.samples[1].wheel_slip = {{"left", 0.3}};
  t.samples[0].wheel_rolling_radius_m = {{"left", 0.16}, {"right", 0.15}};
  t.samples[1].wheel_rolling_radius_m = {{"right", 0.17}};
  const TruthState mid = InterpolateTruth(t, 1.0);
  EXPECT_DOUBLE_EQ(mid.position_m.x(), 2.0);
  EXPECT_DOUBLE_EQ(mid.position_m.y(), -1.0);
  // 3.1 -> -3.1 is +0.0832 rad through pi, not -6.2 rad through 0.
  EXPECT_NEAR(std::abs(mid.phi_rad), kPi, 1e-12);
  const TruthState quarter = InterpolateTruth(t, 0.5);
  EXPECT_NEAR(quarter.phi_rad, 3.1 + 0.25 * (2.0 * kPi - 6.2), 1e-12);
  EXPECT_DOUBLE_EQ(quarter.wheel_slip.at("left"), 0.15);
  EXPECT_EQ(quarter.wheel_slip.count("right"), 0u);  // not in both samples
  EXPECT_DOUBLE_EQ(quarter.wheel_rolling_radius_m.at("right"), 0.155);
  EXPECT_EQ(quarter.wheel_rolling_radius_m.count("left"), 0u);
  EXPECT_DOUBLE_EQ(InterpolateTruth(t, 2.0).wheel_rolling_radius_m.at("right"), 0.17);  // the last sample
  EXPECT_DOUBLE_EQ(InterpolateTruth(t, 2.0).position_m.x(), 4.0);  // end points inclusive
  EXPECT_DOUBLE_EQ(InterpolateTruth(t, 0.0).position_m.x(), 0.0);
}

TEST(InterpolateTruth, RefusesToExtrapolate) {
  const formats::TruthStream t = StraightTruth(3);
  EXPECT_THROW(InterpolateTruth(t, -0.001), EvaluationError);
  EXPECT_THROW(InterpolateTruth(t, 2.001), EvaluationError);
  EXPECT_THROW(InterpolateTruth(formats::TruthStream{}, 0.0), EvaluationError);
}

TEST(InterpolateTruth, HandlesRepeatedTimes) {
  formats::TruthStream t;
  t.samples = {Truth(0.0, 0.0, 0.0, 0.0), Truth(1.0, 1.0, 0.0, 0.0), Truth(1.0, 5.0, 0.0, 0.0), Truth(2.0, 6.0, 0.0, 0.0)};
  EXPECT_DOUBLE_EQ(InterpolateTruth(t, 1.5).position_m.x(), 5.5);
  EXPECT_DOUBLE_EQ(InterpolateTruth(t, 0.5).position_m.x(), 0.5);
}

TEST(PoseErrors, AlongAcrossRelativeToTrueHeadingLeftPositive) {
  formats::TruthStream truth;
  truth.samples = {Truth(0.0, 0.0, 0.0, kPi / 2.0), Truth(1.0, 0.0, 1.0, kPi / 2.0)};  // driving north
  formats::EstimateStream est;
  est.estimates = {Estimate(0.5, -0.1, 0.7, kPi / 2.0 + 0.05)};  // 0.1 m west (left), 0.2 m ahead
  const std::vector<PoseError> e = ComputePoseErrors(truth, est, std::nullopt);
  ASSERT_EQ(e.size(), 1u);
  EXPECT_NEAR(e[0].along_m, 0.2, 1e-12);
  EXPECT_NEAR(e[0].across_m, 0.1, 1e-12);
  EXPECT_NEAR(e[0].total_m, std::hypot(0.1, 0.2), 1e-12);
  EXPECT_NEAR(*e[0].heading_rad, 0.05, 1e-12);
  EXPECT_FALSE(e[0].nees);
}

TEST(PoseErrors, AlongAcrossRelativeToNearestRowOrientedWithTheVehicle) {
  geometry::RowMap map;
  map.rows = {{"r1", {{0.0, 1.0}, {10.0, 1.0}}, false}, {"r2", {{10.0, -1.0}, {0.0, -1.0}}, false}};
  const auto rows = geometry::SegmentIndex::FromRowMap(map);
  formats::TruthStream truth;
  // Near r2 (drawn -x), driving +x with a 0.3 rad heading offset: the reference is +x.
  truth.samples = {Truth(0.0, 5.0, -0.5, 0.3), Truth(1.0, 5.0, -0.5, 0.3),
                   Truth(2.0, 5.0, 0.8, kPi - 0.2), Truth(3.0, 5.0, 0.8, kPi - 0.2)};
  formats::EstimateStream est;
  est.estimates = {Estimate(0.5, 5.2, -0.4), Estimate(2.5, 5.2, 0.9)};
  const std::vector<PoseError> e = ComputePoseErrors(truth, est, rows);
  EXPECT_NEAR(e[0].along_m, 0.2, 1e-12);
  EXPECT_NEAR(e[0].across_m, 0.1, 1e-12);
  // Near r1, driving roughly -x: the reference is -x, left is -y.
  EXPECT_NEAR(e[1].along_m, -0.2, 1e-12);
  EXPECT_NEAR(e[1].across_m, -0.1, 1e-12);
}

TEST(PoseErrors, NeesHandComputedForThreeAndTwoDof) {
  const formats::TruthStream truth = StraightTruth(2);
  formats::EstimateStream est;
  formats::EstimateSample full = Estimate(0.0, 0.1, 0.2, 0.05);
  Eigen::Matrix3d p = Eigen::Vector3d(0.01, 0.04, 0.0025).asDiagonal();
  full.covariance = p;
  formats::EstimateSample no_heading = Estimate(0.5, 0.6, -0.2);  // 3x3 covariance but no phi: (x, y) only
  no_heading.covariance = p;
  formats::EstimateSample two = Estimate(1.0, 1.0, 0.3);
  Eigen::Matrix2d p2;
  p2 << 0.02, 0.01, 0.01, 0.02;
  two.covariance = p2;
  est.estimates = {full, no_heading, two};
  const std::vector<PoseError> e = ComputePoseErrors(truth, est, std::nullopt);
  EXPECT_NEAR(*e[0].nees, 1.0 + 1.0 + 1.0, 1e-12);
  EXPECT_EQ(e[0].nees_dof, 3);
  EXPECT_NEAR(*e[0].sigma_along_m, 0.1, 1e-12);
  EXPECT_NEAR(*e[0].sigma_across_m, 0.2, 1e-12);
  EXPECT_NEAR(*e[0].sigma_heading_rad, 0.05, 1e-12);
  EXPECT_NEAR(*e[1].nees, 0.1 * 0.1 / 0.01 + 0.04 / 0.04, 1e-12);
  EXPECT_EQ(e[1].nees_dof, 2);
  // [0 0.3] inv([[.02 .01][.01 .02]]) [0 0.3]' = 0.09 * 0.02 / (0.0004 - 0.0001) = 6
  EXPECT_NEAR(*e[2].nees, 6.0, 1e-9);
  EXPECT_EQ(e[2].nees_dof, 2);
  EXPECT_NEAR(*e[2].sigma_across_m, std::sqrt(0.02), 1e-12);
}

TEST(PoseErrors, SingularCovarianceHasNoNeesButIsCounted) {
  const formats::TruthStream truth = StraightTruth(2);
  formats::EstimateStream est;
  formats::EstimateSample known = Estimate(0.0, 0.0, 0.0, 0.0);
  known.covariance = Eigen::Matrix3d::Zero();
  formats::EstimateSample fine = Estimate(1.0, 1.0, 0.1, 0.0);
  fine.covariance = Eigen::Matrix3d::Identity();
  est.estimates = {known, fine};
  const EvaluationResult r = Evaluate(truth, est, {});
  EXPECT_TRUE(r.pose_errors[0].covariance_singular);
  EXPECT_FALSE(r.pose_errors[0].nees);
  EXPECT_DOUBLE_EQ(*r.pose_errors[0].sigma_across_m, 0.0);
  EXPECT_EQ(r.singular_covariance_count, 1u);
  EXPECT_EQ(r.nees.count, 1u);
  EXPECT_NEAR(r.nees.mean, 0.01, 1e-12);
}

TEST(PoseErrors, EstimateOutsideTruthNamesItsLine) {
  const formats::TruthStream truth = StraightTruth(3);
  formats::EstimateStream est;
  est.source_name = "est.ndjson";
  est.estimates = {Estimate(1.0, 1.0, 0.0), Estimate(2.5, 2.5, 0.0)};
  est.estimates[1].line = 7;
  try {
    ComputePoseErrors(truth, est, std::nullopt);
    FAIL() << "no error";
  } catch (const EvaluationError& e) {
    EXPECT_THAT(e.what(), HasSubstr("est.ndjson:7: estimate at time 2.5 s is outside the truth's span"));
  }
}

TEST(PositionSummary, AcrossIsAbsoluteWithSignedMean) {
  std::vector<PoseError> errors(2);
  errors[0].across_m = 0.3;
  errors[0].along_m = 0.4;
  errors[0].total_m = 0.5;
  errors[1].across_m = -0.1;
  errors[1].heading_rad = 0.2;
  const PositionSummary s = SummarizePoseErrors(errors);
  EXPECT_DOUBLE_EQ(s.across_abs_m.mean, 0.2);
  EXPECT_DOUBLE_EQ(s.across_abs_m.max_abs, 0.3);
  EXPECT_DOUBLE_EQ(s.across_signed_mean_m, 0.1);
  EXPECT_DOUBLE_EQ(s.along_m.mean, 0.2);
  EXPECT_DOUBLE_EQ(s.total_m.max_abs, 0.5);
  EXPECT_EQ(s.heading_rad.count, 1u);
}

TEST(Consistency, HandComputed) {
  const ConsistencySummary c = SummarizeConsistency({1.0, 2.0, 30.0}, {2, 2, 2});
  EXPECT_EQ(c.count, 3u);
  EXPECT_DOUBLE_EQ(c.total_dof, 6.0);
  EXPECT_DOUBLE_EQ(c.mean, 11.0);
  EXPECT_NEAR(c.fraction_inside, 2.0 / 3.0, 1e-12);  // 30 > 7.38
  EXPECT_FALSE(c.mean_inside);
  EXPECT_NEAR(c.band.upper, ChiSquareInterval(6.0).upper / 3.0, 1e-12);
  EXPECT_THROW(SummarizeConsistency({1.0}, {}), std::invalid_argument);
  EXPECT_EQ(SummarizeConsistency({}, {}).count, 0u);
}

/// Estimates drawn from N(truth, P) with a fixed seed: the NEES must behave like chi2(3).
TEST(NeesProperty, EstimatesDrawnFromTheirCovarianceAreConsistent) {
  const int n = 4000;
  const formats::TruthStream truth = StraightTruth(n);
  Eigen::Matrix3d p;
  p << 0.04, 0.01, 0.002, 0.01, 0.09, -0.003, 0.002, -0.003, 0.01;
  const Eigen::Matrix3d l = p.llt().matrixL();
  std::mt19937_64 rng(20261122);
  std::normal_distribution<double> normal;
  formats::EstimateStream est;
  for (int i = 0; i < n; ++i) {
    const Eigen::Vector3d d = l * Eigen::Vector3d(normal(rng), normal(rng), normal(rng));
    formats::EstimateSample e = Estimate(i, i + d.x(), d.y(), d.z());
    e.covariance = p;
    est.estimates.push_back(e);
  }
  EvaluationOptions options;
  const EvaluationResult r = Evaluate(truth, est, options);
  ASSERT_EQ(r.nees.count, static_cast<std::size_t>(n));
  EXPECT_DOUBLE_EQ(r.nees.total_dof, 3.0 * n);
  // Per-sample interval: Binomial(n, 0.95) samples inside.
  test::ExpectBinomialFrequency(static_cast<std::size_t>(std::lround(r.nees.fraction_inside * n)), n, 0.95);
  // Chi-square goodness of fit of the NEES against chi2(3) in 10 equiprobable bins.
  const boost::math::chi_squared chi3(3.0);
  std::vector<double> counts(10, 0.0);
  for (const PoseError& e : r.pose_errors) {
    counts[std::min<std::size_t>(9, static_cast<std::size_t>(10.0 * boost::math::cdf(chi3, *e.nees)))] += 1.0;
  }
  double statistic = 0.0;
  for (double c : counts) statistic += (c - n / 10.0) * (c - n / 10.0) / (n / 10.0);
  EXPECT_LT(statistic, boost::math::quantile(boost::math::chi_squared(9.0), 1.0 - test::kStatisticalAlpha));
  // The time average falls inside its 95 % band in ~95 % of independent runs of 40 samples.
  std::size_t runs_inside = 0;
  const std::size_t runs = 100;
  for (std::size_t run = 0; run < runs; ++run) {
    std::vector<double> values(r.pose_errors.size() / runs);
    for (std::size_t k = 0; k < values.size(); ++k) values[k] = *r.pose_errors[run * values.size() + k].nees;
    if (SummarizeConsistency(values, std::vector<int>(values.size(), 3)).mean_inside) ++runs_inside;
  }
  test::ExpectBinomialFrequency(runs_inside, runs, 0.95);
  // And an overconfident filter (covariance 4x too small) fails the band.
  for (formats::EstimateSample& e : est.estimates) e.covariance = p / 4.0;
  EXPECT_FALSE(Evaluate(truth, est, options).nees.mean_inside);
}

TEST(Whiteness, HandComputedAlternatingSequence) {
  std::vector<Eigen::VectorXd> w;
  for (int k = 0; k < 6; ++k) w.push_back(Eigen::VectorXd::Constant(1, k % 2 == 0 ? 1.0 : -1.0));
  const WhitenessResult r = InnovationWhiteness(w, 50);
  EXPECT_EQ(r.sample_count, 6u);
  ASSERT_EQ(r.autocorrelation.size(), 5u);  // lags limited to K - 1
  EXPECT_NEAR(r.autocorrelation[0], -1.0, 1e-12);
  EXPECT_NEAR(r.autocorrelation[1], 1.0, 1e-12);
  EXPECT_NEAR(r.band_half_width, 1.959964 / std::sqrt(6.0), 1e-6);
  EXPECT_DOUBLE_EQ(r.fraction_inside, 0.0);
}

TEST(Whiteness, NotComputedForTooFewOrMixedSizes) {
  EXPECT_FALSE(InnovationWhiteness({Eigen::VectorXd::Ones(2)}, 5).not_computed.empty());
  EXPECT_THAT(InnovationWhiteness({Eigen::VectorXd::Ones(2), Eigen::VectorXd::Ones(1)}, 5).not_computed,
              HasSubstr("length changes"));
}

TEST(WhitenessProperty, WhiteNoiseStaysInTheBandAndARandomWalkDoesNot) {
  std::mt19937_64 rng(42);
  std::normal_distribution<double> normal;
  std::size_t inside = 0;
  std::size_t lags = 0;
  for (int run = 0; run < 20; ++run) {
    std::vector<Eigen::VectorXd> w;
    for (int k = 0; k < 1000; ++k) w.push_back(Eigen::Vector2d(normal(rng), normal(rng)));
    const WhitenessResult r = InnovationWhiteness(w, 50);
    inside += static_cast<std::size_t>(std::lround(r.fraction_inside * 50.0));
    lags += 50;
  }
  test::ExpectBinomialFrequency(inside, lags, 0.95);
  std::vector<Eigen::VectorXd> ar;
  double x = 0.0;
  for (int k = 0; k < 1000; ++k) {
    x = 0.9 * x + normal(rng);
    ar.push_back(Eigen::VectorXd::Constant(1, x));
  }
  const WhitenessResult r = InnovationWhiteness(ar, 10);
  EXPECT_NEAR(r.autocorrelation[0], 0.9, 0.05);
  EXPECT_LT(r.fraction_inside, 0.1);
}

formats::UpdateRecord Update(double t, const std::string& sensor, Eigen::VectorXd nu, Eigen::MatrixXd s, double nis,
                    bool accepted = true) {
  formats::UpdateRecord u;
  u.t_s = t;
  u.sensor = sensor;
  u.innovation = std::move(nu);
  u.innovation_covariance = std::move(s);
  u.nis = nis;
  u.accepted = accepted;
  return u;
}

TEST(Innovations, RecomputesNisFlagsMismatchesAndCountsGating) {
  Eigen::Matrix2d s;
  s << 4.0, 0.0, 0.0, 1.0;
  const std::vector<formats::UpdateRecord> updates = {
      Update(0.0, "gnss", Eigen::Vector2d(2.0, 1.0), s, 2.0),          // 1 + 1: matches
      Update(1.0, "gnss", Eigen::Vector2d(2.0, 0.0), s, 1.0 + 2e-6),   // mismatch 2e-6 relative
      Update(2.0, "gnss", Eigen::Vector2d(20.0, 0.0), s, 100.0, false),
      Update(1.5, "us_left", Eigen::VectorXd::Constant(1, 0.3), Eigen::MatrixXd::Constant(1, 1, 0.09), 1.0)};
  const std::vector<SensorInnovationResult> r = AnalyzeInnovations(updates, 50);
  ASSERT_EQ(r.size(), 2u);
  const SensorInnovationResult& g = r[0];
  EXPECT_EQ(g.sensor, "gnss");
  EXPECT_EQ(g.update_count, 3u);
  EXPECT_EQ(g.gated_out_count, 1u);
  EXPECT_NEAR(g.gated_out_fraction, 1.0 / 3.0, 1e-12);
  EXPECT_EQ(g.nis_mismatch_count, 1u);
  EXPECT_NEAR(g.max_nis_relative_difference, 2e-6, 1e-9);
  EXPECT_EQ(g.nis.count, 2u);  // accepted only
  EXPECT_NEAR(g.nis.mean, 1.5, 1e-12);
  EXPECT_EQ(g.nis_values.size(), 3u);
  EXPECT_NEAR(g.nis_values[2], 100.0, 1e-9);
  EXPECT_EQ(g.whiteness.sample_count, 2u);
  // Whitened: (1, 1) and (1, 0): rho(1) = 1 / sqrt(2 * 1).
  ASSERT_EQ(g.whiteness.autocorrelation.size(), 1u);
  EXPECT_NEAR(g.whiteness.autocorrelation[0], 1.0 / std::sqrt(2.0), 1e-12);
  EXPECT_EQ(r[1].sensor, "us_left");
  EXPECT_EQ(r[1].nis_mismatch_count, 0u);
  EXPECT_EQ(r[1].dofs[0], 1);
}

TEST(Drift, IntervalsOfFixLossHandComputed) {
  formats::TruthStream truth;
  for (int i = 0; i <= 30; ++i) {
    const bool gnss = !((i >= 2 && i < 8) || (i >= 10 && i < 13) || i >= 24);
    truth.samples.push_back(Truth(i, i, 0.0, 0.0, gnss));
  }
  std::vector<PoseError> errors;
  for (int i = 0; i <= 30; ++i) {
    PoseError e;
    e.t_s = i + 0.5;
    e.total_m = 0.1 * i;
    if (i < 30) errors.push_back(e);
  }
  const std::vector<DriftInterval> d = DriftAfterFixLoss(truth, errors, 5.0);
  ASSERT_EQ(d.size(), 2u);  // the 3 s outage is too short
  EXPECT_DOUBLE_EQ(d[0].start_s, 2.0);
  EXPECT_DOUBLE_EQ(d[0].end_s, 8.0);
  EXPECT_TRUE(d[0].fixes_returned);
  EXPECT_EQ(d[0].estimate_count, 6u);  // t = 2.5 .. 7.5
  EXPECT_NEAR(d[0].error_start_m, 0.2, 1e-12);
  EXPECT_NEAR(d[0].error_end_m, 0.7, 1e-12);
  EXPECT_NEAR(d[0].growth_m, 0.5, 1e-12);
  EXPECT_NEAR(d[0].max_error_m, 0.7, 1e-12);
  EXPECT_DOUBLE_EQ(d[1].start_s, 24.0);
  EXPECT_DOUBLE_EQ(d[1].end_s, 30.0);
  EXPECT_FALSE(d[1].fixes_returned);
  EXPECT_NEAR(d[1].error_end_m, 2.9, 1e-12);  // the final error of the run
}

TEST(Slip, PerWheelErrorAgainstInterpolatedTruth) {
  formats::TruthStream truth = StraightTruth(3);
  for (auto& s : truth.samples) s.wheel_slip = {{"left", 0.1 * s.t_s}, {"right", 0.05}};
  formats::EstimateStream est;
  est.estimates = {Estimate(0.5, 0.5, 0.0), Estimate(1.5, 1.5, 0.0), Estimate(2.0, 2.0, 0.0)};
  est.estimates[0].wheel_slip = {{"left", 0.08}, {"right", 0.05}, {"spare", 1.0}};
  est.estimates[1].wheel_slip = {{"left", 0.13}};
  const std::vector<WheelSlipError> s = CompareWheelSlip(truth, est);
  ASSERT_EQ(s.size(), 2u);  // "spare" has no truth
  EXPECT_EQ(s[0].wheel, "left");
  EXPECT_EQ(s[0].error.count, 2u);
  EXPECT_NEAR(s[0].error.mean, (0.03 - 0.02) / 2.0, 1e-12);
  EXPECT_NEAR(s[0].error.max_abs, 0.03, 1e-12);
  EXPECT_NEAR(s[0].error.rms, std::sqrt((0.0009 + 0.0004) / 2.0), 1e-12);
  EXPECT_EQ(s[1].error.count, 1u);
  EXPECT_NEAR(s[1].error.max_abs, 0.0, 1e-12);
}

TEST(RollingRadius, ErrorAndNeesPerWheelAgainstInterpolatedTruth) {
  formats::TruthStream truth = StraightTruth(3);
  for (auto& s : truth.samples) s.wheel_rolling_radius_m = {{"left", 0.16 + 0.01 * s.t_s}, {"right", 0.16}};
  formats::EstimateStream est;
  est.estimates = {Estimate(0.5, 0.5, 0.0), Estimate(1.0, 1.0, 0.0), Estimate(1.5, 1.5, 0.0), Estimate(2.0, 2.0, 0.0)};
  est.estimates[0].wheel_calibration = {{"left", 0.167, 0.001, 1.0, 1.0}, {"spare", 0.2, 0.01, 1.0, 1.0}};
  // the estimate at t = 1.0 carries no calibration
  est.estimates[2].wheel_calibration = {{"left", 0.173, 0.002, 1.0, 1.0}, {"right", 0.16, 0.0, 1.0, 1.0}};
  est.estimates[3].wheel_calibration = {{"left", 0.18, 0.004, 0.5, 0.5}};
  const std::vector<RollingRadiusError> r = CompareRollingRadius(truth, est);
  ASSERT_EQ(r.size(), 2u);  // "spare" has no truth
  const RollingRadiusError& left = r[0];
  EXPECT_EQ(left.wheel, "left");
  EXPECT_EQ(left.error_m.count, 3u);
  EXPECT_NEAR(left.error_m.mean, (0.002 - 0.002 + 0.0) / 3.0, 1e-12);
  EXPECT_NEAR(left.error_m.max_abs, 0.002, 1e-12);
  ASSERT_EQ(left.nees.count, 3u);
  EXPECT_NEAR(left.nees.mean, (4.0 + 1.0 + 0.0) / 3.0, 1e-9);
  EXPECT_DOUBLE_EQ(left.nees.total_dof, 3.0);
  EXPECT_EQ(left.zero_sigma_count, 0u);
  EXPECT_DOUBLE_EQ(left.final_estimate_m, 0.18);
  EXPECT_DOUBLE_EQ(left.final_sigma_m, 0.004);
  EXPECT_NEAR(left.final_truth_m, 0.18, 1e-12);
  const RollingRadiusError& right = r[1];
  EXPECT_EQ(right.error_m.count, 1u);
  EXPECT_EQ(right.nees.count, 0u);  // sigma 0: no NEES, counted
  EXPECT_EQ(right.zero_sigma_count, 1u);
  EXPECT_TRUE(CompareRollingRadius(truth, formats::EstimateStream{}).empty());
}

// A consistent calibration (errors drawn with the reported sigma) has its mean NEES inside the
// band; the same draws with a bias of 3 sigma do not.
TEST(RollingRadius, NeesSeparatesConsistentFromBiasedCalibration) {
  formats::TruthStream truth = StraightTruth(2);
  for (auto& s : truth.samples) s.wheel_rolling_radius_m = {{"left", 0.16}};
  std::mt19937_64 rng(7);
  std::normal_distribution<double> normal(0.0, 1.0);
  formats::EstimateStream consistent;
  formats::EstimateStream biased;
  for (int k = 0; k < 2000; ++k) {
    const double t = k / 2000.0;
    const double sigma = 0.001 * (1.0 + k % 5);
    const double error = sigma * normal(rng);
    consistent.estimates.push_back(Estimate(t, t, 0.0));
    consistent.estimates.back().wheel_calibration = {{"left", 0.16 + error, sigma, 1.0, 1.0}};
    biased.estimates.push_back(Estimate(t, t, 0.0));
    biased.estimates.back().wheel_calibration = {{"left", 0.16 + error + 3.0 * sigma, sigma, 1.0, 1.0}};
  }
  const RollingRadiusError good = CompareRollingRadius(truth, consistent).at(0);
  EXPECT_TRUE(good.nees.mean_inside) << good.nees.mean;
  const RollingRadiusError bad = CompareRollingRadius(truth, biased).at(0);
  EXPECT_FALSE(bad.nees.mean_inside);
  EXPECT_GT(bad.nees.mean, 9.0);
}

TEST(Evaluate, RejectsAnEmptyEstimateStream) {
  formats::EstimateStream est;
  est.source_name = "e.ndjson";
  EXPECT_THROW(Evaluate(StraightTruth(3), est, {}), EvaluationError);
}

TEST(Evaluate, ReportsTheReferenceAndSpan) {
  formats::EstimateStream est;
  est.estimates = {Estimate(0.5, 0.5, 0.1), Estimate(1.5, 1.5, -0.1)};
  const EvaluationResult r = Evaluate(StraightTruth(3), est, {});
  EXPECT_EQ(r.reference, AlongAcrossReference::kTrueHeading);
  EXPECT_DOUBLE_EQ(r.start_s, 0.5);
  EXPECT_DOUBLE_EQ(r.end_s, 1.5);
  EXPECT_NEAR(r.position.across_abs_m.mean, 0.1, 1e-12);
  EXPECT_NEAR(r.position.across_signed_mean_m, 0.0, 1e-12);
  EXPECT_EQ(r.nees.count, 0u);
}

}  // namespace
}  // namespace rowloc::sim
