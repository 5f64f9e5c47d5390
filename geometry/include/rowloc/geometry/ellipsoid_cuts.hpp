// Minimum-volume ellipsoids containing E ∩ {cut}: central, deep and parallel (slab) cuts
// (Donati 2021 ch. 3, eqs. (3.2)-(3.12), after Liao & Todd 1993 for the parallel cut).
//
// For a cut with normal g let s = sqrt(g^T P g) and w = P g / s. Every update has the form
//   c+ = c - tau w,     P+ = delta (P - sigma w w^T) = delta (P - sigma (P g)(P g)^T / s^2).
// NOTE: the shape update divides (P g)(P g)^T by s^2 = g^T P g. Donati 2021, eqs. (3.3) and (3.12),
// divides by s = sqrt(g^T P g): that is an erratum (not copied) and gives a wrong, non-containing
// ellipsoid whenever g^T P g != 1.
//
// Depths, in units of E along g: upper plane g^T x <= beta_hi: alpha = (g^T c - beta_hi) / s;
// lower plane g^T x >= beta_lo: alpha_hat = (beta_lo - g^T c) / s. In the normalized frame
// (E -> unit ball, g -> e1) the kept region is { |u| <= 1, alpha_hat <= u1 <= -alpha }.
//   - depth >= 1 on either side: the cut leaves no interior point of E -> kEmpty (never clipped:
//     clipping alpha > 1 to 1, as Donati 2021 does, would return a single point).
//   - depth < -1: that plane does not touch E -> treated as -1 (no constraint).
//   - alpha * alpha_hat >= 1/n (both negative): E itself is the minimum -> kUnchanged.
//   - otherwise (n >= 2), with rho = sqrt(4 (1 - a^2)(1 - ah^2) + n^2 (ah^2 - a^2)^2):
//       sigma = (n + 2 [1 - n^2 (a + ah)^2 / 4] / (1 - a ah + rho / 2)) / (n + 1)
//       tau   = sigma (a - ah) / 2
//       delta = n^2 / (n^2 - 1) (1 - (a^2 + ah^2 - rho / n) / 2)
//     The sigma above is the published (n + 2 (1 - a ah - rho/2) / (a - ah)^2) / (n + 1) rationalized
//     with (1 - a ah)^2 - rho^2 / 4 = (a - ah)^2 [1 - n^2 (a + ah)^2 / 4]: the same number, without
//     the 0/0 at a == ah (a slab centred on c); at a = ah = -t it is (1 - n t^2) / (1 - t^2).
//   - n = 1: delta = n^2 / (n^2 - 1) is undefined; the exact answer is the interval
//     intersection: tau = (a - ah) / 2, sigma = 0, delta = (a + ah)^2 / 4.
// The deep cut is the parallel cut with alpha_hat = -1; the central cut is the deep cut with
// alpha = 0 (tau = 1/(n+1), sigma = 2/(n+1), delta = n^2/(n^2-1)). Derivations and the tests that
// verify all this against a brute-force minimum-volume search: docs/ellipsoid.md.
#pragma once

#include "rowloc/geometry/ellipsoid.hpp"

#include <Eigen/Core>

#include <algorithm>
#include <cmath>
#include <limits>
#include <optional>

