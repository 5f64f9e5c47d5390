// Ellipsoid E(c, P) = { x : (x - c)^T P^-1 (x - c) <= 1 }, P symmetric positive definite (docs/ellipsoid.md).
//
// P is the "shape matrix": for a Gaussian N(c, S) the k-sigma ellipsoid is P = k^2 S
// (FromCovariance). With the Cholesky factor P = L L^T, E = { c + L u : |u| <= 1 } is the image of
// the unit ball, so that
//   (x - c)^T P^-1 (x - c) = |L^-1 (x - c)|^2                      (MahalanobisSquared)
//   log vol(E) = log V_n + sum_i log L_ii,  V_n = pi^(n/2) / Gamma(n/2 + 1)   (LogVolume)
// The projection of E onto a coordinate subspace is E(c_I, P_II), the principal submatrix: the
// support function h(y) = y^T c + sqrt(y^T P y) restricted to y supported on I only involves P_II.
// (The Schur complement P_II - P_IJ P_JJ^-1 P_JI is the slice of E through c: smaller, wrong as a
// bound; Donati 2021 writes the definition with P instead of P^-1: both are its errata, not copied.)
//
// The cuts (central, deep, parallel) live in ellipsoid_cuts.hpp; the math is in docs/ellipsoid.md.
#pragma once

#include <Eigen/Cholesky>
#include <Eigen/Core>

#include <array>
#include <cstddef>
#include <cmath>
#include <numbers>
#include <stdexcept>
#include <string>
#include <vector>

namespace rowloc::geometry {

template <int N>
class Ellipsoid;

namespace detail {

/// Builds ellipsoids from already validated parts (used by the cuts, which check the result with
/// their own Cholesky factorization, so that a cut does not pay for the constructor's checks twice).
struct EllipsoidAccess {
  template <int N>
  static Ellipsoid<N> FromFactoredUnchecked(const typename Ellipsoid<N>::Vector& center,
                                            const typename Ellipsoid<N>::Matrix& shape,
                                            const typename Ellipsoid<N>::Matrix& cholesky_lower) {
    return Ellipsoid<N>(typename Ellipsoid<N>::UncheckedTag{}, center, shape, cholesky_lower);
  }
};

/// log of the volume of the unit ball in R^n: V_0 = 1, V_1 = 2, V_n = (2 pi / n) V_(n-2).
/// (A recurrence rather than std::lgamma, which writes the global signgam on glibc.)
inline double LogUnitBallVolume(Eigen::Index n) {
  double log_volume = (n % 2 == 0) ? 0.0 : std::log(2.0);
  for (Eigen::Index k = (n % 2 == 0) ? 2 : 3; k <= n; k += 2) {
    log_volume += std::log(2.0 * std::numbers::pi / static_cast<double>(k));
  }
  return log_volume;
}

/// Lower Cholesky factor of a symmetric matrix if it is numerically positive definite
/// (LLT succeeds and every pivot is positive and finite); false otherwise.
template <typename MatrixType>
bool CholeskyIfPositiveDefinite(const MatrixType& symmetric, MatrixType* lower) {
  const Eigen::LLT<MatrixType> llt(symmetric);
  if (llt.info() != Eigen::Success) return false;
  *lower = llt.matrixL();
  const auto diagonal = lower->diagonal();
  return diagonal.allFinite() && (diagonal.array() > 0.0).all();
}

}  // namespace detail

/// An ellipsoid in R^N (N >= 1 fixed, or Eigen::Dynamic). Value type; always valid once built.
template <int N>
class Ellipsoid {
  static_assert(N == Eigen::Dynamic || N >= 1, "Ellipsoid<N>: N must be >= 1 or Eigen::Dynamic");

 public:
  using Vector = Eigen::Matrix<double, N, 1>;
  using Matrix = Eigen::Matrix<double, N, N>;

  /// E(center, shape). Throws std::invalid_argument if an entry is not finite, the sizes disagree
  /// (or are 0), shape is not symmetric (relative tolerance 1e-9 of its largest entry; it is then
  /// symmetrized) or not positive definite.
  Ellipsoid(const Vector& center, const Matrix& shape) : center_(center), shape_(shape) {
    ValidateInputs(center, shape);
    shape_ = 0.5 * (shape + shape.transpose());
    if (!detail::CholeskyIfPositiveDefinite(shape_, &cholesky_)) {
      throw std::invalid_argument("Ellipsoid: shape matrix is not positive definite");
    }
  }

  /// The k-sigma ellipsoid of N(mean, covariance): P = k_sigma^2 * covariance.
  /// Throws std::invalid_argument if k_sigma is not finite and > 0, or as the constructor.
  static Ellipsoid FromCovariance(const Vector& mean, const Matrix& covariance, double k_sigma) {
    if (!std::isfinite(k_sigma) || k_sigma <= 0.0) {
      throw std::invalid_argument("Ellipsoid::FromCovariance: k_sigma must be finite and > 0, got " +
                                  std::to_string(k_sigma));
    }
    return Ellipsoid(mean, (k_sigma * k_sigma) * covariance);
  }

