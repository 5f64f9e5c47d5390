// Fixed-interval smoothing of a recorded EKF pass: the Rauch-Tung-Striebel (RTS) smoother
// (Rauch, Tung & Striebel 1965, "Maximum likelihood estimates of linear dynamic systems", AIAA J.
// 3(8); Särkkä, "Bayesian Filtering and Smoothing", 2013, ch. 8 for the linear smoother and ch. 9
// for its extended form, which uses the filter's own Jacobians as the transition).
// docs/localization-filter.md §6 describes its use (rowloc replay --smoothed).
//
// The filter pass is recorded as a chain of nodes k = 0..K. A node is what lies between two
// transitions: its predicted state x_k^- and covariance P_k^- (before its first update) and its
// filtered x_k, P_k (after its last update); Phi_k is the Jacobian of everything between node
// k-1's filtered state and node k's predicted one (prediction steps, re-anchored states; added
// noise only shows in P_k^-). The smoother runs backwards from x_K^s = x_K, P_K^s = P_K:
//   C_k   = P_k Phi_{k+1}^T (P_{k+1}^-)^{-1}
//   x_k^s = x_k + C_k (x_{k+1}^s - x_{k+1}^-)
//   P_k^s = P_k + C_k (P_{k+1}^s - P_{k+1}^-) C_k^T
// Storage. The smoothed state is wanted at a few marked nodes (estimate lines), not at every one.
// With eps_k = x_k^s - x_k and u_k = x_k - x_k^- (node k's update), and since
// C_k P_{k+1}^- C_k^T = C_k Phi_{k+1} P_k, the recursion is linear in eps and in P^s:
//   eps_k = C_k (u_{k+1} + eps_{k+1}),   P_k^s = D_k + C_k P_{k+1}^s C_k^T,   D_k = P_k - C_k Phi_{k+1} P_k.
// So between a marked node m and the next marked node m' (or the chain's end) the maps compose,
// while recording, into
//   eps_m = a_m + G_m eps_m',   P_m^s = B_m + G_m P_m'^s G_m^T
// and each mark keeps (x_m, a_m, G_m, B_m): 2 n^2 + 2 n numbers whatever the number of nodes
// between marks. Each node costs a few n^3 flops (one LDL^T solve for C_k and four products).
// Angle states (the heading, steering angles) are differenced wrapped to (-pi, pi] and the smoothed
// angle is wrapped.
// Check (optional, check_transitions): the noise each transition added, P_{k+1}^- - Phi P_k Phi^T,
// must be positive semi-definite; a transition the filter made without recording it (a missing
// hook) shows as a negative eigenvalue. The smallest one, relative to the largest of the
// predicted covariance, is kept (min_relative_process_noise).
#pragma once

#include <Eigen/Core>

#include <cstddef>
#include <vector>

namespace rowloc::localization {

struct SmoothedState {
  double time_s = 0.0;
  Eigen::VectorXd state;
  Eigen::MatrixXd covariance;
};

/// Records an EKF pass through its hooks, then smooths it. The filter calls, in its own order:
/// Start at (re-)initialisation; BeginTransition, then the Transition* calls, before any change of
/// the state that is not a measurement update; BeginUpdate before each update; End when the pass
/// ends or the filter is reset. Mark asks for the smoothed state at the current node.
/// Misuse (a transition outside BeginTransition, a mark outside a chain, smoothing before End)
/// throws std::logic_error; vectors and matrices of the wrong size std::invalid_argument.
class FixedIntervalSmoother {
 public:
  /// state_size > 0; angle_states: indices of states that are angles in (-pi, pi].
  FixedIntervalSmoother(int state_size, std::vector<int> angle_states, bool check_transitions = false);

