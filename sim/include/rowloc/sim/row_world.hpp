// RowWorld: the exact ground truth of a simulated vineyard (issue 3, "World"): parallel
// rows on a terrain, their canopy as an exact 3-D solid, its outline at any height above the
// terrain, and the true 2-D row map. Documented in docs/simulation-world.md.
//
// Math (all lengths in metres, local ENU frame of `origin`):
// - Reference curve c(s), s in [0, L] its arc length ("station"), starting at (0, 0) with heading
//   theta0 (from +East, counter-clockwise) and piecewise-constant curvature kappa(s):
//   straight: 0; arc: 1/R on [0, L]; S-curve: 1/R on [0, L/2), -1/R on [L/2, L] (R signed,
//   > 0 turns left). Each piece is integrated in closed form (circle or line), so c is exact.
//   n(s) = left unit normal of c.
// - Row k (0-based) is the offset curve at d_k = k * spacing to the left: centre
//   m_k(s) = c(s) + d_k n(s) (concentric arcs for curved rows: radius R - d_k).
//   Every row property is a function of the shared station s (for row k the arc length of its
//   centre is (1 - kappa d_k) ds).
// - Canopy of row k at station s: the horizontal segment from m_k - w_R n to m_k + w_L n, for
//   heights h above the terrain in the band [b_k(s), t_k(s)], except inside gaps (open
//   intervals g0 < s < g1). The half-widths are w_{L,R}(s) = w0 + a_w v_k(s) + rho_{k,L|R}(s):
//   v_k a smooth variation (mean of two sinusoids, wavelengths lambda_w and 1.618 lambda_w,
//   seeded phases, |v_k| <= 1) and rho the leaf-scale roughness (mean of three sinusoids,
//   wavelengths seeded in [lambda_min, lambda_max], |rho| <= A_rho; one per side). The band is
//   b_k = b0 + a_h v'_k(s), t_k = t0 + a_h v''_k(s) with their own seeded phases.
//   The canopy faces are vertical: at a given height the outline does not depend on h, only which
//   stations carry canopy (band and gaps) does.
// - Seeds: row k's phases come from std::mt19937_64 seeded by seed + (k + 1) * 0x9E3779B97F4A7C15,
//   the terrain from the seed itself; draws use the raw engine output (platform independent).
// - Validation guarantees that the outlines do not fold (|kappa| (max |d_k| + w_max) < 0.9) and
//   that neighbouring canopies do not touch (w_max < spacing / 2).
#pragma once

#include "rowloc/geometry/row_map.hpp"
#include "rowloc/sim/terrain_surface.hpp"

#include <Eigen/Core>

#include <cstdint>
#include <filesystem>
#include <optional>
#include <string>
#include <string_view>
#include <vector>

namespace rowloc::sim {

enum class RowCurvature { kStraight, kArc, kSCurve };

/// An interval of stations without canopy in one row.
struct RowGap {
  int row = 0;          ///< 0-based row index
  double start_m = 0;   ///< station where the gap begins, in [0, length)
  double end_m = 0;     ///< station where it ends, in (start, length]
  bool operator==(const RowGap&) const = default;
};

struct CanopyParams {
  double half_width_m = 0.25;              ///< w0, mean half-width of the canopy
  double half_width_variation_m = 0.03;    ///< a_w >= 0
  double width_wavelength_m = 8.0;         ///< lambda_w > 0
  double bottom_m = 0.5;                   ///< b0, mean bottom of the canopy above the terrain
  double top_m = 1.8;                      ///< t0, mean top
  double height_variation_m = 0.1;         ///< a_h >= 0
  double height_wavelength_m = 12.0;       ///< wavelength of the band variation, > 0
  double roughness_amplitude_m = 0.0;      ///< A_rho >= 0 (0: smooth canopy, as in Donati 2021)
  double roughness_min_wavelength_m = 0.1; ///< lambda_min > 0
  double roughness_max_wavelength_m = 0.3; ///< lambda_max >= lambda_min
  bool operator==(const CanopyParams&) const = default;
};

struct RowWorldParams {
  std::string name = "vineyard-002";
  std::uint64_t seed = 2;
  geometry::GeoOrigin origin{45.0703, 7.6869, 240.0};
  int row_count = 6;               ///< in [1, 1000]
  double row_spacing_m = 2.5;      ///< distance between neighbouring centre lines, > 0
  double row_length_m = 50.0;      ///< L, in (0, 10000]
  double heading_rad = 0.0;        ///< theta0, finite
  RowCurvature curvature = RowCurvature::kStraight;
  double curvature_radius_m = 0.0; ///< R, signed, non-zero for arcs and S-curves (ignored if straight)
  std::vector<RowGap> gaps;
  CanopyParams canopy;
  TerrainParams terrain;
};

/// Why the parameters are unusable (naming the field as in the JSON file), or nullopt.
std::optional<std::string> RowWorldParamsProblem(const RowWorldParams& params);

/// Parses a world file (format in docs/simulation-world.md): every key required, unknown keys
/// rejected. Throws std::runtime_error "<source>: <key>: <reason>" on any problem, including
/// RowWorldParamsProblem.
RowWorldParams ParseRowWorldParams(std::string_view json_text, std::string_view source_name = "<string>");
/// Reads and parses a file; the error also names the file when it cannot be read.
RowWorldParams LoadRowWorldParams(const std::filesystem::path& path);

/// The canopy outline of one part of a row (between gaps) at one height: a closed polygon,
/// left edge forward then right edge backward.
struct OutlinePart {
  int row = 0;                               ///< 0-based row index
  int part = 0;                              ///< 0-based part index within the row
  std::vector<Eigen::Vector2d> polygon_m;    ///< >= 4 vertices, not repeated at the end
};

class RowWorld {
 public:
  /// Throws std::invalid_argument with RowWorldParamsProblem's message on bad parameters.
  explicit RowWorld(RowWorldParams params);