  const Vector& center() const { return center_; }
  const Matrix& shape() const { return shape_; }
  /// Lower-triangular L with P = L L^T; E is the image of the unit ball under u -> c + L u.
  const Matrix& cholesky_factor() const { return cholesky_; }
  Eigen::Index dimension() const { return center_.size(); }

  /// (x - c)^T P^-1 (x - c). Throws std::invalid_argument if x has the wrong size.
  double MahalanobisSquared(const Vector& x) const {
    RequireSize(x.size(), "MahalanobisSquared");
    const Vector whitened = cholesky_.template triangularView<Eigen::Lower>().solve(x - center_);
    return whitened.squaredNorm();
  }

  /// MahalanobisSquared(x) <= 1 + relative_tolerance (false for a non-finite x).
  bool Contains(const Vector& x, double relative_tolerance = 1e-9) const {
    return MahalanobisSquared(x) <= 1.0 + relative_tolerance;
  }

  /// Natural log of the volume (the unit-ball volume included), in log(m^n) for metric coordinates.
  double LogVolume() const {
    return detail::LogUnitBallVolume(dimension()) + cholesky_.diagonal().array().log().sum();
  }

  /// Projection onto the listed coordinates (in that order): E(c_I, P_II), the principal
  /// submatrix. Throws std::invalid_argument for an empty list, an index outside [0, n) or a
  /// repeated index.
  Ellipsoid<Eigen::Dynamic> Project(const std::vector<int>& coordinates) const {
    ValidateCoordinates(coordinates);
    return Ellipsoid<Eigen::Dynamic>(center_(coordinates), shape_(coordinates, coordinates));
  }
  /// Fixed-size projection, e.g. Project(std::array<int, 2>{0, 1}) or Project<2>({0, 1}).
  /// (M is std::size_t, the type std::array uses, so that it can be deduced.)
  template <std::size_t M>
  Ellipsoid<static_cast<int>(M)> Project(const std::array<int, M>& coordinates) const {
    static_assert(M >= 1, "Project<M>: M must be >= 1");
    static_assert(N == Eigen::Dynamic || static_cast<int>(M) <= N, "Project<M>: more coordinates than N");
    ValidateCoordinates(coordinates);
    return Ellipsoid<static_cast<int>(M)>(center_(coordinates), shape_(coordinates, coordinates));
  }

 private:
  friend struct detail::EllipsoidAccess;
  struct UncheckedTag {};

  Ellipsoid(UncheckedTag, const Vector& center, const Matrix& shape, const Matrix& cholesky_lower)
      : center_(center), shape_(shape), cholesky_(cholesky_lower) {}

  static void ValidateInputs(const Vector& center, const Matrix& shape) {
    if (center.size() < 1 || shape.rows() != center.size() || shape.cols() != center.size()) {
      throw std::invalid_argument("Ellipsoid: center has size " + std::to_string(center.size()) +
                                  " but shape is " + std::to_string(shape.rows()) + "x" +
                                  std::to_string(shape.cols()) + " (need n x n, n >= 1)");
    }
    if (!center.allFinite() || !shape.allFinite()) {
      throw std::invalid_argument("Ellipsoid: center or shape has a non-finite entry");
    }
    const double largest = shape.cwiseAbs().maxCoeff();
    const double asymmetry = (shape - shape.transpose()).cwiseAbs().maxCoeff();
    if (asymmetry > 1e-9 * largest) {
      throw std::invalid_argument("Ellipsoid: shape matrix is not symmetric (max |P - P^T| = " +
                                  std::to_string(asymmetry) + ")");
    }
  }

  void RequireSize(Eigen::Index size, const char* what) const {
    if (size != dimension()) {
      throw std::invalid_argument(std::string("Ellipsoid::") + what + ": point has size " +
                                  std::to_string(size) + ", ellipsoid has dimension " +
                                  std::to_string(dimension()));
    }
  }

  template <typename Indices>
  void ValidateCoordinates(const Indices& coordinates) const {
    if (coordinates.empty()) throw std::invalid_argument("Ellipsoid::Project: no coordinates given");
    for (std::size_t i = 0; i < coordinates.size(); ++i) {
      if (coordinates[i] < 0 || coordinates[i] >= dimension()) {
        throw std::invalid_argument("Ellipsoid::Project: coordinate " + std::to_string(coordinates[i]) +
                                    " outside [0, " + std::to_string(dimension()) + ")");
      }
      for (std::size_t j = 0; j < i; ++j) {
        if (coordinates[j] == coordinates[i]) {
          throw std::invalid_argument("Ellipsoid::Project: coordinate " +
                                      std::to_string(coordinates[i]) + " repeated");
        }
      }
    }
  }

  Vector center_;
  Matrix shape_;
  Matrix cholesky_;
};

}  // namespace rowloc::geometry
