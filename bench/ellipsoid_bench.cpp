// Cost of the ellipsoid calculus (docs/ellipsoid.md): parallel cuts in 2-D (the map-aided range update) and in
// 12-D (the full AgriMaRo state), fixed and dynamic size, and the 12 -> 2 projection.
// Target: a 2-D parallel cut <= 100 ns. Run the Release build with
//   ellipsoid_bench --benchmark_repetitions=5 --benchmark_report_aggregates_only=true
#include "rowloc/geometry/ellipsoid.hpp"
#include "rowloc/geometry/ellipsoid_cuts.hpp"

#include <benchmark/benchmark.h>

#include <array>
#include <cmath>
#include <vector>

namespace {

using rowloc::geometry::CutStatus;
using rowloc::geometry::Ellipsoid;
using rowloc::geometry::ParallelCut;

/// A correlated SPD matrix with a fixed pattern: A A^T + I, A(i, j) = sin(i + 2 j).
template <int N>
Ellipsoid<N> CorrelatedEllipsoid(int n) {
  typename Ellipsoid<N>::Matrix a(n, n);
  typename Ellipsoid<N>::Vector center(n);
  for (int i = 0; i < n; ++i) {
    center(i) = 0.1 * i;
    for (int j = 0; j < n; ++j) a(i, j) = std::sin(i + 2.0 * j);
  }
  return Ellipsoid<N>(center, a * a.transpose() + decltype(a)::Identity(n, n));
}

/// The slab with depths (alpha, alpha_hat) for E and g, as (beta_lo, beta_hi).
template <int N>
std::array<double, 2> Slab(const Ellipsoid<N>& e, const typename Ellipsoid<N>::Vector& g, double alpha,
                           double alpha_hat) {
  const double s = std::sqrt(g.dot(e.shape() * g));
  const double gc = g.dot(e.center());
  return {gc + alpha_hat * s, gc - alpha * s};
}

template <int N>
void RunParallelCut(benchmark::State& state, int n, double alpha, double alpha_hat) {
  const Ellipsoid<N> e = CorrelatedEllipsoid<N>(n);
  typename Ellipsoid<N>::Vector g(n);
  for (int i = 0; i < n; ++i) g(i) = 1.0 + 0.25 * i;
  const auto [beta_lo, beta_hi] = Slab(e, g, alpha, alpha_hat);
  if (ParallelCut(e, g, beta_lo, beta_hi).status != CutStatus::kUpdated) {
    state.SkipWithError("benchmark cut does not update");
    return;
  }
  for (auto _ : state) {
    auto result = ParallelCut(e, g, beta_lo, beta_hi);
    benchmark::DoNotOptimize(result);
  }
}

void BM_ParallelCut2dCentred(benchmark::State& state) { RunParallelCut<2>(state, 2, -0.3, -0.3); }
void BM_ParallelCut2dOffCentre(benchmark::State& state) { RunParallelCut<2>(state, 2, 0.2, -0.6); }
void BM_ParallelCut12dFixed(benchmark::State& state) { RunParallelCut<12>(state, 12, 0.05, -0.2); }
void BM_ParallelCut12dDynamic(benchmark::State& state) { RunParallelCut<Eigen::Dynamic>(state, 12, 0.05, -0.2); }

void BM_Project12To2Fixed(benchmark::State& state) {
  const Ellipsoid<12> e = CorrelatedEllipsoid<12>(12);
  for (auto _ : state) {
    auto position = e.Project(std::array<int, 2>{0, 1});
    benchmark::DoNotOptimize(position);
  }
}

void BM_Project12To2Dynamic(benchmark::State& state) {
  const Ellipsoid<12> e = CorrelatedEllipsoid<12>(12);
  const std::vector<int> coordinates{0, 1};
  for (auto _ : state) {
    auto position = e.Project(coordinates);
    benchmark::DoNotOptimize(position);
  }
}

}  // namespace

BENCHMARK(BM_ParallelCut2dCentred);
BENCHMARK(BM_ParallelCut2dOffCentre);
BENCHMARK(BM_ParallelCut12dFixed);
BENCHMARK(BM_ParallelCut12dDynamic);
BENCHMARK(BM_Project12To2Fixed);
BENCHMARK(BM_Project12To2Dynamic);
