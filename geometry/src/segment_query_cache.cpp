#include "rowloc/geometry/segment_query_cache.hpp"

#include <algorithm>
#include <cmath>
#include <stdexcept>

namespace rowloc::geometry {

SegmentQueryCache::SegmentQueryCache(double margin_m, std::size_t slots) : margin_m_(margin_m), slots_(slots) {
  if (!(std::isfinite(margin_m) && margin_m >= 0.0)) {
    throw std::invalid_argument("SegmentQueryCache: margin_m must be finite and >= 0");
  }
  if (slots == 0) throw std::invalid_argument("SegmentQueryCache: at least one slot is needed");
}

void SegmentQueryCache::Clear() {
  for (Slot& slot : slots_) {
    slot.items.clear();  // keeps the capacity
    slot.last_use = 0;
  }
}

const std::vector<SegmentQueryCache::Item>* SegmentQueryCache::Find(const Box& query,
                                                                    const std::shared_ptr<const void>& owner) {
  // Owner equivalence (the same control block), not address equality: the weak handle keeps the
  // control block of the last owner alive, so a new index can never pass for a destroyed one.
  if (owner_.owner_before(owner) || owner.owner_before(owner_)) {
    Clear();
    owner_ = owner;
  }
  ++clock_;
  for (Slot& slot : slots_) {
    if (slot.last_use != 0 && slot.box.Contains(query)) {
      slot.last_use = clock_;
      ++hits_;
      return &slot.items;
    }
  }
  ++misses_;
  return nullptr;
}

std::vector<SegmentQueryCache::Item>& SegmentQueryCache::Store(const Box& query, Box& grown) {
  Slot& slot = *std::min_element(slots_.begin(), slots_.end(),
                                 [](const Slot& l, const Slot& r) { return l.last_use < r.last_use; });
  grown = Box{query.lo.array() - margin_m_, query.hi.array() + margin_m_};
  slot.box = grown;
  slot.last_use = ++clock_;
  slot.items.clear();
  return slot.items;
}

}  // namespace rowloc::geometry
