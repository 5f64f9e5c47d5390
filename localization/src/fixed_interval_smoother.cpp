#include "rowloc/localization/fixed_interval_smoother.hpp"

#include "rowloc/localization/kalman_update.hpp"

#include <Eigen/Cholesky>
#include <Eigen/Eigenvalues>

#include <algorithm>
#include <stdexcept>
#include <string>
#include <utility>

namespace rowloc::localization {

namespace {

void Symmetrize(Eigen::MatrixXd& m) { m = 0.5 * (m + m.transpose()).eval(); }

}  // namespace

FixedIntervalSmoother::FixedIntervalSmoother(int state_size, std::vector<int> angle_states, bool check_transitions)
    : n_(state_size), angle_states_(std::move(angle_states)), check_transitions_(check_transitions) {
  if (n_ <= 0) throw std::invalid_argument("smoother: the state size must be > 0");
  for (const int a : angle_states_) {
    if (a < 0 || a >= n_) throw std::invalid_argument("smoother: angle state " + std::to_string(a) + " out of range");
  }
}

void FixedIntervalSmoother::CheckSizes(const Eigen::VectorXd& x, const Eigen::MatrixXd& p) const {
  if (x.size() != n_ || p.rows() != n_ || p.cols() != n_) {
    throw std::invalid_argument("smoother: state of size " + std::to_string(x.size()) + " and covariance " +
                                std::to_string(p.rows()) + "x" + std::to_string(p.cols()) + ", expected " +
                                std::to_string(n_));
  }
}

void FixedIntervalSmoother::RequireTransition(const char* what) const {
  if (phase_ == Phase::kIdle) return;
  if (phase_ != Phase::kInTransition) {
    throw std::logic_error(std::string("smoother: ") + what + " without BeginTransition");
  }
}

void FixedIntervalSmoother::Start(const Eigen::VectorXd& x, const Eigen::MatrixXd& p) {
  CheckSizes(x, p);
  if (phase_ != Phase::kIdle) throw std::logic_error("smoother: Start within a chain (End it first)");
  chains_.push_back({records_.size(), Eigen::MatrixXd()});
  phase_ = Phase::kInNode;
  has_gain_ = false;
  node_marked_ = false;
  open_record_ = false;
  predicted_x_ = x;
  ++nodes_;
}

void FixedIntervalSmoother::BeginTransition(const Eigen::VectorXd& x, const Eigen::MatrixXd& p) {
  if (phase_ != Phase::kInNode) return;
  CloseNode(x, p);
  transition_.setIdentity(n_, n_);
  phase_ = Phase::kInTransition;
}

void FixedIntervalSmoother::TransitionBlock(int first, const Eigen::MatrixXd& block) {
  RequireTransition("TransitionBlock");
  if (first < 0 || block.rows() != block.cols() || first + block.rows() > n_) {
    throw std::invalid_argument("smoother: transition block out of range");
  }
  if (phase_ == Phase::kIdle) return;
  auto rows = transition_.middleRows(first, block.rows());
  rows = (block * rows).eval();
}

void FixedIntervalSmoother::TransitionAddRows(const std::vector<int>& rows, const Eigen::MatrixXd& m) {
  RequireTransition("TransitionAddRows");
  if (m.rows() != static_cast<Eigen::Index>(rows.size()) || m.cols() != n_ ||
      std::any_of(rows.begin(), rows.end(), [this](int r) { return r < 0 || r >= n_; })) {
    throw std::invalid_argument("smoother: added rows out of range");
  }
  if (phase_ == Phase::kIdle) return;
  const Eigen::MatrixXd added = m * transition_;  // from Phi before any row changes
  for (std::size_t i = 0; i < rows.size(); ++i) transition_.row(rows[i]) += added.row(static_cast<Eigen::Index>(i));
}

void FixedIntervalSmoother::TransitionZeroRows(const std::vector<int>& rows) {
  RequireTransition("TransitionZeroRows");
  if (std::any_of(rows.begin(), rows.end(), [this](int r) { return r < 0 || r >= n_; })) {
    throw std::invalid_argument("smoother: zeroed row out of range");
  }
  if (phase_ == Phase::kIdle) return;
  for (const int r : rows) transition_.row(r).setZero();
}

void FixedIntervalSmoother::BeginUpdate(const Eigen::VectorXd& x, const Eigen::MatrixXd& p) {
  if (phase_ != Phase::kInTransition) return;
  OpenNode(x, p);
}

std::size_t FixedIntervalSmoother::Mark(double time_s, const Eigen::VectorXd& x, const Eigen::MatrixXd& p) {
  if (phase_ == Phase::kIdle) throw std::logic_error("smoother: Mark outside a chain (before Start or after End)");
  if (phase_ == Phase::kInTransition) OpenNode(x, p);
  if (!node_marked_) {
    node_marked_ = true;
    node_time_s_ = time_s;
  }
  mark_record_.push_back(records_.size());  // the record this node gets when it closes
  return mark_record_.size() - 1;
}

void FixedIntervalSmoother::End(const Eigen::VectorXd& x, const Eigen::MatrixXd& p) {
  if (phase_ == Phase::kIdle) return;
  if (phase_ == Phase::kInNode) CloseNode(x, p);
  chains_.back().end_covariance = filtered_p_;
  open_record_ = false;
  phase_ = Phase::kIdle;
}

void FixedIntervalSmoother::OpenNode(const Eigen::VectorXd& x, const Eigen::MatrixXd& p) {
  CheckSizes(x, p);
  predicted_x_ = x;
  has_gain_ = open_record_ || check_transitions_;
  if (has_gain_) {
    // C = P_k Phi^T (P^-)^{-1}: P^- C^T = Phi P_k (P^- symmetric); D = P_k - C Phi P_k.
    const Eigen::MatrixXd moved = transition_ * filtered_p_;
    const Eigen::LDLT<Eigen::MatrixXd> factor(p);
    if (factor.info() != Eigen::Success || !factor.isPositive()) {
      throw std::runtime_error("smoother: the predicted covariance of node " + std::to_string(nodes_) +
                               " is not positive definite");
    }
    node_gain_ = factor.solve(moved).transpose();
    node_spread_ = filtered_p_ - node_gain_ * moved;
    Symmetrize(node_spread_);
    if (!node_gain_.allFinite() || !node_spread_.allFinite()) {
      throw std::runtime_error("smoother: non-finite gain at node " + std::to_string(nodes_));
    }
    if (check_transitions_) {
      Eigen::MatrixXd noise = p - moved * transition_.transpose();
      Symmetrize(noise);
      const double lowest = Eigen::SelfAdjointEigenSolver<Eigen::MatrixXd>(noise, Eigen::EigenvaluesOnly).eigenvalues()(0);
      const double scale = Eigen::SelfAdjointEigenSolver<Eigen::MatrixXd>(p, Eigen::EigenvaluesOnly).eigenvalues()(n_ - 1);
      min_relative_noise_ = std::min(min_relative_noise_, lowest / scale);
    }
  }
  node_marked_ = false;
  phase_ = Phase::kInNode;
  ++nodes_;
}

void FixedIntervalSmoother::CloseNode(const Eigen::VectorXd& x, const Eigen::MatrixXd& p) {
  CheckSizes(x, p);
  if (open_record_ && has_gain_) {
    // Fold node k+1 into the composition: a += G C u, B += G D G^T, G <- G C.
    Record& r = records_.back();
    const Eigen::VectorXd update = Difference(x, predicted_x_);
    r.offset.noalias() += r.gain * (node_gain_ * update);
    const Eigen::MatrixXd spread = r.gain * node_spread_;
    r.spread.noalias() += spread * r.gain.transpose();
    r.gain = (r.gain * node_gain_).eval();
  }
  if (node_marked_) {
    records_.push_back({node_time_s_, x, Eigen::VectorXd::Zero(n_), Eigen::MatrixXd::Identity(n_, n_),
                        Eigen::MatrixXd::Zero(n_, n_)});
    open_record_ = true;
    node_marked_ = false;
  }
  filtered_p_ = p;
}

Eigen::VectorXd FixedIntervalSmoother::Difference(const Eigen::VectorXd& a, const Eigen::VectorXd& b) const {
  Eigen::VectorXd d = a - b;
  for (const int i : angle_states_) d(i) = WrapAngle(d(i));
  return d;
}

std::vector<SmoothedState> FixedIntervalSmoother::Smooth() const {
  if (phase_ != Phase::kIdle) throw std::logic_error("smoother: Smooth before End");
  std::vector<SmoothedState> by_record(records_.size());
  for (std::size_t c = 0; c < chains_.size(); ++c) {
    const std::size_t first = chains_[c].first_record;
    const std::size_t last = c + 1 < chains_.size() ? chains_[c + 1].first_record : records_.size();
    Eigen::VectorXd eps = Eigen::VectorXd::Zero(n_);
    Eigen::MatrixXd covariance = chains_[c].end_covariance;
    for (std::size_t r = last; r-- > first;) {
      const Record& record = records_[r];
      eps = (record.offset + record.gain * eps).eval();
      covariance = (record.spread + record.gain * covariance * record.gain.transpose()).eval();
      Symmetrize(covariance);
      Eigen::VectorXd x = record.filtered + eps;
      for (const int i : angle_states_) x(i) = WrapAngle(x(i));
      by_record[r] = {record.time_s, std::move(x), covariance};
    }
  }
  std::vector<SmoothedState> smoothed;
  smoothed.reserve(mark_record_.size());
  for (const std::size_t r : mark_record_) smoothed.push_back(by_record[r]);
  return smoothed;
}

}  // namespace rowloc::localization
