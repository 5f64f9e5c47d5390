// The filter's recording for fixed-interval smoothing (issue 29 item 2; docs/localization-filter.md
// §6): owns the optional FixedIntervalSmoother (fixed_interval_smoother.hpp, the Rauch-Tung-Striebel
// smoother: Rauch, Tung & Striebel 1965; Särkkä 2013, ch. 8-9) and forwards the filter's hooks to it
// while smoothing is enabled; every hook is a no-op otherwise, so the filter calls them
// unconditionally and its own results never depend on the recording.
// The angle states the smoother differences wrapped are the heading and the steering angles of
// the layout (the wheel angles are cumulative, not wrapped). A state set anew (re-anchored to a
// measurement, SetPose) is a transition whose rows for it are zero: BeginTransition's rows_reset.
// The filter (VehicleEkf) says when it (re-)initialises (Start), ends a pass (End), changes its
// state other than by an update (BeginTransition, then the Transition* calls) and updates
// (BeginUpdate); Finish ends the recording and returns the smoothed marks.
#pragma once

#include "rowloc/localization/fixed_interval_smoother.hpp"
#include "rowloc/localization/state_layout.hpp"

#include <Eigen/Core>

#include <cstddef>
#include <initializer_list>
#include <optional>
#include <vector>

namespace rowloc::localization {

class SmoothingRecorder {
 public:
  /// layout: the filter's (its size and angle states).
  explicit SmoothingRecorder(const StateLayout& layout);

  bool enabled() const { return smoother_.has_value(); }
  /// The recorder while smoothing is enabled, else null.
  const FixedIntervalSmoother* smoother() const { return smoother_ ? &*smoother_ : nullptr; }
  /// The angle states differenced wrapped: the heading, then the steering angles.
  const std::vector<int>& angle_states() const { return angle_states_; }

  /// Starts recording (check_transitions: FixedIntervalSmoother's check, costly). The caller starts
  /// the first chain if its filter is initialised. std::logic_error when already enabled.
  void Enable(bool check_transitions);
  /// A chain starts at (x, P): the filter (re-)initialised.
  void Start(const Eigen::VectorXd& x, const Eigen::MatrixXd& p);
  /// The chain ends at (x, P): the filter is reset (no effect outside a chain).
  void End(const Eigen::VectorXd& x, const Eigen::MatrixXd& p);
  /// The state (x, P) is about to change other than by an update; rows_reset, if any, are set anew.
  void BeginTransition(const Eigen::VectorXd& x, const Eigen::MatrixXd& p, std::initializer_list<int> rows_reset = {});
  /// Phi <- F Phi for F the identity but its square block starting at `first`.
  void TransitionBlock(int first, const Eigen::MatrixXd& block);
  /// Phi <- (I + E (scale m)) Phi: rows[i] of Phi gains scale m.row(i) Phi (computed only when enabled).
  void TransitionAddRows(const std::vector<int>& rows, double scale, const Eigen::MatrixXd& m);
  /// An update is about to be applied at (x, P).
  void BeginUpdate(const Eigen::VectorXd& x, const Eigen::MatrixXd& p);
  /// Asks for the smoothed state at time_s, the state (x, P); returns the mark's index.
  /// std::logic_error when not enabled.
  std::size_t Mark(double time_s, const Eigen::VectorXd& x, const Eigen::MatrixXd& p);
  /// Ends the chain at (x, P), disables the recording and returns the smoothed state of every mark.
  /// std::logic_error when not enabled; std::runtime_error from the smoother (then disabled too).
  std::vector<SmoothedState> Finish(const Eigen::VectorXd& x, const Eigen::MatrixXd& p);

 private:
  int state_size_;
  std::vector<int> angle_states_;
  std::optional<FixedIntervalSmoother> smoother_;  ///< recording the pass, or none
};

}  // namespace rowloc::localization
