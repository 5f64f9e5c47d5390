// The filter's hooks into the fixed-interval smoother (smoothing_recorder.hpp).
#include "rowloc/localization/smoothing_recorder.hpp"

#include <stdexcept>
#include <utility>

namespace rowloc::localization {

SmoothingRecorder::SmoothingRecorder(const StateLayout& layout)
    : state_size_(layout.size), angle_states_{StateLayout::kPhi} {
  for (const int d : layout.steering) {
    if (d >= 0) angle_states_.push_back(d);
  }
}

void SmoothingRecorder::Enable(bool check_transitions) {
  if (smoother_) throw std::logic_error("EnableSmoothing: smoothing is already enabled");
  smoother_.emplace(state_size_, angle_states_, check_transitions);
}

void SmoothingRecorder::Start(const Eigen::VectorXd& x, const Eigen::MatrixXd& p) {
  if (smoother_) smoother_->Start(x, p);
}

void SmoothingRecorder::End(const Eigen::VectorXd& x, const Eigen::MatrixXd& p) {
  if (smoother_) smoother_->End(x, p);
}

void SmoothingRecorder::BeginTransition(const Eigen::VectorXd& x, const Eigen::MatrixXd& p,
                                        std::initializer_list<int> rows_reset) {
  if (!smoother_) return;
  smoother_->BeginTransition(x, p);
  if (rows_reset.size() > 0) smoother_->TransitionZeroRows(std::vector<int>(rows_reset));
}

void SmoothingRecorder::TransitionBlock(int first, const Eigen::MatrixXd& block) {
  if (smoother_) smoother_->TransitionBlock(first, block);
}

void SmoothingRecorder::TransitionAddRows(const std::vector<int>& rows, double scale, const Eigen::MatrixXd& m) {
  if (smoother_) smoother_->TransitionAddRows(rows, scale * m);
}

void SmoothingRecorder::BeginUpdate(const Eigen::VectorXd& x, const Eigen::MatrixXd& p) {
  if (smoother_) smoother_->BeginUpdate(x, p);
}

std::size_t SmoothingRecorder::Mark(double time_s, const Eigen::VectorXd& x, const Eigen::MatrixXd& p) {
  if (!smoother_) throw std::logic_error("MarkForSmoothing: smoothing is not enabled (EnableSmoothing)");
  return smoother_->Mark(time_s, x, p);
}

std::vector<SmoothedState> SmoothingRecorder::Finish(const Eigen::VectorXd& x, const Eigen::MatrixXd& p) {
  if (!smoother_) throw std::logic_error("FinishSmoothing: smoothing is not enabled (EnableSmoothing)");
  smoother_->End(x, p);
  const FixedIntervalSmoother recorded = std::move(*smoother_);
  smoother_.reset();
  return recorded.Smooth();
}

}  // namespace rowloc::localization
