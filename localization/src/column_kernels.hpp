// Plain loop kernels over the contiguous columns of column-major matrices, shared by the process
// model and the Kalman update (internal header). For the filter's sizes (n ~ 10-30) Eigen's
// expression set-up per column costs more than the arithmetic; these loops vectorize.
//
// ROWLOC_VECTOR_CLONES: put before a kernel (loops over raw pointers; Eigen only for coefficient
// access) to build it twice, for baseline x86-64 (SSE2, 2 doubles per instruction) and for AVX2
// (4), the copy chosen once at load time by the CPU (GCC/Clang target_clones, an ifunc). Only code
// inlined into the kernel gets AVX2; out-of-line functions it calls keep the baseline target.
// Eigen's own code is not affected: its vector width is fixed at compile time, and the project
// never builds with -march
// (cmake/RowlocOptions.cmake). AVX2 does not bring FMA, and the project builds with
// -ffp-contract=off, so both copies round every operation alike: results (and replays) do not
// depend on the machine. Elsewhere (other architectures, other compilers) the macro is empty.
#pragma once

#include <Eigen/Core>

#if defined(__x86_64__) && defined(__GNUC__) && defined(__has_attribute)
#if __has_attribute(target_clones)
#define ROWLOC_VECTOR_CLONES __attribute__((target_clones("avx2", "default")))
#endif
#endif
#ifndef ROWLOC_VECTOR_CLONES
#define ROWLOC_VECTOR_CLONES
#endif

namespace rowloc::localization::detail {

/// Most columns CombineColumns takes in one pass.
inline constexpr int kMaxCombinedColumns = 8;

/// target[r] = (Accumulate ? target[r] : first product) + scales[e] sources[e][r] for e in order,
/// r < n: one pass over the rows, each entry summed in a register (Count is a compile-time
/// constant, so the sum over e unrolls and the loop over the rows vectorizes). The sources must not
/// overlap target.
template <int Count, bool Accumulate>
inline void CombineColumnsOf(const double* const* sources, const double* scales, Eigen::Index n,
                             double* __restrict__ target) {
  for (Eigen::Index r = 0; r < n; ++r) {
    double sum = Accumulate ? target[r] + scales[0] * sources[0][r] : scales[0] * sources[0][r];
    for (int e = 1; e < Count; ++e) sum += scales[e] * sources[e][r];
    target[r] = sum;
  }
}

/// CombineColumnsOf for a run-time count, 1 <= count <= kMaxCombinedColumns.
template <bool Accumulate>
inline void CombineColumns(const double* const* sources, const double* scales, int count, Eigen::Index n,
                           double* __restrict__ target) {
  switch (count) {
    case 1: CombineColumnsOf<1, Accumulate>(sources, scales, n, target); break;
    case 2: CombineColumnsOf<2, Accumulate>(sources, scales, n, target); break;
    case 3: CombineColumnsOf<3, Accumulate>(sources, scales, n, target); break;
    case 4: CombineColumnsOf<4, Accumulate>(sources, scales, n, target); break;
    case 5: CombineColumnsOf<5, Accumulate>(sources, scales, n, target); break;
    case 6: CombineColumnsOf<6, Accumulate>(sources, scales, n, target); break;
    case 7: CombineColumnsOf<7, Accumulate>(sources, scales, n, target); break;
    default: CombineColumnsOf<kMaxCombinedColumns, Accumulate>(sources, scales, n, target); break;
  }
}

}  // namespace rowloc::localization::detail
