// Plain loop kernels over the contiguous columns of column-major matrices, shared by the process
// model and the Kalman update (internal header). For the filter's sizes (n ~ 10-30) Eigen's
// expression set-up per column costs more than the arithmetic; these loops vectorize.
//
// ROWLOC_VECTOR_CLONES: put before a kernel (loops over raw pointers; Eigen only for coefficient
// access) to build it twice, for baseline x86-64 (SSE2, 2 doubles per instruction) and for AVX2
// (4), the copy chosen once at load time by the CPU (GCC target_clones, an ifunc). Only code
// inlined into the kernel gets AVX2; out-of-line functions it calls keep the baseline target.
// Eigen's own code is not affected: its vector width is fixed at compile time, and the project
// never builds with -march
// (cmake/RowlocOptions.cmake). AVX2 does not bring FMA, and the project builds with
// -ffp-contract=off, so both copies round every operation alike: results (and replays) do not
// depend on the machine. Elsewhere (other architectures, other compilers) the macro is empty; so it
// is with clang (the fuzz preset), whose target_clones (clang 14) takes neither function templates
// nor member functions defined out of their class.
#pragma once

#include <Eigen/Core>

#include <cstring>

#if defined(__x86_64__) && defined(__GNUC__) && !defined(__clang__) && defined(__has_attribute)
#if __has_attribute(target_clones)
#define ROWLOC_VECTOR_CLONES __attribute__((target_clones("avx2", "default")))
#endif
#endif
#ifndef ROWLOC_VECTOR_CLONES
#define ROWLOC_VECTOR_CLONES
#endif

// ROWLOC_INLINE: these helpers are meant to be inlined into the cloned kernels (a call would run the
// baseline copy, and cost more than the loop at these sizes), whatever the inliner's size limits.
#if defined(__GNUC__)
#define ROWLOC_INLINE [[gnu::always_inline]] inline
#else
#define ROWLOC_INLINE inline
#endif

// Double4 below: GCC (and clang) report -Wpsabi at the end of the translation unit, so it is
// silenced for the rest of each (internal) file that includes this header, not between a push and
// a pop.
#if defined(__GNUC__)
#pragma GCC diagnostic ignored "-Wpsabi"
#endif

namespace rowloc::localization::detail {

/// Most columns CombineColumns takes in one pass.
inline constexpr int kMaxCombinedColumns = 8;

/// Four doubles as one value (GCC/Clang vector extension): one AVX register in the avx2 clone, two
/// SSE2 halves in the baseline one. Its operations are lane-wise IEEE operations, so each lane
/// rounds exactly like the scalar expression: a kernel gives the same bits with it as without.
/// GCC warns (-Wpsabi) that passing it by value outside AVX code has another ABI than inside; these
/// helpers and the kernels' lambdas are inline functions of one translation unit each, never called
/// across a boundary compiled otherwise, so the warning is silenced (top of this header).
using Double4 = double __attribute__((vector_size(4 * sizeof(double))));
inline constexpr Eigen::Index kLanes = 4;
ROWLOC_INLINE Double4 Load4(const double* p) {
  Double4 v;
  std::memcpy(&v, p, sizeof v);  // an unaligned load
  return v;
}
ROWLOC_INLINE void Store4(double* p, const Double4& v) { std::memcpy(p, &v, sizeof v); }
ROWLOC_INLINE Double4 Broadcast4(double x) { return Double4{x, x, x, x}; }

/// Applies a column operation to the rows [0, n), n >= kLanes, four at a time without a scalar
/// remainder: block(r) gives the new rows [r, r + 4) from the old ones; the last block starts at
/// n - 4 and may overlap the one before it, so it is computed from the old values before any row is
/// written (an overlapped row gets the same value twice). For n ~ 10-30 the remainder loops of a
/// compiled vector loop cost about a third of the instructions. target is not restrict-qualified:
/// block reads the same rows through the caller's pointer, and the tail must be read first.
template <class Block>
ROWLOC_INLINE void ForEachRowBlock(Eigen::Index n, double* target, Block&& block) {
  const Eigen::Index last = n - kLanes;
  const Double4 tail = block(last);
  for (Eigen::Index r = 0; r < last; r += kLanes) Store4(target + r, block(r));
  Store4(target + last, tail);
}

/// target[r] = (Accumulate ? target[r] : first product) + scales[e] sources[e][r] for e in order,
/// r < n: one pass over the rows, each entry summed in a register (Count is a compile-time
/// constant, so the sum over e unrolls and the loop over the rows vectorizes). The sources must not
/// overlap target.
template <int Count, bool Accumulate>
ROWLOC_INLINE void CombineColumnsOf(const double* const* sources, const double* scales, Eigen::Index n,
                                    double* __restrict__ target) {
  if (n < kLanes) {
    for (Eigen::Index r = 0; r < n; ++r) {
      double sum = Accumulate ? target[r] + scales[0] * sources[0][r] : scales[0] * sources[0][r];
      for (int e = 1; e < Count; ++e) sum += scales[e] * sources[e][r];
      target[r] = sum;
    }
    return;
  }
  Double4 factor[Count];
  for (int e = 0; e < Count; ++e) factor[e] = Broadcast4(scales[e]);
  ForEachRowBlock(n, target, [&](Eigen::Index r) {  // the same operations as the scalar loop, lane-wise
    const Double4 first = factor[0] * Load4(sources[0] + r);
    Double4 sum = Accumulate ? Load4(target + r) + first : first;
    for (int e = 1; e < Count; ++e) sum += factor[e] * Load4(sources[e] + r);
    return sum;
  });
}

/// CombineColumnsOf for a run-time count, 1 <= count <= kMaxCombinedColumns.
template <bool Accumulate>
ROWLOC_INLINE void CombineColumns(const double* const* sources, const double* scales, int count, Eigen::Index n,
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
