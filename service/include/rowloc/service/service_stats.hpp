// Counters of the service for `stats` (docs/service.md §2): messages, refusals by error code,
// dropped subscription lines, and the distribution of the time from a line's arrival to the end
// of its handling. Lock-free (atomics), so that every connection thread can count.
//
// Latencies are kept in a histogram of logarithmic bins, 16 per doubling from 1/16 us to about
// 67 s: a percentile is the upper edge of its bin, within 4.4 % of the true value.
#pragma once

#include "rowloc/service/service_error.hpp"

#include <array>
#include <atomic>
#include <cstddef>
#include <cstdint>

namespace rowloc::service {

class LatencyHistogram {
 public:
  static constexpr int kBinsPerDoubling = 16;
  static constexpr int kBins = 30 * kBinsPerDoubling;
  void Record(double microseconds);
  /// The q-quantile (0 < q <= 1) in microseconds; 0 when nothing was recorded.
  double Quantile(double q) const;
  double max_us() const { return max_ns_.load(std::memory_order_relaxed) / 1000.0; }
  std::uint64_t count() const;

 private:
  static double UpperEdgeUs(int bin);
  std::array<std::atomic<std::uint64_t>, kBins> bins_{};
  std::atomic<std::uint64_t> max_ns_{0};
};

struct ServiceStats {
  std::atomic<std::uint64_t> lines{0};
  std::atomic<std::uint64_t> sensor_messages{0};
  std::atomic<std::uint64_t> dropped_lines{0};
  /// The longest outgoing queue any connection has held (lines): the slow-client bound at work.
  std::atomic<std::uint64_t> queue_high_water_lines{0};
  std::atomic<std::uint64_t> connections{0};
  std::atomic<std::uint64_t> connections_total{0};
  std::array<std::atomic<std::uint64_t>, std::size(kAllErrorCodes)> rejects{};
  LatencyHistogram latency;

  void RecordQueueLength(std::uint64_t queue_lines) {
    std::uint64_t seen = queue_high_water_lines.load(std::memory_order_relaxed);
    while (queue_lines > seen && !queue_high_water_lines.compare_exchange_weak(seen, queue_lines, std::memory_order_relaxed)) {
    }
  }
  void CountReject(ErrorCode code) { rejects[static_cast<std::size_t>(code)].fetch_add(1, std::memory_order_relaxed); }
};

}  // namespace rowloc::service