  /// A chain starts at (x, P) (the filter initialised); ends the previous chain first, at its last node.
  void Start(const Eigen::VectorXd& x, const Eigen::MatrixXd& p);
  /// The state is about to change by a transition: closes the current node with (x, P) as its filtered
  /// state and starts the transition Phi = I. No effect outside a chain or within a transition.
  void BeginTransition(const Eigen::VectorXd& x, const Eigen::MatrixXd& p);
  /// Phi <- F Phi for F the identity but its square diagonal block starting at `first`.
  void TransitionBlock(int first, const Eigen::MatrixXd& block);
  /// Phi <- (I + E M) Phi: row rows[i] of Phi gains M.row(i) Phi (states driven by others).
  void TransitionAddRows(const std::vector<int>& rows, const Eigen::MatrixXd& m);
  /// Phi <- F Phi for F the identity with these rows zero (states re-anchored to a measurement).
  void TransitionZeroRows(const std::vector<int>& rows);
  /// An update is about to be applied at (x, P): within a transition, opens a new node with (x, P)
  /// as its predicted state. No effect outside a chain or within a node.
  void BeginUpdate(const Eigen::VectorXd& x, const Eigen::MatrixXd& p);
  /// Asks for the smoothed state at time_s, the current state (x, P) (a node is opened for it
  /// within a transition). Returns the mark's index into Smooth()'s result.
  std::size_t Mark(double time_s, const Eigen::VectorXd& x, const Eigen::MatrixXd& p);
  /// Ends the chain at (x, P) (the last node's filtered state). No effect outside a chain.
  void End(const Eigen::VectorXd& x, const Eigen::MatrixXd& p);

  /// The smoothed state of every mark, in mark order. Requires the last chain to have ended.
  /// Throws std::runtime_error when a predicted covariance could not be factorized.
  std::vector<SmoothedState> Smooth() const;

  std::size_t marks() const { return mark_record_.size(); }
  std::size_t nodes() const { return nodes_; }  ///< nodes recorded, all chains
  bool recording() const { return phase_ != Phase::kIdle; }
  /// With check_transitions: min over nodes of lambda_min(P^- - Phi P Phi^T) / lambda_max(P^-)
  /// (0 when nothing was checked); a clearly negative value means an unrecorded transition.
  double min_relative_process_noise() const { return min_relative_noise_; }

 private:
  enum class Phase { kIdle, kInNode, kInTransition };
  /// One marked node: eps_m = offset + gain eps_next, P_m^s = spread + gain P_next^s gain^T.
  struct Record {
    double time_s = 0.0;
    Eigen::VectorXd filtered;
    Eigen::VectorXd offset;
    Eigen::MatrixXd gain;
    Eigen::MatrixXd spread;
  };
  struct Chain {
    std::size_t first_record = 0;  ///< records [first_record, next chain's first_record)
    Eigen::MatrixXd end_covariance;
  };

  void CheckSizes(const Eigen::VectorXd& x, const Eigen::MatrixXd& p) const;
  void RequireTransition(const char* what) const;
  void CloseNode(const Eigen::VectorXd& x, const Eigen::MatrixXd& p);
  void OpenNode(const Eigen::VectorXd& x, const Eigen::MatrixXd& p);
  /// a - b with the angle states wrapped.
  Eigen::VectorXd Difference(const Eigen::VectorXd& a, const Eigen::VectorXd& b) const;

  int n_;
  std::vector<int> angle_states_;
  bool check_transitions_;
  Phase phase_ = Phase::kIdle;
  std::size_t nodes_ = 0;
  double min_relative_noise_ = 0.0;

  // The last closed node (its filtered state) and the transition since.
  Eigen::VectorXd filtered_x_;
  Eigen::MatrixXd filtered_p_;
  Eigen::MatrixXd transition_;
  // The open node: its predicted state, and the gain C and spread D from the node before it
  // (has_gain false for a chain's first node).
  Eigen::VectorXd predicted_x_;
  bool has_gain_ = false;
  Eigen::MatrixXd node_gain_, node_spread_;
  bool node_marked_ = false;
  double node_time_s_ = 0.0;

  // records_.back() composes from the chain's last marked node to the current one (open_record_;
  // false before the chain's first mark).
  bool open_record_ = false;
  std::vector<Record> records_;
  std::vector<Chain> chains_;
  std::vector<std::size_t> mark_record_;  ///< mark -> record
};

}  // namespace rowloc::localization
