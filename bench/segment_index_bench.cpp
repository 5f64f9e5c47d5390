// SegmentIndex query cost on 10^5-segment maps (docs/planar-geometry.md; target: an index
// query <= 2 us). Two maps: a vineyard (closed canopy outlines of 1 m segments, rows 2.5 m apart,
// queries from the corridors) and uniformly random segments of the same density.
// Run: segment_index_bench --benchmark_repetitions=5 --benchmark_report_aggregates_only=true
#include "rowloc/geometry/segment_index.hpp"

#include <benchmark/benchmark.h>

#include <cmath>
#include <numbers>
#include <random>
#include <vector>

namespace {

using rowloc::geometry::Cone2;
using rowloc::geometry::RowMap;
using rowloc::geometry::SegmentIndex;

constexpr double kHalfAperture = 7.5 * std::numbers::pi / 180.0;  // 15 deg full aperture
constexpr double kRange = 4.0;                                    // metres
constexpr std::size_t kQueries = 4096;

struct Query {
  Eigen::Vector2d origin;
  Eigen::Vector2d direction;
};

// 495 rows x 202 segments = 99 990 segments.
std::vector<SegmentIndex::Entry> VineyardEntries() {
  rowloc::geometry::SampleRowMapParams params;
  params.row_count = 495;
  params.row_length_m = 100.0;
  params.vertex_spacing_m = 1.0;
  return SegmentIndex::FromRowMap(rowloc::geometry::MakeSampleRowMap(params)).entries();
}

// 10^5 segments of 0.2-2 m in a 350 m square (the vineyard's density).
std::vector<SegmentIndex::Entry> RandomEntries() {
  std::mt19937_64 rng(42);
  std::uniform_real_distribution<double> centre(0.0, 350.0), length(0.2, 2.0), angle(-3.14159, 3.14159);
  std::vector<SegmentIndex::Entry> entries;
  for (std::size_t i = 0; i < 100000; ++i) {
    const Eigen::Vector2d c(centre(rng), centre(rng));
    const double a = angle(rng);
    const Eigen::Vector2d half = 0.5 * length(rng) * Eigen::Vector2d(std::cos(a), std::sin(a));
    entries.push_back({{c - half, c + half}, i, 0});
  }
  return entries;
}

// Vineyard queries: mid-corridor positions (the robot's), random headings.
std::vector<Query> VineyardQueries() {
  rowloc::geometry::SampleRowMapParams params;
  std::mt19937_64 rng(7);
  std::uniform_real_distribution<double> along(0.0, 100.0), angle(-3.14159, 3.14159);
  std::uniform_int_distribution<int> corridor(0, 493);
  const Eigen::Vector2d t(std::cos(params.heading_rad), std::sin(params.heading_rad));
  const Eigen::Vector2d n(-t.y(), t.x());
  std::vector<Query> queries;
  for (std::size_t i = 0; i < kQueries; ++i) {
    const double u = along(rng);
    const double xi = 2.0 * u / 100.0 - 1.0;
    const double offset = (corridor(rng) + 0.5) * params.row_spacing_m + params.bow_m * (1.0 - xi * xi);
    const double a = angle(rng);
    queries.push_back({u * t + offset * n, Eigen::Vector2d(std::cos(a), std::sin(a))});
  }
  return queries;
}

std::vector<Query> RandomQueries() {
  std::mt19937_64 rng(8);
  std::uniform_real_distribution<double> coord(0.0, 350.0), angle(-3.14159, 3.14159);
  std::vector<Query> queries;
  for (std::size_t i = 0; i < kQueries; ++i) {
    const double a = angle(rng);
    queries.push_back({{coord(rng), coord(rng)}, Eigen::Vector2d(std::cos(a), std::sin(a))});
  }
  return queries;
}

struct Fixture {
  std::vector<SegmentIndex::Entry> entries;
  SegmentIndex index;
  std::vector<Query> queries;
};

const Fixture& Vineyard() {
  static const Fixture f{VineyardEntries(), SegmentIndex(VineyardEntries()), VineyardQueries()};
  return f;
}
const Fixture& Random() {
  static const Fixture f{RandomEntries(), SegmentIndex(RandomEntries()), RandomQueries()};
  return f;
}

template <const Fixture& (*Map)()>
void BM_Build(benchmark::State& state) {
  const auto& entries = Map().entries;
  for (auto _ : state) {
    SegmentIndex index(entries);
    benchmark::DoNotOptimize(index);
  }
  state.counters["segments"] = static_cast<double>(entries.size());
}

template <const Fixture& (*Map)()>
void BM_Nearest1(benchmark::State& state) {
  const Fixture& f = Map();
  std::size_t i = 0;
  for (auto _ : state) {
    benchmark::DoNotOptimize(f.index.Nearest(f.queries[i++ % kQueries].origin, 1));
  }
}

template <const Fixture& (*Map)()>
void BM_RayCast(benchmark::State& state) {
  const Fixture& f = Map();
  std::size_t i = 0, hits = 0;
  for (auto _ : state) {
    const Query& q = f.queries[i++ % kQueries];
    const auto hit = f.index.RayCast(q.origin, q.direction, kRange);
    hits += hit.has_value();
    benchmark::DoNotOptimize(hit);
  }
  state.counters["hit_rate"] = static_cast<double>(hits) / static_cast<double>(std::max<std::size_t>(i, 1));
}

template <const Fixture& (*Map)()>
void BM_ConeCast(benchmark::State& state) {
  const Fixture& f = Map();
  std::size_t i = 0, hits = 0;
  for (auto _ : state) {
    const Query& q = f.queries[i++ % kQueries];
    const auto hit = f.index.ConeCast(Cone2{q.origin, q.direction, kHalfAperture, kRange});
    hits += hit.has_value();
    benchmark::DoNotOptimize(hit);
  }
  state.counters["hit_rate"] = static_cast<double>(hits) / static_cast<double>(std::max<std::size_t>(i, 1));
}

template <const Fixture& (*Map)()>
void BM_ConeCastAll(benchmark::State& state) {
  const Fixture& f = Map();
  std::size_t i = 0;
  for (auto _ : state) {
    const Query& q = f.queries[i++ % kQueries];
    benchmark::DoNotOptimize(f.index.ConeCastAll(Cone2{q.origin, q.direction, kHalfAperture, kRange}));
  }
}

BENCHMARK(BM_Build<Vineyard>)->Name("Build/Vineyard")->Unit(benchmark::kMillisecond);
BENCHMARK(BM_Build<Random>)->Name("Build/Random")->Unit(benchmark::kMillisecond);
BENCHMARK(BM_Nearest1<Vineyard>)->Name("Nearest1/Vineyard");
BENCHMARK(BM_Nearest1<Random>)->Name("Nearest1/Random");
BENCHMARK(BM_RayCast<Vineyard>)->Name("RayCast4m/Vineyard");
BENCHMARK(BM_RayCast<Random>)->Name("RayCast4m/Random");
BENCHMARK(BM_ConeCast<Vineyard>)->Name("ConeCast7.5deg4m/Vineyard");
BENCHMARK(BM_ConeCast<Random>)->Name("ConeCast7.5deg4m/Random");
BENCHMARK(BM_ConeCastAll<Vineyard>)->Name("ConeCastAll7.5deg4m/Vineyard");
BENCHMARK(BM_ConeCastAll<Random>)->Name("ConeCastAll7.5deg4m/Random");

}  // namespace
