// Latency histogram of the service's statistics (see service_stats.hpp).
#include "rowloc/service/service_stats.hpp"

#include <algorithm>
#include <cmath>

namespace rowloc::service {

double LatencyHistogram::UpperEdgeUs(int bin) {
  return std::exp2(static_cast<double>(bin + 1) / kBinsPerDoubling - 4.0);  // bin 0: up to 2^-4 us
}

void LatencyHistogram::Record(double microseconds) {
  if (!(microseconds >= 0.0)) return;
  const double position = (std::log2(std::max(microseconds, 1e-3)) + 4.0) * kBinsPerDoubling;
  const int bin = std::clamp(static_cast<int>(std::ceil(position)) - 1, 0, kBins - 1);
  bins_[static_cast<std::size_t>(bin)].fetch_add(1, std::memory_order_relaxed);
  const auto ns = static_cast<std::uint64_t>(std::min(microseconds * 1000.0, 1.8e19));
  std::uint64_t seen = max_ns_.load(std::memory_order_relaxed);
  while (ns > seen && !max_ns_.compare_exchange_weak(seen, ns, std::memory_order_relaxed)) {
  }
}

std::uint64_t LatencyHistogram::count() const {
  std::uint64_t n = 0;
  for (const auto& bin : bins_) n += bin.load(std::memory_order_relaxed);
  return n;
}

double LatencyHistogram::Quantile(double q) const {
  const std::uint64_t n = count();
  if (n == 0) return 0.0;
  const auto rank = static_cast<std::uint64_t>(std::ceil(std::clamp(q, 0.0, 1.0) * static_cast<double>(n)));
  std::uint64_t seen = 0;
  for (int bin = 0; bin < kBins; ++bin) {
    seen += bins_[static_cast<std::size_t>(bin)].load(std::memory_order_relaxed);
    if (seen >= std::max<std::uint64_t>(rank, 1)) return std::min(UpperEdgeUs(bin), max_us());
  }
  return max_us();
}

}  // namespace rowloc::service
