// Fixed-interval (RTS) smoother (fixed_interval_smoother.hpp). The reference is the exact posterior
// of a linear-Gaussian chain: the joint Gaussian of every node's state conditioned on every
// measurement at once (no recursion), which any correct smoother must reproduce.
#include "rowloc/localization/fixed_interval_smoother.hpp"

#include "rowloc/localization/kalman_update.hpp"
#include "random_spd.hpp"

#include <gtest/gtest.h>

#include <Eigen/Cholesky>
#include <Eigen/Eigenvalues>

#include <cmath>
#include <limits>
#include <numbers>
#include <random>
#include <stdexcept>
#include <vector>

namespace rowloc::localization {
namespace {

constexpr double kNoGate = std::numeric_limits<double>::infinity();

struct Measurement {
  Eigen::MatrixXd h;
  Eigen::MatrixXd r;
  Eigen::VectorXd z;
};
/// Node k > 0: x_k = Z transition x_{k-1} + offset + w, w ~ N(0, noise), Z the identity with the
/// zeroed rows zero (states re-anchored, to `offset`); then its measurements (maybe none).
struct Node {
  Eigen::MatrixXd transition;
  Eigen::MatrixXd noise;
  std::vector<int> zeroed_rows;  ///< recorded as TransitionZeroRows after the transition
  Eigen::VectorXd offset;        ///< empty: none
  std::vector<Measurement> measurements;
  bool marked = true;

