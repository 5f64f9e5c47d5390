// Time ordering inside a reorder window (see reorder_buffer.hpp).
#include "rowloc/localization/reorder_buffer.hpp"

#include <algorithm>
#include <cmath>
#include <stdexcept>

namespace rowloc::localization {

ReorderBuffer::ReorderBuffer(double window_s) : window_s_(window_s) {
  if (!std::isfinite(window_s) || window_s < 0.0) throw std::invalid_argument("reorder window must be finite and >= 0 s");
}

ReorderBuffer::Admission ReorderBuffer::Add(formats::SensorMessage message) {
  const double t = formats::TimeOf(message);
  if (!std::isfinite(t)) throw std::invalid_argument("reorder buffer: message time is not finite");
  if (t < released_time_s_) return Admission::kTooOld;
  newest_time_s_ = std::max(newest_time_s_, t);
  held_.emplace(std::make_pair(t, arrivals_++), std::move(message));
  return Admission::kHeld;
}

formats::SensorMessage ReorderBuffer::Release(
    std::multimap<std::pair<double, std::uint64_t>, formats::SensorMessage>::iterator it) {
  released_time_s_ = it->first.first;
  formats::SensorMessage message = std::move(it->second);
  held_.erase(it);
  return message;
}

std::optional<formats::SensorMessage> ReorderBuffer::PopReady() {
  if (held_.empty() || held_.begin()->first.first > newest_time_s_ - window_s_) return std::nullopt;
  return Release(held_.begin());
}

std::optional<formats::SensorMessage> ReorderBuffer::PopAny() {
  if (held_.empty()) return std::nullopt;
  return Release(held_.begin());
}

}  // namespace rowloc::localization