  const RowWorldParams& params() const { return params_; }
  const TerrainSurface& terrain() const { return terrain_; }

  /// Reference point c(s) and left unit normal n(s); s is clamped to [0, L].
  Eigen::Vector2d ReferencePoint(double station_m) const;
  Eigen::Vector2d ReferenceNormal(double station_m) const;
  /// Signed curvature kappa(s), 1/m.
  double CurvatureAt(double station_m) const;

  /// Centre m_k(s) of row k. Throws std::out_of_range for a bad row.
  Eigen::Vector2d RowCentre(int row, double station_m) const;
  /// w_L(s) and w_R(s) (including roughness), metres.
  double LeftHalfWidth(int row, double station_m) const;
  double RightHalfWidth(int row, double station_m) const;
  /// Canopy band [b_k(s), t_k(s)] above the terrain, metres.
  double BandBottom(int row, double station_m) const;
  double BandTop(int row, double station_m) const;
  /// True if row k has canopy at station s (s in [0, L], not inside a gap) at height h above
  /// the terrain (b_k(s) <= h <= t_k(s)).
  bool HasCanopy(int row, double station_m, double height_m) const;

  /// The outline of every row at height h above the terrain, sampled every <= step metres of
  /// station (plus the exact gap ends); runs of stations with canopy become OutlineParts.
  /// Throws std::invalid_argument unless h is finite, step is in [1e-4, 10] m and the outline
  /// needs at most 2e7 stations over all rows.
  std::vector<OutlinePart> OutlineAt(double height_m, double step_m) const;

  /// M >= |p''(s)| for every outline edge p(s) = m_k(s) +- w(s) n(s) (1/m): with e = d_k +- w,
  /// p'' = -2 e' kappa t + ((1 - e kappa) kappa + e'') n, bounded term by term. Linear
  /// interpolation between stations delta apart is then within M delta^2 / 8 of the true edge.
  double OutlineCurvatureBound() const;
  /// The largest station step (<= 1 m) whose sampled outline is within tolerance_m of the true
  /// one: sqrt(8 tolerance / M). Throws std::invalid_argument unless tolerance is in [1e-9, 1] m
  /// and the step is >= 1e-4 m.
  double StepForTolerance(double tolerance_m) const;

  /// The true row map at height h: one closed polygon per part, ids "row-<k+1>" for a row in one
  /// part, "row-<k+1>.part-<j+1>" otherwise; origin = params().origin.
  /// Throws std::invalid_argument as OutlineAt, or if no canopy exists at that height.
  geometry::RowMap TrueRowMap(double height_m, double step_m) const;

 private:
  struct Piece {
    double start_m, length_m, curvature_per_m, heading_rad;
    Eigen::Vector2d start_point_m;
  };
  struct Sinusoid {
    double wave_number_rad_per_m, phase_rad;
  };
  struct RowShape {
    std::vector<Sinusoid> width, bottom, top, rough_left, rough_right;
  };
  const Piece& PieceAt(double station_m) const;
  const RowShape& Shape(int row) const;
  std::vector<double> Stations(int row, double step_m) const;
  bool InGap(int row, double station_m) const;

  RowWorldParams params_;
  TerrainSurface terrain_;
  std::vector<Piece> pieces_;
  std::vector<RowShape> shapes_;
};

}  // namespace rowloc::sim
