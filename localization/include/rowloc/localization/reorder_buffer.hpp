// Time ordering of a message stream whose messages may arrive late (a GNSS fix computed after
// newer IMU samples were sent; several sensor processes writing to one socket).
//
// A message is held until a message at least window_s newer has arrived (the newest time seen
// minus window_s reaches its time), then released; released messages come out in time order,
// equal times in arrival order. A message older than the last one released cannot be ordered any
// more: Add refuses it (kTooOld). With window_s = 0 every message is released at once and any
// message older than the one before it is refused, which is the rule of a sensor log. Flush
// releases everything held (the end of a stream). The order of releases is a function of the order
// of arrivals only, so the same arrivals always give the same filter input (the service's journal
// replays bit for bit).
#pragma once

#include "rowloc/formats/sensor_messages.hpp"

#include <cstddef>
#include <cstdint>
#include <limits>
#include <map>
#include <optional>
#include <utility>

namespace rowloc::localization {

class ReorderBuffer {
 public:
  /// window_s: finite, >= 0 (std::invalid_argument otherwise).
  explicit ReorderBuffer(double window_s);

  enum class Admission { kHeld, kTooOld };
  /// Holds the message (kHeld), or refuses it when its time is before the last released one.
  /// The time must be finite (std::invalid_argument otherwise).
  Admission Add(formats::SensorMessage message);

  /// The next message that may be released now, if any.
  std::optional<formats::SensorMessage> PopReady();
  /// The next held message, ready or not (end of stream).
  std::optional<formats::SensorMessage> PopAny();

  double window_s() const { return window_s_; }
  std::size_t held() const { return held_.size(); }
  /// The time of the last released message (-inf before any).
  double released_time_s() const { return released_time_s_; }
  /// The newest time seen (-inf before any).
  double newest_time_s() const { return newest_time_s_; }

 private:
  formats::SensorMessage Release(std::multimap<std::pair<double, std::uint64_t>, formats::SensorMessage>::iterator it);

  double window_s_;
  std::multimap<std::pair<double, std::uint64_t>, formats::SensorMessage> held_;
  std::uint64_t arrivals_ = 0;
  double newest_time_s_ = -std::numeric_limits<double>::infinity();
  double released_time_s_ = -std::numeric_limits<double>::infinity();
};

}  // namespace rowloc::localization
