// SegmentQueryCache: the slots on their own (containment, least-recently-used replacement, owner
// change, bad parameters), and SegmentIndex::ConeCastNearest with a cache against the same query
// without one: bit for bit the same hits, for sensors driving along vineyard rows and for random
// cones on random segments, with both hits and misses of the cache exercised.
#include "rowloc/geometry/segment_query_cache.hpp"

#include "rowloc/geometry/row_map.hpp"
#include "rowloc/geometry/segment_index.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <limits>
#include <memory>
#include <numbers>
#include <random>
#include <stdexcept>
#include <vector>

namespace rowloc::geometry {
namespace {

using Box = SegmentQueryCache::Box;
using Item = SegmentQueryCache::Item;
using Hit = SegmentIndex::Hit;

Box MakeBox(double x0, double y0, double x1, double y1) { return Box{{x0, y0}, {x1, y1}}; }

TEST(SegmentQueryCacheBox, ContainsAndMeetsAreClosed) {
  const Box box = MakeBox(0.0, 0.0, 2.0, 1.0);
  EXPECT_TRUE(box.Contains(box));
  EXPECT_TRUE(box.Contains(MakeBox(0.5, 0.2, 2.0, 1.0)));
  EXPECT_FALSE(box.Contains(MakeBox(0.5, 0.2, 2.0 + 1e-12, 1.0)));
  EXPECT_FALSE(box.Contains(MakeBox(-1e-12, 0.2, 1.0, 1.0)));
  EXPECT_TRUE(box.Meets(MakeBox(2.0, 1.0, 3.0, 3.0)));  // touching corners meet (Boost's intersects)
  EXPECT_FALSE(box.Meets(MakeBox(2.0 + 1e-12, 0.0, 3.0, 3.0)));
  EXPECT_FALSE(box.Meets(MakeBox(0.0, -2.0, 1.0, -1e-12)));
}

TEST(SegmentQueryCache, RejectsBadParameters) {
  EXPECT_THROW(SegmentQueryCache(-0.1), std::invalid_argument);
  EXPECT_THROW(SegmentQueryCache(std::nan("")), std::invalid_argument);
  // Braces: with parentheses this statement declares a variable (clang refuses it; GCC reads an expression).
  EXPECT_THROW(SegmentQueryCache{std::numeric_limits<double>::infinity()}, std::invalid_argument);
  EXPECT_THROW(SegmentQueryCache(1.0, 0), std::invalid_argument);
  const SegmentQueryCache cache(0.0, 1);  // no margin and one slot are valid
  EXPECT_EQ(cache.margin_m(), 0.0);
  EXPECT_EQ(cache.slot_count(), 1u);
}

TEST(SegmentQueryCache, FindsAStoredBoxThatHoldsTheQuery) {
  const auto owner = std::make_shared<int>(1);
  SegmentQueryCache cache(0.5, 2);
  const Box query = MakeBox(0.0, 0.0, 1.0, 1.0);
  EXPECT_EQ(cache.Find(query, owner), nullptr);
  Box grown;
  std::vector<Item>& items = cache.Store(query, grown);
  EXPECT_EQ(grown.lo, Eigen::Vector2d(-0.5, -0.5));
  EXPECT_EQ(grown.hi, Eigen::Vector2d(1.5, 1.5));
  EXPECT_TRUE(items.empty());
  items.push_back(Item{MakeBox(0.0, 0.0, 1.0, 0.0), Segment2{{0.0, 0.0}, {1.0, 0.0}}, 7});
  const std::vector<Item>* found = cache.Find(MakeBox(-0.5, 0.2, 1.5, 1.5), owner);  // inside the grown box
  ASSERT_NE(found, nullptr);
  ASSERT_EQ(found->size(), 1u);
  EXPECT_EQ(found->front().entry, 7u);
  EXPECT_EQ(cache.Find(MakeBox(-0.6, 0.2, 1.0, 1.0), owner), nullptr);  // sticks out of it
  EXPECT_EQ(cache.hits(), 1u);
  EXPECT_EQ(cache.misses(), 2u);
  cache.Clear();
  EXPECT_EQ(cache.Find(query, owner), nullptr);  // forgotten; the counters stay
  EXPECT_EQ(cache.misses(), 3u);
}

TEST(SegmentQueryCache, ReplacesTheLeastRecentlyUsedSlot) {
  const auto owner = std::make_shared<int>(1);
  SegmentQueryCache cache(0.0, 2);
  Box grown;
  const Box a = MakeBox(0.0, 0.0, 1.0, 1.0), b = MakeBox(10.0, 0.0, 11.0, 1.0), c = MakeBox(20.0, 0.0, 21.0, 1.0);
  ASSERT_EQ(cache.Find(a, owner), nullptr);
  cache.Store(a, grown).push_back(Item{a, Segment2{{0.0, 0.0}, {1.0, 1.0}}, 1});
  ASSERT_EQ(cache.Find(b, owner), nullptr);
  cache.Store(b, grown).push_back(Item{b, Segment2{{10.0, 0.0}, {11.0, 1.0}}, 2});
  ASSERT_NE(cache.Find(a, owner), nullptr);  // a used last: b is the older one
  ASSERT_EQ(cache.Find(c, owner), nullptr);
  cache.Store(c, grown);
  EXPECT_NE(cache.Find(a, owner), nullptr);
  EXPECT_NE(cache.Find(c, owner), nullptr);
  EXPECT_EQ(cache.Find(b, owner), nullptr);  // replaced
}

TEST(SegmentQueryCache, ForgetsEverythingForAnotherOwner) {
  auto first = std::make_shared<int>(1);
  SegmentQueryCache cache(1.0, 4);
  const Box query = MakeBox(0.0, 0.0, 1.0, 1.0);
  Box grown;
  ASSERT_EQ(cache.Find(query, first), nullptr);
  cache.Store(query, grown);
  ASSERT_NE(cache.Find(query, first), nullptr);
  const std::shared_ptr<const void> copy = first;  // the same owner through another handle
  EXPECT_NE(cache.Find(query, copy), nullptr);
  const auto second = std::make_shared<int>(1);
  EXPECT_EQ(cache.Find(query, second), nullptr);
  cache.Store(query, grown);
  EXPECT_EQ(cache.Find(query, first), nullptr);  // switching back forgets the second's slot too
  // A destroyed owner and a new object, possibly at the same address, are different owners.
  first.reset();
  const auto third = std::make_shared<int>(3);
  cache.Store(query, grown);
  EXPECT_EQ(cache.Find(query, third), nullptr);
}

// ---- through SegmentIndex: the same hits with and without a cache ----------------------------

void ExpectSameHits(const std::vector<Hit>& expected, const std::vector<Hit>& got, int query) {
  ASSERT_EQ(expected.size(), got.size()) << "query " << query;
  for (std::size_t i = 0; i < expected.size(); ++i) {
    EXPECT_EQ(expected[i].entry, got[i].entry) << "query " << query;
    EXPECT_EQ(expected[i].hit.range_m, got[i].hit.range_m) << "query " << query;  // bit for bit
    EXPECT_EQ(expected[i].hit.point, got[i].hit.point) << "query " << query;
    EXPECT_EQ(expected[i].hit.normal, got[i].hit.normal) << "query " << query;
    EXPECT_EQ(expected[i].hit.segment_param, got[i].hit.segment_param) << "query " << query;
  }
}

TEST(SegmentIndexWithQueryCache, SensorsDrivingAlongRowsGetTheSameHits) {
  SampleRowMapParams params;
  params.row_count = 8;
  params.row_length_m = 40.0;
  params.vertex_spacing_m = 1.0;
  const SegmentIndex index = SegmentIndex::FromRowMap(MakeSampleRowMap(params));
  SegmentQueryCache cache;  // the defaults a filter uses
  std::mt19937_64 rng(11);
  std::normal_distribution<double> jitter(0.0, 0.03);
  const Eigen::Vector2d along(std::cos(params.heading_rad), std::sin(params.heading_rad));
  const Eigen::Vector2d across(-along.y(), along.x());
  const double beams[] = {std::numbers::pi / 2, -std::numbers::pi / 2, 0.3, std::numbers::pi - 0.3};
  std::vector<Hit> plain, cached;
  int query = 0;
  std::size_t nonempty = 0;
  for (double u = 2.0; u < 38.0; u += 0.1) {  // 10 cm per round of four sensors
    const Eigen::Vector2d apex = u * along + (2.5 * 3.5 + jitter(rng)) * across;
    for (const double beam : beams) {
      const double heading = params.heading_rad + beam + jitter(rng);
      const Cone2 cone{apex, {std::cos(heading), std::sin(heading)}, 7.5 * std::numbers::pi / 180.0, 5.0};
      const double window_m = std::abs(jitter(rng)) * 5.0;
      index.ConeCastNearest(cone, window_m, plain);
      index.ConeCastNearest(cone, window_m, cached, &cache);
      ExpectSameHits(plain, cached, query++);
      nonempty += plain.empty() ? 0 : 1;
    }
  }
  EXPECT_GT(nonempty, static_cast<std::size_t>(query) / 2);  // the sideways sensors see rows
  EXPECT_GT(cache.hits(), 5 * cache.misses());  // most queries answered from the cache ...
  EXPECT_GT(cache.misses(), 8u);                // ... and the drive leaves stored boxes behind
}

TEST(SegmentIndexWithQueryCache, RandomConesAndAnIndexSwitchGetTheSameHits) {
  std::mt19937_64 rng(5);
  std::uniform_real_distribution<double> coord(0.0, 60.0), length(0.2, 3.0), angle(-std::numbers::pi, std::numbers::pi);
  const auto random_index = [&](std::size_t n) {
    std::vector<SegmentIndex::Entry> entries;
    for (std::size_t i = 0; i < n; ++i) {
      const Eigen::Vector2d c(coord(rng), coord(rng));
      const double a = angle(rng);
      const Eigen::Vector2d half = 0.5 * length(rng) * Eigen::Vector2d(std::cos(a), std::sin(a));
      entries.push_back(SegmentIndex::Entry{Segment2{c - half, c + half}, i, 0});
    }
    return SegmentIndex(std::move(entries));
  };
  const SegmentIndex first = random_index(3000), second = random_index(3000);
  SegmentQueryCache cache(0.7, 3);
  std::uniform_real_distribution<double> step(-0.3, 0.3), aperture(0.0, 0.5), window(0.0, 2.0);
  Eigen::Vector2d apex(30.0, 30.0);
  std::vector<Hit> plain, cached;
  for (int q = 0; q < 600; ++q) {
    apex += Eigen::Vector2d(step(rng), step(rng));  // a random walk: hits and misses
    const double a = angle(rng);
    const double max_range_m = q % 3 == 0 ? std::numeric_limits<double>::infinity() : 4.0;
    const Cone2 cone{apex, {std::cos(a), std::sin(a)}, aperture(rng), max_range_m};
    const SegmentIndex& index = (q / 50) % 2 == 0 ? first : second;  // the cache follows the index
    const double window_m = window(rng);
    index.ConeCastNearest(cone, window_m, plain);
    index.ConeCastNearest(cone, window_m, cached, &cache);
    ExpectSameHits(plain, cached, q);
  }
  EXPECT_GT(cache.hits(), 0u);
  EXPECT_GT(cache.misses(), 12u);  // at least one per switch of the index
}

}  // namespace
}  // namespace rowloc::geometry
