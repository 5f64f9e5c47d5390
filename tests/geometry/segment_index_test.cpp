// SegmentIndex (docs/planar-geometry.md): every query against an exhaustive loop over all
// segments, on 10^5 random segments and on vineyard maps with rows in every direction.
#include "rowloc/geometry/segment_index.hpp"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <limits>
#include <numbers>
#include <random>
#include <stdexcept>
#include <string>

namespace rowloc::geometry {
namespace {

using Entry = SegmentIndex::Entry;
using Hit = SegmentIndex::Hit;
constexpr double kPi = std::numbers::pi;
const double kInf = std::numeric_limits<double>::infinity();

// Brute-force queries per test: unoptimized (sanitizer) builds run about 50x slower, so they run
// a fiftieth of the queries; the map keeps its 10^5 segments.
#ifdef NDEBUG
constexpr int kQueryScale = 50;
#else
constexpr int kQueryScale = 1;
#endif

double Deg(double deg) { return deg * kPi / 180.0; }
Eigen::Vector2d Heading(double rad) { return {std::cos(rad), std::sin(rad)}; }

// ---- brute force: exhaustive loops, ties to the lower entry --------------------------------

template <class Cast>
std::optional<Hit> BruteNearestHit(const std::vector<Entry>& entries, Cast cast) {
  std::optional<Hit> best;
  for (std::size_t i = 0; i < entries.size(); ++i) {
    if (auto h = cast(entries[i].segment); h && (!best || h->range_m < best->hit.range_m)) best = Hit{*h, i};
  }
  return best;
}

std::optional<Hit> BruteRay(const std::vector<Entry>& e, const Eigen::Vector2d& o,
                            const Eigen::Vector2d& d, double range) {
  return BruteNearestHit(e, [&](const Segment2& s) { return RayCast(s, o, d, range); });
}

// PreparedCone::Cast is ConeCast(s, cone) without re-validating the cone for every segment.
std::optional<Hit> BruteCone(const std::vector<Entry>& e, const Cone2& cone) {
  const PreparedCone prepared(cone);
  return BruteNearestHit(e, [&](const Segment2& s) { return prepared.Cast(s); });
}

std::vector<std::size_t> BruteConeAll(const std::vector<Entry>& e, const Cone2& cone) {
  const PreparedCone prepared(cone);
  std::vector<std::size_t> touched;
  for (std::size_t i = 0; i < e.size(); ++i) {
    if (prepared.Cast(e[i].segment)) touched.push_back(i);
  }
  return touched;
}

std::vector<double> BruteNearestDistances(const std::vector<Entry>& e, const Eigen::Vector2d& p,
                                          std::size_t k) {
  std::vector<double> d;
  d.reserve(e.size());
  for (const Entry& entry : e) d.push_back(entry.segment.Distance(p));
  k = std::min(k, d.size());
  std::partial_sort(d.begin(), d.begin() + static_cast<std::ptrdiff_t>(k), d.end());
  d.resize(k);
  return d;
}

void ExpectSameHit(const std::optional<Hit>& index, const std::optional<Hit>& brute,
                   const std::string& what) {
  ASSERT_EQ(index.has_value(), brute.has_value()) << what;
  if (!index) return;
  EXPECT_EQ(index->entry, brute->entry) << what;
  EXPECT_EQ(index->hit.range_m, brute->hit.range_m) << what;
  EXPECT_EQ(index->hit.point, brute->hit.point) << what;
}

// ---- maps -----------------------------------------------------------------------------------

std::vector<Entry> RandomSegments(std::size_t n, double extent_m, std::uint64_t seed) {
  std::mt19937_64 rng(seed);
  std::uniform_real_distribution<double> centre(0.0, extent_m);
  std::uniform_real_distribution<double> length(0.2, 3.0);
  std::uniform_real_distribution<double> angle(-kPi, kPi);
  std::vector<Entry> entries;
  entries.reserve(n);
  for (std::size_t i = 0; i < n; ++i) {
    const Eigen::Vector2d c(centre(rng), centre(rng));
    const Eigen::Vector2d half = 0.5 * length(rng) * Heading(angle(rng));
    entries.push_back(Entry{Segment2{c - half, c + half}, i, 0});
  }
  return entries;
}

class RandomMap : public ::testing::Test {
 protected:
  static void SetUpTestSuite() {
    entries_ = new std::vector<Entry>(RandomSegments(100000, 300.0, 42));
    index_ = new SegmentIndex(*entries_);
  }
  static void TearDownTestSuite() {
    delete index_;
    delete entries_;
  }
  static std::vector<Entry>* entries_;
  static SegmentIndex* index_;
  std::mt19937_64 rng_{1234};
  std::uniform_real_distribution<double> coord_{-20.0, 320.0};
  std::uniform_real_distribution<double> angle_{-kPi, kPi};
};
std::vector<Entry>* RandomMap::entries_ = nullptr;
SegmentIndex* RandomMap::index_ = nullptr;

TEST_F(RandomMap, HoldsEveryEntry) {
  EXPECT_EQ(index_->size(), 100000u);
  ASSERT_EQ(index_->entries().size(), entries_->size());
  EXPECT_EQ(index_->entries()[777].segment.a, (*entries_)[777].segment.a);
}

TEST_F(RandomMap, NearestMatchesBruteForce) {
  for (int q = 0; q < 20 * kQueryScale; ++q) {
    const Eigen::Vector2d p(coord_(rng_), coord_(rng_));
    const std::size_t k = q % 2 == 0 ? 1 : 8;
    const auto nearest = index_->Nearest(p, k);
    const auto brute = BruteNearestDistances(*entries_, p, k);
    ASSERT_EQ(nearest.size(), brute.size());
    for (std::size_t i = 0; i < k; ++i) {
      EXPECT_EQ(nearest[i].first, brute[i]) << "query " << q << " rank " << i;
      EXPECT_EQ(nearest[i].first, (*entries_)[nearest[i].second].segment.Distance(p));
    }
  }
}

TEST_F(RandomMap, RayCastMatchesBruteForce) {
  const double ranges[] = {4.0, 25.0, kInf};
  int hits = 0;
  for (int q = 0; q < 20 * kQueryScale; ++q) {
    const Eigen::Vector2d o(coord_(rng_), coord_(rng_));
    const Eigen::Vector2d d = 3.0 * Heading(angle_(rng_));  // not unit on purpose
    const double range = ranges[q % 3];
    const auto index = index_->RayCast(o, d, range);
    ExpectSameHit(index, BruteRay(*entries_, o, d, range), "ray " + std::to_string(q));
    hits += index.has_value();
  }
  EXPECT_GT(hits, 6 * kQueryScale);
}

TEST_F(RandomMap, ConeCastMatchesBruteForce) {
  const double ranges[] = {4.0, 15.0, kInf};
  std::uniform_real_distribution<double> aperture(0.0, Deg(80.0));
  int hits = 0;
  for (int q = 0; q < 20 * kQueryScale; ++q) {
    const double h = q % 4 == 0 ? Deg(7.5) : aperture(rng_);
    const Cone2 cone{{coord_(rng_), coord_(rng_)}, Heading(angle_(rng_)), h, ranges[q % 3]};
    const auto index = index_->ConeCast(cone);
    ExpectSameHit(index, BruteCone(*entries_, cone), "cone " + std::to_string(q));
    hits += index.has_value();
  }
  EXPECT_GT(hits, 10 * kQueryScale);
}

TEST_F(RandomMap, ConeCastAllMatchesBruteForce) {
  std::uniform_real_distribution<double> aperture(0.0, Deg(60.0));
  std::size_t touched_total = 0;
  for (int q = 0; q < 4 * kQueryScale; ++q) {
    const Cone2 cone{{coord_(rng_), coord_(rng_)}, Heading(angle_(rng_)), aperture(rng_), 6.0};
    const auto all = index_->ConeCastAll(cone);
    std::vector<std::size_t> got;
    for (std::size_t i = 0; i < all.size(); ++i) {
      got.push_back(all[i].entry);
      if (i > 0) {
        EXPECT_LE(all[i - 1].hit.range_m, all[i].hit.range_m);
      }
      EXPECT_EQ(all[i].hit.range_m, ConeCast((*entries_)[all[i].entry].segment, cone)->range_m);
    }
    std::sort(got.begin(), got.end());
    EXPECT_EQ(got, BruteConeAll(*entries_, cone)) << "cone " << q;
    touched_total += got.size();
  }
  EXPECT_GT(touched_total, 4u * kQueryScale);
}

TEST_F(RandomMap, ConeCastAllFromAMinimumRangeMatchesBruteForce) {
  std::uniform_real_distribution<double> aperture(0.0, Deg(60.0));
  std::uniform_real_distribution<double> min_range(0.0, 4.0);
  std::size_t dropped_total = 0, kept_total = 0;
  for (int q = 0; q < 4 * kQueryScale; ++q) {
    const Cone2 cone{{coord_(rng_), coord_(rng_)}, Heading(angle_(rng_)), aperture(rng_), 6.0};
    const double from_m = min_range(rng_);
    std::vector<std::size_t> expected;
    for (const std::size_t entry : BruteConeAll(*entries_, cone)) {
      if (ConeCast((*entries_)[entry].segment, cone)->range_m >= from_m) {
        expected.push_back(entry);
      } else {
        ++dropped_total;
      }
    }
    std::vector<std::size_t> got;
    for (const Hit& hit : index_->ConeCastAll(cone, from_m)) {
      EXPECT_GE(hit.hit.range_m, from_m);
      got.push_back(hit.entry);
    }
    std::sort(got.begin(), got.end());
    EXPECT_EQ(got, expected) << "cone " << q << " from " << from_m << " m";
    kept_total += got.size();
  }
  EXPECT_GT(dropped_total, 0u);  // the minimum range really removes hits ...
  EXPECT_GT(kept_total, 0u);     // ... and keeps others
  const Cone2 cone{{0.0, 0.0}, {1.0, 0.0}, Deg(10.0), 6.0};
  EXPECT_TRUE(index_->ConeCastAll(cone, 7.0).empty());  // beyond max_range: nothing
  EXPECT_THROW(index_->ConeCastAll(cone, -0.1), std::invalid_argument);
  EXPECT_THROW(index_->ConeCastAll(cone, std::nan("")), std::invalid_argument);
  EXPECT_THROW(index_->ConeCastAll(cone, std::numeric_limits<double>::infinity()), std::invalid_argument);
}

TEST_F(RandomMap, ConeCastNearestMatchesBruteForceWindow) {
  std::uniform_real_distribution<double> aperture(0.0, Deg(60.0));
  std::uniform_real_distribution<double> window(0.0, 3.0);
  std::size_t beyond_window = 0, several = 0;
  std::vector<Hit> reused;  // one buffer for every query
  for (int q = 0; q < 4 * kQueryScale; ++q) {
    const Cone2 cone{{coord_(rng_), coord_(rng_)}, Heading(angle_(rng_)), aperture(rng_), q % 2 == 0 ? 6.0 : kInf};
    const double window_m = q % 7 == 0 ? 0.0 : window(rng_);
    // Brute force: every hit of the sector, those within window_m of the nearest.
    std::vector<std::pair<double, std::size_t>> all;
    for (const std::size_t entry : BruteConeAll(*entries_, cone)) {
      all.emplace_back(ConeCast((*entries_)[entry].segment, cone)->range_m, entry);
    }
    std::sort(all.begin(), all.end());
    std::vector<std::size_t> expected;
    for (const auto& [range_m, entry] : all) {
      if (range_m <= all.front().first + window_m) {
        expected.push_back(entry);
      } else {
        ++beyond_window;
      }
    }
    std::vector<std::size_t> got;
    const std::vector<Hit> hits = index_->ConeCastNearest(cone, window_m);
    index_->ConeCastNearest(cone, window_m, reused);  // the buffer version: cleared, then the same
    ASSERT_EQ(reused.size(), hits.size());
    for (std::size_t i = 0; i < hits.size(); ++i) {
      EXPECT_EQ(reused[i].entry, hits[i].entry);
      EXPECT_EQ(reused[i].hit.range_m, hits[i].hit.range_m);
    }
    for (std::size_t i = 0; i < hits.size(); ++i) {
      got.push_back(hits[i].entry);
      if (i > 0) {
        EXPECT_LE(hits[i - 1].hit.range_m, hits[i].hit.range_m);  // by range
      }
    }
    EXPECT_EQ(got, expected) << "cone " << q << " window " << window_m << " m";
    if (!hits.empty()) {  // the first is ConeCast's hit
      const std::optional<Hit> nearest = index_->ConeCast(cone);
      ASSERT_TRUE(nearest.has_value());
      EXPECT_EQ(hits.front().entry, nearest->entry);
      EXPECT_EQ(hits.front().hit.range_m, nearest->hit.range_m);
    }
    several += got.size() > 1 ? 1 : 0;
  }
  EXPECT_GT(beyond_window, 0u);  // the window really removes hits ...
  EXPECT_GT(several, 0u);        // ... and keeps several in some cones
  const Cone2 cone{{0.0, 0.0}, {1.0, 0.0}, Deg(10.0), 6.0};
  EXPECT_THROW(index_->ConeCastNearest(cone, -0.1), std::invalid_argument);
  EXPECT_THROW(index_->ConeCastNearest(cone, std::nan("")), std::invalid_argument);
  std::vector<std::size_t> all, unbounded;  // an infinite window: every hit, as ConeCastAll
  for (const Hit& hit : index_->ConeCastAll(cone)) all.push_back(hit.entry);
  for (const Hit& hit : index_->ConeCastNearest(cone, kInf)) unbounded.push_back(hit.entry);
  EXPECT_EQ(unbounded, all);
  EXPECT_TRUE(SegmentIndex({}).ConeCastNearest(cone, 1.0).empty());  // an empty index
}

// ---- vineyards: rows in every direction -------------------------------------------------------

class VineyardHeading : public ::testing::TestWithParam<double> {};

TEST_P(VineyardHeading, QueriesMatchBruteForce) {
  SampleRowMapParams params;
  params.heading_rad = Deg(GetParam());
  params.row_count = 6;
  params.row_length_m = 30.0;
  params.vertex_spacing_m = 0.5;
  params.bow_m = GetParam() == 0.0 || GetParam() == 90.0 ? 0.0 : 0.4;  // exactly axis-parallel rows
  const RowMap map = MakeSampleRowMap(params);
  const SegmentIndex index = SegmentIndex::FromRowMap(map);
  ASSERT_EQ(index.size(), map.SegmentCount());
  const auto& entries = index.entries();
  const Eigen::Vector2d along = Heading(params.heading_rad);
  const Eigen::Vector2d across(-along.y(), along.x());
  std::mt19937_64 rng(99);
  std::uniform_real_distribution<double> u(-5.0, 35.0), v(-3.0, 15.0), angle(-kPi, kPi);
  for (int q = 0; q < 12 * kQueryScale; ++q) {
    const Eigen::Vector2d p = u(rng) * along + v(rng) * across;
    // Half the queries look exactly along or across the rows (parallel and perpendicular cases).
    const Eigen::Vector2d dirs[] = {along, -along, across, -across, Heading(angle(rng))};
    const Eigen::Vector2d d = dirs[q % 5];
    const std::string what = "heading " + std::to_string(GetParam()) + " query " + std::to_string(q);
    ExpectSameHit(index.RayCast(p, d, 4.0), BruteRay(entries, p, d, 4.0), what);
    const Cone2 cone{p, d, Deg(7.5), 4.0};
    ExpectSameHit(index.ConeCast(cone), BruteCone(entries, cone), what);
    EXPECT_EQ(index.Nearest(p, 3).front().first, BruteNearestDistances(entries, p, 1).front()) << what;
  }
}

INSTANTIATE_TEST_SUITE_P(Headings, VineyardHeading,
                         ::testing::Values(0.0, 45.0, 90.0, 135.0, 180.0, 270.0));

// Segments that graze the edge rays of the cones (perpendicular offsets around the contact
// tolerance, collinear with an edge, through the apex, just behind it): the pruning of the index
// (piece boxes, half-planes, distance cut-off) must keep exactly what the brute force keeps.
TEST(SegmentIndex, GrazingSegmentsMatchBruteForce) {
  const double offsets[] = {-3e-9, -1.5e-9, -1e-9, -5e-10, 0.0, 5e-10, 1e-9, 2e-9};
  const double ranges[] = {0.7, 1.9, 3.999999999, 4.0, 4.000000001, 6.5};
  std::mt19937_64 rng(5);
  std::uniform_real_distribution<double> coord(0.0, 40.0), angle(-kPi, kPi), half(0.0, Deg(45.0));
  std::vector<Cone2> cones;
  std::vector<Entry> entries = RandomSegments(400, 40.0, 6);
  for (int c = 0; c < 6; ++c) {
    const Cone2 cone{{coord(rng), coord(rng)}, Heading(angle(rng)), c == 0 ? 0.0 : half(rng), 4.0};
    cones.push_back(cone);
    const PreparedCone prepared(cone);
    for (const Eigen::Vector2d& edge : {prepared.edge_cw(), prepared.edge_ccw()}) {
      const Eigen::Vector2d out = edge == prepared.edge_cw() ? Eigen::Vector2d(edge.y(), -edge.x())
                                                            : Eigen::Vector2d(-edge.y(), edge.x());
      for (double r : ranges) {
        for (double offset : offsets) {
          const Eigen::Vector2d foot = cone.apex + r * edge + offset * out;
          entries.push_back(Entry{Segment2{foot, foot + 0.3 * out}, 0, entries.size()});  // across
          entries.push_back(Entry{Segment2{foot, foot + 0.4 * edge}, 0, entries.size()});  // along
        }
      }
    }
    entries.push_back(Entry{Segment2{cone.apex, cone.apex - 0.5 * cone.axis}, 0, entries.size()});
    const Eigen::Vector2d behind = cone.apex - 1e-9 * cone.axis;
    const Eigen::Vector2d side(-cone.axis.y(), cone.axis.x());
    entries.push_back(Entry{Segment2{behind - side, behind + side}, 0, entries.size()});
  }
  const SegmentIndex index(entries);
  for (std::size_t c = 0; c < cones.size(); ++c) {
    const Cone2& cone = cones[c];
    const std::string what = "cone " + std::to_string(c);
    ExpectSameHit(index.ConeCast(cone), BruteCone(entries, cone), what);
    const PreparedCone prepared(cone);
    for (const Eigen::Vector2d& d : {prepared.edge_cw(), prepared.edge_ccw(), cone.axis}) {
      ExpectSameHit(index.RayCast(cone.apex, d, cone.max_range_m),
                    BruteRay(entries, cone.apex, d, cone.max_range_m), what + " ray");
    }
    std::vector<std::size_t> got;
    for (const Hit& hit : index.ConeCastAll(cone)) got.push_back(hit.entry);
    std::sort(got.begin(), got.end());
    EXPECT_EQ(got, BruteConeAll(entries, cone)) << what;
    EXPECT_GT(got.size(), 20u) << what;  // the grazing segments are really touched
  }
}

// A hit inside the contact tolerance can be nearer than its segment is: the ray meets the line of
// `grazing` 0.3 nm before the wall, 0.5 nm before the segment starts; the cast reports that nearer
// range and it wins over the wall although the wall segment is nearer to the origin.
TEST(SegmentIndex, HitWithinTheContactToleranceBeatsANearerSegment) {
  const Eigen::Vector2d u = Heading(Deg(30.0));
  const Eigen::Vector2d crossing(2.0 - 0.3e-9, 0.0);
  std::vector<Entry> entries = RandomSegments(500, 20.0, 15);
  for (Entry& e : entries) {  // keep the background away from the ray
    e.segment.a.y() += 30.0;
    e.segment.b.y() += 30.0;
  }
  entries.push_back(Entry{Segment2{{2.0, -0.5}, {2.0, 0.5}}, 0, 0});                    // the wall
  entries.push_back(Entry{Segment2{crossing + 0.5e-9 * u, crossing + 1.0 * u}, 0, 0});  // grazing
  const SegmentIndex index(entries);
  const auto ray = index.RayCast({0.0, 0.0}, {1.0, 0.0}, 4.0);
  ExpectSameHit(ray, BruteRay(entries, {0.0, 0.0}, {1.0, 0.0}, 4.0), "ray");
  ASSERT_TRUE(ray.has_value());
  EXPECT_EQ(ray->entry, entries.size() - 1);
  EXPECT_LT(ray->hit.range_m, 2.0);
  const Cone2 cone{{0.0, 0.0}, {1.0, 0.0}, 0.0, 4.0};
  ExpectSameHit(index.ConeCast(cone), BruteCone(entries, cone), "cone");
}

// Map coordinates of a projected frame (UTM: 10^5-10^6 m): the rounding margins scale with them.
TEST(SegmentIndex, LargeCoordinatesMatchBruteForce) {
  const Eigen::Vector2d utm(452317.25, 5412873.5);
  std::vector<Entry> entries = RandomSegments(20000, 150.0, 11);
  for (Entry& e : entries) {
    e.segment.a += utm;
    e.segment.b += utm;
  }
  const SegmentIndex index(entries);
  std::mt19937_64 rng(12);
  std::uniform_real_distribution<double> coord(0.0, 150.0), angle(-kPi, kPi), half(0.0, Deg(60.0));
  const double ranges[] = {4.0, 20.0, kInf};
  int hits = 0;
  for (int q = 0; q < 6 * kQueryScale; ++q) {
    const Cone2 cone{utm + Eigen::Vector2d(coord(rng), coord(rng)), Heading(angle(rng)),
                     q % 3 == 0 ? Deg(7.5) : half(rng), ranges[q % 3]};
    const std::string what = "query " + std::to_string(q);
    const auto hit = index.ConeCast(cone);
    ExpectSameHit(hit, BruteCone(entries, cone), what);
    ExpectSameHit(index.RayCast(cone.apex, cone.axis, cone.max_range_m),
                  BruteRay(entries, cone.apex, cone.axis, cone.max_range_m), what);
    hits += hit.has_value();
  }
  EXPECT_GT(hits, 3 * kQueryScale);
}

// Identical segments under different entries: every query reports the lower entry.
TEST(SegmentIndex, DuplicateSegmentsReportTheLowerEntry) {
  std::vector<Entry> entries = RandomSegments(3000, 30.0, 13);
  const std::size_t n = entries.size();
  for (std::size_t i = 0; i < n; ++i) entries.push_back(entries[i]);  // entry i + n copies entry i
  const SegmentIndex index(entries);
  std::mt19937_64 rng(14);
  std::uniform_real_distribution<double> coord(0.0, 30.0), angle(-kPi, kPi);
  int hits = 0;
  for (int q = 0; q < 200; ++q) {
    const Cone2 cone{{coord(rng), coord(rng)}, Heading(angle(rng)), Deg(7.5), 4.0};
    const auto hit = index.ConeCast(cone);
    ExpectSameHit(hit, BruteCone(entries, cone), "cone " + std::to_string(q));
    const auto ray = index.RayCast(cone.apex, cone.axis, 4.0);
    ExpectSameHit(ray, BruteRay(entries, cone.apex, cone.axis, 4.0), "ray " + std::to_string(q));
    if (hit) {
      EXPECT_LT(hit->entry, n);
    }
    if (ray) {
      EXPECT_LT(ray->entry, n);
    }
    hits += hit.has_value();
  }
  EXPECT_GT(hits, 50);
}

TEST(SegmentIndex, FromRowMapNumbersRowsAndSegments) {
  RowMap map;
  map.rows.push_back(Row{"a", {{0.0, 0.0}, {1.0, 0.0}, {2.0, 0.0}}, false, 0.0});
  map.rows.push_back(Row{"b", {{0.0, 2.0}, {1.0, 2.0}, {1.0, 3.0}}, true, 0.0});
  const SegmentIndex index = SegmentIndex::FromRowMap(map);
  ASSERT_EQ(index.size(), 5u);
  EXPECT_EQ(index.entries()[1].row, 0u);
  EXPECT_EQ(index.entries()[1].segment_in_row, 1u);
  EXPECT_EQ(index.entries()[4].row, 1u);
  EXPECT_EQ(index.entries()[4].segment_in_row, 2u);
  EXPECT_EQ(index.entries()[4].segment.b, Eigen::Vector2d(0.0, 2.0));  // closing segment
}

TEST(SegmentIndex, LongWallOfShortSegmentsMatchesAnalyticConeRange) {
  // Wall y = 2 made of 0.5 m segments; apex at the origin; axis at theta from the wall normal.
  std::vector<Entry> entries;
  for (int i = -400; i < 400; ++i) {
    entries.push_back(Entry{Segment2{{0.5 * i, 2.0}, {0.5 * (i + 1), 2.0}}, 0, entries.size()});
  }
  const SegmentIndex index(entries);
  for (double h_deg : {0.0, 7.5, 30.0}) {
    for (double theta_deg : {-60.0, -7.5, 0.0, 3.0, 40.0, 75.0}) {
      const double h = Deg(h_deg), theta = Deg(theta_deg);
      const double expected = std::abs(theta) <= h ? 2.0 : 2.0 / std::cos(std::abs(theta) - h);
      const auto hit = index.ConeCast(Cone2{{0.0, 0.0}, Heading(kPi / 2.0 + theta), h, kInf});
      ASSERT_TRUE(hit.has_value());
      EXPECT_NEAR(hit->hit.range_m, expected, 1e-9) << h_deg << " " << theta_deg;
    }
  }
}

TEST(SegmentIndex, ConeCastAllAtAPolygonCornerReturnsBothSegments) {
  RowMap map;
  map.rows.push_back(Row{"square", {{0.0, 0.0}, {1.0, 0.0}, {1.0, 1.0}, {0.0, 1.0}}, true, 0.0});
  const SegmentIndex index = SegmentIndex::FromRowMap(map);
  const auto all = index.ConeCastAll(Cone2{{2.0, 2.0}, {-1.0, -1.0}, Deg(7.5), 2.0});
  ASSERT_EQ(all.size(), 2u);
  EXPECT_EQ(all[0].entry, 1u);  // equal ranges: by entry
  EXPECT_EQ(all[1].entry, 2u);
  EXPECT_NEAR(all[0].hit.range_m, std::sqrt(2.0), 1e-12);
  EXPECT_NEAR(all[1].hit.range_m, std::sqrt(2.0), 1e-12);
  // The ray exactly through the corner reports the lower entry.
  const auto ray = index.RayCast({2.0, 2.0}, {-1.0, -1.0}, 5.0);
  ASSERT_TRUE(ray.has_value());
  EXPECT_EQ(ray->entry, 1u);
}

TEST(SegmentIndex, FarAwaySegmentIsFoundWithInfiniteRange) {
  std::vector<Entry> entries = RandomSegments(1000, 10.0, 3);
  entries.push_back(Entry{Segment2{{5000.0, -1.0}, {5000.0, 1.0}}, 0, 0});
  const SegmentIndex index(entries);
  const auto hit = index.RayCast({20.0, 0.0}, {1.0, 0.0}, kInf);
  ASSERT_TRUE(hit.has_value());
  EXPECT_EQ(hit->entry, 1000u);
  EXPECT_NEAR(hit->hit.range_m, 4980.0, 1e-9);
  EXPECT_FALSE(index.RayCast({20.0, 0.0}, {1.0, 0.0}, 4979.0).has_value());
}

TEST(SegmentIndex, EmptyIndexAnswersNothing) {
  const SegmentIndex index(std::vector<Entry>{});
  EXPECT_EQ(index.size(), 0u);
  EXPECT_TRUE(index.Nearest({0.0, 0.0}, 3).empty());
  EXPECT_FALSE(index.RayCast({0.0, 0.0}, {1.0, 0.0}, kInf).has_value());
  EXPECT_FALSE(index.ConeCast(Cone2{{0.0, 0.0}, {1.0, 0.0}, 0.1, 4.0}).has_value());
  EXPECT_TRUE(index.ConeCastAll(Cone2{{0.0, 0.0}, {1.0, 0.0}, 0.1, 4.0}).empty());
  // Bad queries are still rejected.
  EXPECT_THROW(index.RayCast({0.0, 0.0}, {0.0, 0.0}, 1.0), std::invalid_argument);
}

TEST(SegmentIndex, NearestCountEdgeCases) {
  const SegmentIndex index(RandomSegments(5, 10.0, 8));
  EXPECT_TRUE(index.Nearest({1.0, 1.0}, 0).empty());
  const auto all = index.Nearest({1.0, 1.0}, 50);
  ASSERT_EQ(all.size(), 5u);
  for (std::size_t i = 1; i < all.size(); ++i) EXPECT_LE(all[i - 1].first, all[i].first);
}

TEST(SegmentIndex, RejectsBadEntriesAndQueries) {
  std::vector<Entry> entries = RandomSegments(3, 10.0, 9);
  entries[1].segment.b = entries[1].segment.a;
  try {
    SegmentIndex index(entries);
    FAIL() << "a degenerate segment was accepted";
  } catch (const std::invalid_argument& e) {
    EXPECT_NE(std::string(e.what()).find("entry 1"), std::string::npos) << e.what();
  }
  entries[1].segment.b.x() = std::numeric_limits<double>::quiet_NaN();
  EXPECT_THROW(SegmentIndex{entries}, std::invalid_argument);

  const SegmentIndex index(RandomSegments(10, 10.0, 9));
  const double nan = std::numeric_limits<double>::quiet_NaN();
  EXPECT_THROW(index.Nearest({nan, 0.0}, 1), std::invalid_argument);
  EXPECT_THROW(index.RayCast({nan, 0.0}, {1.0, 0.0}, 1.0), std::invalid_argument);
  EXPECT_THROW(index.RayCast({0.0, 0.0}, {1.0, 0.0}, 0.0), std::invalid_argument);
  EXPECT_THROW(index.RayCast({0.0, 0.0}, {1.0, 0.0}, nan), std::invalid_argument);
  EXPECT_THROW(index.ConeCast(Cone2{{0.0, 0.0}, {1.0, 0.0}, kPi / 2.0, 4.0}), std::invalid_argument);
  EXPECT_THROW(index.ConeCast(Cone2{{0.0, 0.0}, {0.0, 0.0}, 0.1, 4.0}), std::invalid_argument);
  EXPECT_THROW(index.ConeCastAll(Cone2{{0.0, 0.0}, {1.0, 0.0}, 0.1, -4.0}), std::invalid_argument);
}

TEST(SegmentIndex, CopiesAnswerLikeTheOriginal) {
  const SegmentIndex original(RandomSegments(2000, 30.0, 10));
  const SegmentIndex copy = original;  // NOLINT(performance-unnecessary-copy-initialization)
  const Cone2 cone{{15.0, 15.0}, {0.3, 1.0}, Deg(7.5), 4.0};
  ExpectSameHit(copy.ConeCast(cone), original.ConeCast(cone), "copy");
  EXPECT_EQ(copy.Nearest({3.0, 3.0}, 4), original.Nearest({3.0, 3.0}, 4));
}

}  // namespace
}  // namespace rowloc::geometry