namespace rowloc::geometry {

enum class CutStatus {
  kUpdated,       ///< E+ is the minimum-volume ellipsoid of E ∩ cut (strictly smaller than E)
  kUnchanged,     ///< the cut removes too little: E itself is the minimum-volume ellipsoid
  kEmpty,         ///< E ∩ cut has no interior point (the cut misses E, or only touches it)
  kInvalidInput,  ///< zero / non-finite normal, non-finite offset, dimension mismatch, a slab of
                  ///< zero width, or a slab so thin that P+ is not numerically positive definite
};
const char* ToString(CutStatus status);

/// tau (step), sigma (dilation) and delta (expansion) of a cut with effective depths
/// alpha, alpha_hat in [-1, 1), alpha + alpha_hat < 0, alpha * alpha_hat < 1/n, n >= 1 (formulas in
/// the header comment). Outside that domain every field is NaN.
struct CutParameters {
  double tau;
  double sigma;
  double delta;
  /// 1 - sigma without cancellation (thin slabs: ~ (n - 1) h^2 for a centred slab of half-width h;
  /// formula in docs/ellipsoid.md, "Thin slabs").
  double one_minus_sigma;
};
CutParameters ParallelCutParameters(double alpha, double alpha_hat, Eigen::Index n);

template <int N>
struct CutResult {
  CutStatus status;
  Ellipsoid<N> ellipsoid;  ///< the updated ellipsoid; the input one unchanged when status != kUpdated
  double alpha;            ///< depth of the upper cut as given (before the clamp to -1); NaN if n/a
  double alpha_hat;        ///< depth of the lower cut as given (before the clamp to -1); NaN if n/a
  /// kUpdated only: the slab is so thin that double precision cannot hold the minimum-volume
  /// ellipsoid; E+ was widened along the cut normal (by more than 0.1 % of its thin axis) so that it
  /// still contains E ∩ cut. Always false for central and deep cuts.
  bool precision_limited = false;
};

namespace detail {

inline constexpr double kNotApplicable = std::numeric_limits<double>::quiet_NaN();

/// A cut normal scaled by 1/|g|_inf (so that s neither underflows nor overflows), with s and w.
template <int N>
struct CutFrame {
  typename Ellipsoid<N>::Vector w;  ///< P g' / s: the semi-axis of E conjugate to the cut planes
  double s;                         ///< sqrt(g'^T P g') > 0
  double g_dot_center;              ///< g'^T c
  double scale;                     ///< |g|_inf; g' = g / scale, offsets are divided by it too
  double g_norm;                    ///< |g'|_2, in [1, sqrt(n)]
};

/// nullopt for a normal of the wrong size, non-finite or zero.
template <int N>
std::optional<CutFrame<N>> MakeCutFrame(const Ellipsoid<N>& e, const typename Ellipsoid<N>::Vector& g) {
  if (g.size() != e.dimension() || !g.allFinite()) return std::nullopt;
  const double scale = g.cwiseAbs().maxCoeff();
  if (!(scale > 0.0)) return std::nullopt;
  const typename Ellipsoid<N>::Vector g_scaled = g / scale;
  typename Ellipsoid<N>::Vector p_g = e.shape() * g_scaled;
  const double s = std::sqrt(g_scaled.dot(p_g));
  if (!(s > 0.0) || !std::isfinite(s)) return std::nullopt;
  p_g /= s;
  return CutFrame<N>{p_g, s, g_scaled.dot(e.center()), scale, g_scaled.norm()};
}

/// Relative rounding of a depth computed as (g'^T c - beta') / s: a depth this close to 1 is a
/// plane tangent to E within rounding (kEmpty), not a cap of E of volume 1e-24.
template <int N>
double DepthRounding(const Ellipsoid<N>& e, const CutFrame<N>& frame, double beta_scaled) {
  constexpr double kEps = std::numeric_limits<double>::epsilon();
  const double n = static_cast<double>(e.dimension());
  return 16.0 * kEps * (1.0 + (n * frame.g_norm * e.center().norm() + std::abs(beta_scaled)) / frame.s);
}

/// 1 - sigma below which the shape update is formed as delta ((P - w w^T) + (1 - sigma) w w^T)
/// with a rounding margin (docs/ellipsoid.md, "Thin slabs"); above it, delta (P - sigma w w^T).
inline constexpr double kThinSlabOneMinusSigma = 1e-2;

/// The rounding margin added to 1 - sigma for a thin slab: the absolute rounding of P - w w^T and
/// of the Cholesky factor along g (~ n eps |P|_F |g|^2 / s^2), and of a point's coordinate along g
/// (eps (|c| + sqrt|P|_F) |g| / s) against the thin axis sqrt(1 - sigma).
template <int N>
double ThinSlabMargin(const Ellipsoid<N>& e, const CutFrame<N>& frame, double one_minus_sigma) {
  constexpr double kEps = std::numeric_limits<double>::epsilon();
  const double n = static_cast<double>(e.dimension());
  const double p_norm = e.shape().norm();  // Frobenius
  const double g_norm2 = frame.g_norm * frame.g_norm;
  const double kappa = p_norm * g_norm2 / (frame.s * frame.s);
  const double point_rounding = kEps * (e.center().norm() + std::sqrt(p_norm)) * std::sqrt(g_norm2) / frame.s;
  return 16.0 * n * kEps * kappa + 8.0 * n * point_rounding * std::sqrt(one_minus_sigma) +
         64.0 * point_rounding * point_rounding;
}

/// The common update for depths alpha (upper plane) and alpha_hat (lower plane); the reported
/// depths are returned as given. depth_rounding: DepthRounding of the planes (0 for a central cut).
template <int N>
CutResult<N> ApplyCut(const Ellipsoid<N>& e, const CutFrame<N>& frame, double alpha, double alpha_hat,
                      double reported_alpha, double reported_alpha_hat, double depth_rounding) {
  const auto keep = [&](CutStatus status) {
    return CutResult<N>{status, e, reported_alpha, reported_alpha_hat};
  };
  if (alpha >= 1.0 - depth_rounding || alpha_hat >= 1.0 - depth_rounding) return keep(CutStatus::kEmpty);
  const double a = std::max(alpha, -1.0);
  const double a_hat = std::max(alpha_hat, -1.0);
  if (a + a_hat > 0.0) return keep(CutStatus::kEmpty);
  if (a + a_hat == 0.0) return keep(CutStatus::kInvalidInput);  // zero-width slab: a flat disc
  if (a * a_hat >= 1.0 / static_cast<double>(e.dimension())) return keep(CutStatus::kUnchanged);

  const CutParameters p = ParallelCutParameters(a, a_hat, e.dimension());
  using Vector = typename Ellipsoid<N>::Vector;
  using Matrix = typename Ellipsoid<N>::Matrix;
  const Vector center = e.center() - p.tau * frame.w;
  const Matrix w_wt = frame.w * frame.w.transpose();
  // Divided by s^2 (w w^T = (P g)(P g)^T / s^2), not by s as in Donati 2021 eq. (3.12), an erratum.
  Matrix shape_unsymmetric;
  bool precision_limited = false;
  if (e.dimension() > 1 && p.one_minus_sigma < kThinSlabOneMinusSigma) {
    // Thin slab: P - sigma w w^T cancels to ~eps |P| along g, which is no longer small against the
    // thin axis; (P - w w^T) + (1 - sigma) w w^T with the margin keeps E ∩ cut inside E+.
    const double margin = ThinSlabMargin(e, frame, p.one_minus_sigma);
    precision_limited = margin > 1e-3 * p.one_minus_sigma;
    shape_unsymmetric = p.delta * ((e.shape() - w_wt) + (p.one_minus_sigma + margin) * w_wt);
  } else {
    shape_unsymmetric = p.delta * (e.shape() - p.sigma * w_wt);
  }
  const Matrix shape = 0.5 * (shape_unsymmetric + shape_unsymmetric.transpose());
  Matrix cholesky;
  if (!center.allFinite() || !detail::CholeskyIfPositiveDefinite(shape, &cholesky)) {
    return keep(CutStatus::kInvalidInput);  // not expected: the margin keeps P+ positive definite
  }
  CutResult<N> result{CutStatus::kUpdated, EllipsoidAccess::FromFactoredUnchecked<N>(center, shape, cholesky),
                      reported_alpha, reported_alpha_hat};
  result.precision_limited = precision_limited;
  return result;
}

}  // namespace detail

/// Minimum-volume ellipsoid of E ∩ { x : g^T (x - c) <= 0 }.
template <int N>
CutResult<N> CentralCut(const Ellipsoid<N>& e, const typename Ellipsoid<N>::Vector& g) {
  const auto frame = detail::MakeCutFrame(e, g);
  if (!frame) {
    return CutResult<N>{CutStatus::kInvalidInput, e, detail::kNotApplicable, detail::kNotApplicable};
  }
  return detail::ApplyCut(e, *frame, 0.0, -1.0, 0.0, detail::kNotApplicable, 0.0);
}

/// Minimum-volume ellipsoid of E ∩ { x : g^T x <= beta }.
template <int N>
CutResult<N> DeepCut(const Ellipsoid<N>& e, const typename Ellipsoid<N>::Vector& g, double beta) {
  const auto frame = detail::MakeCutFrame(e, g);
  if (!frame || !std::isfinite(beta)) {
    return CutResult<N>{CutStatus::kInvalidInput, e, detail::kNotApplicable, detail::kNotApplicable};
  }
  const double alpha = (frame->g_dot_center - beta / frame->scale) / frame->s;
  return detail::ApplyCut(e, *frame, alpha, -1.0, alpha, detail::kNotApplicable,
                          detail::DepthRounding(e, *frame, beta / frame->scale));
}

/// Minimum-volume ellipsoid of E ∩ { x : beta_lo <= g^T x <= beta_hi } (a slab).
template <int N>
CutResult<N> ParallelCut(const Ellipsoid<N>& e, const typename Ellipsoid<N>::Vector& g, double beta_lo,
                         double beta_hi) {
  const auto frame = detail::MakeCutFrame(e, g);
  if (!frame || !std::isfinite(beta_lo) || !std::isfinite(beta_hi)) {
    return CutResult<N>{CutStatus::kInvalidInput, e, detail::kNotApplicable, detail::kNotApplicable};
  }
  const double alpha = (frame->g_dot_center - beta_hi / frame->scale) / frame->s;
  const double alpha_hat = (beta_lo / frame->scale - frame->g_dot_center) / frame->s;
  if (beta_lo > beta_hi) return CutResult<N>{CutStatus::kEmpty, e, alpha, alpha_hat};
  if (beta_lo == beta_hi && alpha < 1.0 && alpha_hat < 1.0) {
    return CutResult<N>{CutStatus::kInvalidInput, e, alpha, alpha_hat};  // zero width
  }
  const double depth_rounding = detail::DepthRounding(
      e, *frame, std::max(std::abs(beta_lo), std::abs(beta_hi)) / frame->scale);
  return detail::ApplyCut(e, *frame, alpha, alpha_hat, alpha, alpha_hat, depth_rounding);
}

}  // namespace rowloc::geometry