  Eigen::MatrixXd Effective() const {
    Eigen::MatrixXd f = transition;
    for (const int r : zeroed_rows) f.row(r).setZero();
    return f;
  }
  Eigen::VectorXd Offset() const { return offset.size() > 0 ? offset : Eigen::VectorXd::Zero(transition.rows()); }
};
struct Chain {
  Eigen::VectorXd prior_mean;
  Eigen::MatrixXd prior_covariance;
  std::vector<Node> nodes;  ///< nodes[0]: its transition and noise are unused
};

Eigen::MatrixXd RandomMatrix(Eigen::Index rows, Eigen::Index cols, std::mt19937_64& rng, double scale) {
  std::normal_distribution<double> normal(0.0, scale);
  Eigen::MatrixXd m(rows, cols);
  for (Eigen::Index i = 0; i < m.size(); ++i) m(i) = normal(rng);
  return m;
}

Chain RandomChain(int n, int nodes, std::mt19937_64& rng) {
  Chain c{RandomMatrix(n, 1, rng, 1.0), test::RandomSpd(n, rng, 0.5), {}};
  std::uniform_int_distribution<int> count(0, 2), dim(1, n);
  for (int k = 0; k < nodes; ++k) {
    Node node;
    node.transition = Eigen::MatrixXd::Identity(n, n) + RandomMatrix(n, n, rng, 0.2);
    node.noise = 0.1 * test::RandomSpd(n, rng, 0.01);
    for (int j = count(rng); j > 0; --j) {
      const int m = dim(rng);
      node.measurements.push_back({RandomMatrix(m, n, rng, 1.0), test::RandomSpd(m, rng, 0.2), RandomMatrix(m, 1, rng, 2.0)});
    }
    c.nodes.push_back(std::move(node));
  }
  return c;
}

/// Runs the Kalman filter over the chain while recording it; returns the filtered (x, P) per node.
std::vector<SmoothedState> FilterAndRecord(const Chain& c, FixedIntervalSmoother& smoother, int angle_index = -1) {
  Eigen::VectorXd x = c.prior_mean;
  Eigen::MatrixXd p = c.prior_covariance;
  std::vector<SmoothedState> filtered;
  for (std::size_t k = 0; k < c.nodes.size(); ++k) {
    const Node& node = c.nodes[k];
    if (k == 0) {
      smoother.Start(x, p);
    } else {
      smoother.BeginTransition(x, p);
      smoother.TransitionBlock(0, node.transition);
      if (!node.zeroed_rows.empty()) smoother.TransitionZeroRows(node.zeroed_rows);
      const Eigen::MatrixXd f = node.Effective();
      x = (f * x + node.Offset()).eval();
      if (angle_index >= 0) x(angle_index) = WrapAngle(x(angle_index));
      const Eigen::MatrixXd moved = f * p * f.transpose() + node.noise;
      p = 0.5 * (moved + moved.transpose());
    }
    for (const Measurement& m : node.measurements) {
      smoother.BeginUpdate(x, p);
      Eigen::VectorXd innovation = m.z - m.h * x;
      if (angle_index >= 0 && m.h.rows() == 1 && m.h(0, angle_index) == 1.0) innovation(0) = WrapAngle(innovation(0));
      EXPECT_TRUE(KalmanUpdate(x, p, innovation, m.h, m.r, kNoGate, angle_index).accepted);
    }
    if (node.marked) smoother.Mark(static_cast<double>(k), x, p);
    filtered.push_back({static_cast<double>(k), x, p});
  }
  smoother.End(x, p);
  return filtered;
}

/// The exact posterior marginal of every node (joint Gaussian conditioning, batch).
std::vector<SmoothedState> BatchPosterior(const Chain& c) {
  const auto n = c.prior_mean.size();
  const auto k_count = static_cast<Eigen::Index>(c.nodes.size());
  Eigen::VectorXd mean(n * k_count);
  Eigen::MatrixXd cov = Eigen::MatrixXd::Zero(n * k_count, n * k_count);
  mean.head(n) = c.prior_mean;
  cov.topLeftCorner(n, n) = c.prior_covariance;
  for (Eigen::Index k = 1; k < k_count; ++k) {
    const Node& node = c.nodes[static_cast<std::size_t>(k)];
    const Eigen::MatrixXd f = node.Effective();
    mean.segment(k * n, n) = f * mean.segment((k - 1) * n, n) + node.Offset();
    for (Eigen::Index j = 0; j < k; ++j) {  // Cov(x_k, x_j) = F Cov(x_{k-1}, x_j)
      cov.block(k * n, j * n, n, n) = f * cov.block((k - 1) * n, j * n, n, n);
      cov.block(j * n, k * n, n, n) = cov.block(k * n, j * n, n, n).transpose();
    }
    cov.block(k * n, k * n, n, n) = f * cov.block((k - 1) * n, (k - 1) * n, n, n) * f.transpose() + node.noise;
  }
  std::vector<Eigen::MatrixXd> rows;
  Eigen::Index m_total = 0;
  for (const Node& node : c.nodes) {
    for (const Measurement& m : node.measurements) m_total += m.h.rows();
  }
  Eigen::MatrixXd h = Eigen::MatrixXd::Zero(m_total, n * k_count), r = Eigen::MatrixXd::Zero(m_total, m_total);
  Eigen::VectorXd z(m_total);
  Eigen::Index row = 0;
  for (Eigen::Index k = 0; k < k_count; ++k) {
    for (const Measurement& m : c.nodes[static_cast<std::size_t>(k)].measurements) {
      h.block(row, k * n, m.h.rows(), n) = m.h;
      r.block(row, row, m.h.rows(), m.h.rows()) = m.r;
      z.segment(row, m.h.rows()) = m.z;
      row += m.h.rows();
    }
  }
  const Eigen::MatrixXd s = h * cov * h.transpose() + r;
  const Eigen::MatrixXd gain = cov * h.transpose() * s.ldlt().solve(Eigen::MatrixXd::Identity(m_total, m_total));
  const Eigen::VectorXd post_mean = mean + gain * (z - h * mean);
  const Eigen::MatrixXd post_cov = cov - gain * h * cov;
  std::vector<SmoothedState> out;
  for (Eigen::Index k = 0; k < k_count; ++k) {
    out.push_back({static_cast<double>(k), post_mean.segment(k * n, n), post_cov.block(k * n, k * n, n, n)});
  }
  return out;
}

void ExpectMarksEqualBatch(const Chain& c, const std::vector<SmoothedState>& smoothed, double tolerance) {
  const std::vector<SmoothedState> batch = BatchPosterior(c);
  std::size_t mark = 0;
  for (std::size_t k = 0; k < c.nodes.size(); ++k) {
    if (!c.nodes[k].marked) continue;
    ASSERT_LT(mark, smoothed.size());
    const SmoothedState& s = smoothed[mark++];
    EXPECT_EQ(s.time_s, static_cast<double>(k));
    EXPECT_LT((s.state - batch[k].state).cwiseAbs().maxCoeff(), tolerance) << "node " << k;
    EXPECT_LT((s.covariance - batch[k].covariance).cwiseAbs().maxCoeff(), tolerance) << "node " << k;
  }
  EXPECT_EQ(mark, smoothed.size());
}

TEST(FixedIntervalSmoother, EveryNodeMarkedEqualsTheBatchPosterior) {
  std::mt19937_64 rng(7);
  for (int trial = 0; trial < 20; ++trial) {
    const Chain c = RandomChain(4, 12, rng);
    FixedIntervalSmoother smoother(4, {});
    FilterAndRecord(c, smoother);
    EXPECT_EQ(smoother.nodes(), c.nodes.size());
    ExpectMarksEqualBatch(c, smoother.Smooth(), 1e-8);
  }
}

TEST(FixedIntervalSmoother, SparseMarksComposeToTheSameResult) {
  std::mt19937_64 rng(11);
  for (int trial = 0; trial < 20; ++trial) {
    Chain c = RandomChain(5, 15, rng);
    for (std::size_t k = 0; k < c.nodes.size(); ++k) c.nodes[k].marked = k % 4 == 1 || k == 10;
    FixedIntervalSmoother smoother(5, {});
    FilterAndRecord(c, smoother);
    EXPECT_EQ(smoother.marks(), 5u);
    ExpectMarksEqualBatch(c, smoother.Smooth(), 1e-8);
  }
}

TEST(FixedIntervalSmoother, ReanchoredStatesAndNodesWithoutMeasurements) {
  // A re-anchored state: its row of the transition is zero and the noise alone sets it (singular
  // noise elsewhere: the batch reference does not need the noise's inverse).
  std::mt19937_64 rng(13);
  for (int trial = 0; trial < 20; ++trial) {
    Chain c = RandomChain(4, 10, rng);
    for (std::size_t k = 1; k < c.nodes.size(); ++k) {
      Node& node = c.nodes[k];
      if (k % 3 != 0) continue;
      node.zeroed_rows = {2};
      node.offset = Eigen::VectorXd::Zero(4);
      node.offset(2) = 1.5;  // re-anchored to a measured value
      node.noise.setZero();
      node.noise(2, 2) = 0.05;
      node.measurements.clear();  // a node with no update (marked: opened by the mark)
    }
    FixedIntervalSmoother smoother(4, {}, /*check_transitions=*/true);
    FilterAndRecord(c, smoother);
    ExpectMarksEqualBatch(c, smoother.Smooth(), 1e-8);
    EXPECT_GT(smoother.min_relative_process_noise(), -1e-12);
  }
}

TEST(FixedIntervalSmoother, AddedRowsEqualTheirDenseTransition) {
  std::mt19937_64 rng(17);
  const int n = 4;
  const Eigen::VectorXd x = RandomMatrix(n, 1, rng, 1.0);
  const Eigen::MatrixXd p = test::RandomSpd(n, rng, 0.5);
  const Eigen::MatrixXd m = RandomMatrix(2, n, rng, 0.3);
  const Eigen::MatrixXd block = Eigen::MatrixXd::Identity(2, 2) + RandomMatrix(2, 2, rng, 0.2);
  Eigen::MatrixXd dense = Eigen::MatrixXd::Identity(n, n);
  dense.row(3) += m.row(0);
  dense.row(1) += m.row(1);
  Eigen::MatrixXd blocked = Eigen::MatrixXd::Identity(n, n);
  blocked.block(0, 0, 2, 2) = block;
  dense = (blocked * dense).eval();
  const Eigen::MatrixXd predicted = dense * p * dense.transpose() + 0.1 * Eigen::MatrixXd::Identity(n, n);
  const auto run = [&](bool sparse) {
    FixedIntervalSmoother s(n, {});
    s.Start(x, p);
    s.Mark(0.0, x, p);
    s.BeginTransition(x, p);
    if (sparse) {
      s.TransitionAddRows({3, 1}, m);
      s.TransitionBlock(0, block);
    } else {
      s.TransitionBlock(0, dense);
    }
    s.Mark(1.0, dense * x, predicted);
    s.End(dense * x, predicted);
    return s.Smooth();
  };
  const std::vector<SmoothedState> a = run(true), b = run(false);
  ASSERT_EQ(a.size(), 2u);
  EXPECT_LT((a[0].covariance - b[0].covariance).cwiseAbs().maxCoeff(), 1e-12);
  EXPECT_LT((a[0].state - b[0].state).cwiseAbs().maxCoeff(), 1e-12);
}

TEST(FixedIntervalSmoother, SmoothedCovarianceIsSymmetricAndBelowTheFiltered) {
  std::mt19937_64 rng(19);
  for (int trial = 0; trial < 10; ++trial) {
    const Chain c = RandomChain(5, 20, rng);
    FixedIntervalSmoother smoother(5, {});
    const std::vector<SmoothedState> filtered = FilterAndRecord(c, smoother);
    const std::vector<SmoothedState> smoothed = smoother.Smooth();
    ASSERT_EQ(smoothed.size(), filtered.size());
    for (std::size_t k = 0; k < smoothed.size(); ++k) {
      EXPECT_EQ(smoothed[k].covariance, smoothed[k].covariance.transpose());
      const Eigen::VectorXd gap =
          Eigen::SelfAdjointEigenSolver<Eigen::MatrixXd>(filtered[k].covariance - smoothed[k].covariance).eigenvalues();
      EXPECT_GT(gap.minCoeff(), -1e-10) << "node " << k;  // P - P^s positive semi-definite
      EXPECT_GT(Eigen::SelfAdjointEigenSolver<Eigen::MatrixXd>(smoothed[k].covariance).eigenvalues().minCoeff(), 0.0);
    }
    // The last node has nothing after it: smoothed = filtered.
    EXPECT_LT((smoothed.back().state - filtered.back().state).cwiseAbs().maxCoeff(), 1e-12);
    EXPECT_LT((smoothed.back().covariance - filtered.back().covariance).cwiseAbs().maxCoeff(), 1e-12);
  }
}

TEST(FixedIntervalSmoother, ChainsAreSmoothedIndependently) {
  std::mt19937_64 rng(23);
  const Chain first = RandomChain(3, 8, rng), second = RandomChain(3, 6, rng);
  FixedIntervalSmoother smoother(3, {});
  FilterAndRecord(first, smoother);
  FilterAndRecord(second, smoother);
  const std::vector<SmoothedState> smoothed = smoother.Smooth();
  ASSERT_EQ(smoothed.size(), 14u);
  ExpectMarksEqualBatch(first, {smoothed.begin(), smoothed.begin() + 8}, 1e-8);
  ExpectMarksEqualBatch(second, {smoothed.begin() + 8, smoothed.end()}, 1e-8);
}

TEST(FixedIntervalSmoother, AnglesAreDifferencedAcrossTheWrap) {
  // State (angle, rate): angle' = angle + rate. Smoothing a track that crosses +-pi must give the
  // track smoothed a quarter turn away (no wrap), turned back.
  const auto chain_at = [](double offset) {
    Chain c{Eigen::Vector2d(std::numbers::pi - 0.3 + offset, 0.1), Eigen::Vector2d(0.04, 0.01).asDiagonal(), {}};
    for (int k = 0; k < 8; ++k) {
      Node node;
      node.transition = (Eigen::Matrix2d() << 1.0, 1.0, 0.0, 1.0).finished();
      node.noise = Eigen::Vector2d(1e-4, 1e-4).asDiagonal();
      const double measured = std::numbers::pi - 0.3 + 0.1 * k + 0.02 * std::sin(3.0 * k) + offset;
      node.measurements.push_back({Eigen::RowVector2d(1.0, 0.0), Eigen::Matrix<double, 1, 1>(0.01),
                                   Eigen::Matrix<double, 1, 1>(WrapAngle(measured))});
      c.nodes.push_back(node);
    }
    return c;
  };
  FixedIntervalSmoother wrapped(2, {0}), plain(2, {0});
  FilterAndRecord(chain_at(0.0), wrapped, 0);
  FilterAndRecord(chain_at(-std::numbers::pi / 2), plain, 0);
  const std::vector<SmoothedState> a = wrapped.Smooth(), b = plain.Smooth();
  ASSERT_EQ(a.size(), b.size());
  bool crossed = false;
  for (std::size_t k = 0; k < a.size(); ++k) {
    crossed = crossed || a[k].state(0) < 0.0;
    EXPECT_GT(a[k].state(0), -std::numbers::pi);
    EXPECT_LE(a[k].state(0), std::numbers::pi);
    EXPECT_NEAR(WrapAngle(a[k].state(0) - (b[k].state(0) + std::numbers::pi / 2)), 0.0, 1e-9) << k;
    EXPECT_NEAR(a[k].state(1), b[k].state(1), 1e-9);
  }
  EXPECT_TRUE(crossed);  // the track did cross the wrap
}

TEST(FixedIntervalSmoother, AnUnrecordedTransitionShowsAsNegativeNoise) {
  std::mt19937_64 rng(31);
  Chain c = RandomChain(4, 6, rng);
  FixedIntervalSmoother honest(4, {}, true);
  FilterAndRecord(c, honest);
  EXPECT_GT(honest.min_relative_process_noise(), -1e-12);
  // The same filter, with one transition applied to (x, P) but not recorded.
  FixedIntervalSmoother missing(4, {}, true);
  const Eigen::MatrixXd shrink = 0.3 * Eigen::MatrixXd::Identity(4, 4);
  Eigen::VectorXd x = c.prior_mean;
  Eigen::MatrixXd p = c.prior_covariance;
  missing.Start(x, p);
  missing.BeginTransition(x, p);
  x = shrink * x;
  p = shrink * p * shrink;
  missing.BeginUpdate(x, p);
  missing.End(x, p);
  EXPECT_LT(missing.min_relative_process_noise(), -0.1);
}

TEST(FixedIntervalSmoother, MisuseIsRefused) {
  EXPECT_THROW(FixedIntervalSmoother(0, {}), std::invalid_argument);
  EXPECT_THROW(FixedIntervalSmoother(3, {3}), std::invalid_argument);
  FixedIntervalSmoother s(2, {});
  const Eigen::Vector2d x(1.0, 2.0);
  const Eigen::Matrix2d p = Eigen::Matrix2d::Identity();
  EXPECT_THROW(s.Mark(0.0, x, p), std::logic_error);  // no chain
  EXPECT_THROW(s.Start(Eigen::Vector3d::Zero(), p), std::invalid_argument);
  s.Start(x, p);
  EXPECT_THROW(s.Start(x, p), std::logic_error);
  EXPECT_THROW(s.TransitionZeroRows({0}), std::logic_error);  // no BeginTransition
  EXPECT_THROW(s.Smooth(), std::logic_error);                 // not ended
  s.BeginTransition(x, p);
  EXPECT_THROW(s.TransitionZeroRows({2}), std::invalid_argument);
  EXPECT_THROW(s.TransitionBlock(1, Eigen::Matrix2d::Identity()), std::invalid_argument);
  EXPECT_THROW(s.TransitionAddRows({0}, Eigen::MatrixXd::Zero(2, 2)), std::invalid_argument);
  EXPECT_THROW(s.BeginUpdate(x, Eigen::Matrix3d::Identity()), std::invalid_argument);
  s.Mark(1.0, x, p);
  s.End(x, p);
  EXPECT_EQ(s.Smooth().size(), 1u);
}

TEST(FixedIntervalSmoother, APredictedCovarianceThatIsNotPositiveDefiniteIsReported) {
  FixedIntervalSmoother s(2, {});
  const Eigen::Vector2d x(0.0, 0.0);
  s.Start(x, Eigen::Matrix2d::Identity());
  s.Mark(0.0, x, Eigen::Matrix2d::Identity());
  s.BeginTransition(x, Eigen::Matrix2d::Identity());
  EXPECT_THROW(s.BeginUpdate(x, Eigen::Vector2d(1.0, -1.0).asDiagonal().toDenseMatrix()), std::runtime_error);
}

}  // namespace
}  // namespace rowloc::localization
