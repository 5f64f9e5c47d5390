#include "rowloc/sim/row_world.hpp"

#include "rowloc/mapio/local_frame.hpp"

#include <algorithm>
#include <cmath>
#include <numbers>
#include <random>
#include <stdexcept>

namespace rowloc::sim {
namespace {

constexpr double kTwoPi = 2.0 * std::numbers::pi;
constexpr double kGoldenRatio = 1.618;
/// Two stations closer than this are merged (far below any sampling step, above rounding).
constexpr double kStationMerge_m = 1e-6;
/// Most stations (over all rows) of one outline: 2e7 stations, ~0.6 GB of vertices and index.
constexpr double kMaxOutlineStations = 2e7;
/// Shortest gap, and shortest distance between two gaps of a row (metres).
constexpr double kMinGap_m = 1e-3;

double Uniform01(std::mt19937_64& rng) { return static_cast<double>(rng() >> 11) * 0x1.0p-53; }

bool Finite(double v) { return std::isfinite(v); }

/// Mean of the sinusoids at s (in [-1, 1]).
template <typename Sinusoids>
double MeanSine(const Sinusoids& terms, double s) {
  double sum = 0.0;
  for (const auto& t : terms) sum += std::sin(t.wave_number_rad_per_m * s + t.phase_rad);
  return sum / static_cast<double>(terms.size());
}

std::optional<std::string> CanopyProblem(const CanopyParams& c, double spacing_m) {
  const double values[] = {c.half_width_m, c.half_width_variation_m, c.width_wavelength_m, c.bottom_m, c.top_m,
                           c.height_variation_m, c.height_wavelength_m, c.roughness_amplitude_m,
                           c.roughness_min_wavelength_m, c.roughness_max_wavelength_m};
  for (double v : values)
    if (!Finite(v)) return "canopy: every value must be finite";
  if (c.half_width_variation_m < 0 || c.height_variation_m < 0 || c.roughness_amplitude_m < 0)
    return "canopy: variations and roughness amplitude must be >= 0";
  if (c.width_wavelength_m <= 0 || c.height_wavelength_m <= 0 || c.roughness_min_wavelength_m <= 0)
    return "canopy: wavelengths must be > 0";
  if (c.roughness_max_wavelength_m < c.roughness_min_wavelength_m)
    return "canopy.roughness_max_wavelength_m must be >= roughness_min_wavelength_m";
  if (c.half_width_m - c.half_width_variation_m - c.roughness_amplitude_m < 0.01)
    return "canopy: half_width_m - half_width_variation_m - roughness_amplitude_m must be >= 0.01 m";
  if (c.half_width_m + c.half_width_variation_m + c.roughness_amplitude_m >= 0.5 * spacing_m)
    return "canopy: the widest canopy (half_width_m + variation + roughness) must be < spacing_m / 2";
  if (c.bottom_m - c.height_variation_m < 0) return "canopy: bottom_m - height_variation_m must be >= 0";
  if (c.top_m - c.bottom_m <= 2 * c.height_variation_m)
    return "canopy: top_m - bottom_m must exceed 2 height_variation_m (the band must never be empty)";
  return std::nullopt;
}

std::optional<std::string> LayoutProblem(const RowWorldParams& p) {
  if (p.row_count < 1 || p.row_count > 1000) return "rows.count must be in [1, 1000]";
  if (!Finite(p.row_spacing_m) || p.row_spacing_m <= 0) return "rows.spacing_m must be finite and > 0";
  if (!Finite(p.row_length_m) || p.row_length_m <= 0 || p.row_length_m > 1e4)
    return "rows.length_m must be in (0, 10000]";
  if (!Finite(p.heading_rad)) return "rows.heading_rad must be finite";
  if (p.curvature == RowCurvature::kStraight) return std::nullopt;
  if (!Finite(p.curvature_radius_m) || p.curvature_radius_m == 0)
    return "curvature.radius_m must be finite and non-zero";
  const CanopyParams& c = p.canopy;
  const double reach_m = (p.row_count - 1) * p.row_spacing_m + c.half_width_m + c.half_width_variation_m +
                         c.roughness_amplitude_m;
  if (reach_m >= 0.9 * std::abs(p.curvature_radius_m))
    return "curvature.radius_m is too small: |radius| must exceed (count - 1) spacing + widest half-width by 10 %";
  return std::nullopt;
}

std::optional<std::string> GapProblem(const RowWorldParams& p) {
  for (std::size_t i = 0; i < p.gaps.size(); ++i) {
    const RowGap& g = p.gaps[i];
    const std::string where = "gaps[" + std::to_string(i) + "]";
    if (g.row < 0 || g.row >= p.row_count) return where + ".row must be in [0, rows.count)";
    if (!Finite(g.start_m) || !Finite(g.end_m) || g.start_m < 0 || g.end_m > p.row_length_m ||
        g.end_m - g.start_m < kMinGap_m)
      return where + ": need 0 <= start_m, start_m + 0.001 <= end_m <= rows.length_m";
    for (std::size_t j = 0; j < i; ++j) {
      const RowGap& o = p.gaps[j];
      if (o.row == g.row && g.start_m < o.end_m + kMinGap_m && o.start_m < g.end_m + kMinGap_m)
        return where + " and gaps[" + std::to_string(j) + "] overlap or are closer than 1 mm (merge them)";
    }
  }
  return std::nullopt;
}

/// The two wavelengths of a smooth variation.
std::vector<double> Wavelengths(double wavelength_m) { return {wavelength_m, kGoldenRatio * wavelength_m}; }

}  // namespace

std::optional<std::string> RowWorldParamsProblem(const RowWorldParams& p) {
  if (p.name.empty()) return "name must not be empty";
  const std::string origin =
      mapio::GeodeticPositionProblem(p.origin.latitude_deg, p.origin.longitude_deg, p.origin.altitude_m);
  if (!origin.empty()) return "origin: " + origin;
  if (auto problem = LayoutProblem(p)) return problem;
  if (auto problem = CanopyProblem(p.canopy, p.row_spacing_m)) return problem;
  if (auto problem = GapProblem(p)) return problem;
  return TerrainParamsProblem(p.terrain);
}

namespace {
RowWorldParams Validated(RowWorldParams p) {
  if (auto problem = RowWorldParamsProblem(p)) throw std::invalid_argument("RowWorld: " + *problem);
  return p;
}
}  // namespace

RowWorld::RowWorld(RowWorldParams params)
    : params_(Validated(std::move(params))), terrain_(params_.terrain, params_.seed) {
  const double length_m = params_.row_length_m;
  const double kappa = params_.curvature == RowCurvature::kStraight ? 0.0 : 1.0 / params_.curvature_radius_m;
  std::vector<std::pair<double, double>> lengths_and_curvatures;
  if (params_.curvature == RowCurvature::kSCurve)
    lengths_and_curvatures = {{0.5 * length_m, kappa}, {0.5 * length_m, -kappa}};
  else
    lengths_and_curvatures = {{length_m, kappa}};
  Piece piece{0.0, 0.0, 0.0, params_.heading_rad, Eigen::Vector2d::Zero()};
  for (const auto& [piece_length_m, curvature] : lengths_and_curvatures) {
    piece.length_m = piece_length_m;
    piece.curvature_per_m = curvature;
    pieces_.push_back(piece);
    piece.start_point_m = ReferencePoint(piece.start_m + piece_length_m);
    piece.heading_rad += curvature * piece_length_m;
    piece.start_m += piece_length_m;
  }
  const CanopyParams& c = params_.canopy;
  for (int k = 0; k < params_.row_count; ++k) {
    std::mt19937_64 rng(params_.seed + static_cast<std::uint64_t>(k + 1) * 0x9E3779B97F4A7C15ULL);
    auto smooth = [&](double wavelength_m) {
      std::vector<Sinusoid> terms;
      for (double w : Wavelengths(wavelength_m)) terms.push_back({kTwoPi / w, kTwoPi * Uniform01(rng)});
      return terms;
    };
    auto rough = [&] {
      std::vector<Sinusoid> terms;
      for (int j = 0; j < 3; ++j) {
        const double w = c.roughness_min_wavelength_m +
                         (c.roughness_max_wavelength_m - c.roughness_min_wavelength_m) * Uniform01(rng);
        terms.push_back({kTwoPi / w, kTwoPi * Uniform01(rng)});
      }
      return terms;
    };
    RowShape shape;
    shape.width = smooth(c.width_wavelength_m);
    shape.bottom = smooth(c.height_wavelength_m);
    shape.top = smooth(c.height_wavelength_m);
    shape.rough_left = rough();
    shape.rough_right = rough();
    shapes_.push_back(std::move(shape));
  }
}

const RowWorld::Piece& RowWorld::PieceAt(double station_m) const {
  for (const Piece& p : pieces_)
    if (station_m < p.start_m + p.length_m) return p;
  return pieces_.back();
}

Eigen::Vector2d RowWorld::ReferencePoint(double station_m) const {
  const double s = std::clamp(station_m, 0.0, params_.row_length_m);
  const Piece& p = PieceAt(s);
  const double t = s - p.start_m;
  const double h0 = p.heading_rad;
  if (p.curvature_per_m == 0.0) return p.start_point_m + t * Eigen::Vector2d(std::cos(h0), std::sin(h0));
  const double h1 = h0 + p.curvature_per_m * t;
  return p.start_point_m +
         Eigen::Vector2d(std::sin(h1) - std::sin(h0), std::cos(h0) - std::cos(h1)) / p.curvature_per_m;
}

Eigen::Vector2d RowWorld::ReferenceNormal(double station_m) const {
  const double s = std::clamp(station_m, 0.0, params_.row_length_m);
  const Piece& p = PieceAt(s);
  const double heading = p.heading_rad + p.curvature_per_m * (s - p.start_m);
  return {-std::sin(heading), std::cos(heading)};
}

double RowWorld::CurvatureAt(double station_m) const {
  return PieceAt(std::clamp(station_m, 0.0, params_.row_length_m)).curvature_per_m;
}

const RowWorld::RowShape& RowWorld::Shape(int row) const {
  if (row < 0 || row >= params_.row_count)
    throw std::out_of_range("RowWorld: row " + std::to_string(row) + " is not in [0, " +
                            std::to_string(params_.row_count) + ")");
  return shapes_[static_cast<std::size_t>(row)];
}

Eigen::Vector2d RowWorld::RowCentre(int row, double station_m) const {
  Shape(row);
  return ReferencePoint(station_m) + row * params_.row_spacing_m * ReferenceNormal(station_m);
}

double RowWorld::LeftHalfWidth(int row, double station_m) const {
  const RowShape& s = Shape(row);
  const CanopyParams& c = params_.canopy;
  return c.half_width_m + c.half_width_variation_m * MeanSine(s.width, station_m) +
         c.roughness_amplitude_m * MeanSine(s.rough_left, station_m);
}

double RowWorld::RightHalfWidth(int row, double station_m) const {
  const RowShape& s = Shape(row);
  const CanopyParams& c = params_.canopy;
  return c.half_width_m + c.half_width_variation_m * MeanSine(s.width, station_m) +
         c.roughness_amplitude_m * MeanSine(s.rough_right, station_m);
}

double RowWorld::BandBottom(int row, double station_m) const {
  return params_.canopy.bottom_m + params_.canopy.height_variation_m * MeanSine(Shape(row).bottom, station_m);
}

double RowWorld::BandTop(int row, double station_m) const {
  return params_.canopy.top_m + params_.canopy.height_variation_m * MeanSine(Shape(row).top, station_m);
}

bool RowWorld::InGap(int row, double station_m) const {
  return std::any_of(params_.gaps.begin(), params_.gaps.end(), [&](const RowGap& g) {
    return g.row == row && station_m > g.start_m && station_m < g.end_m;
  });
}

bool RowWorld::HasCanopy(int row, double station_m, double height_m) const {
  if (station_m < 0 || station_m > params_.row_length_m || InGap(row, station_m)) return false;
  return height_m >= BandBottom(row, station_m) && height_m <= BandTop(row, station_m);
}

std::vector<double> RowWorld::Stations(int row, double step_m) const {
  // The uniform grid, minus grid points within kStationMerge_m of a gap end, plus the exact gap
  // ends (so that a part ends exactly where its gap begins).
  std::vector<double> gap_ends;
  for (const RowGap& g : params_.gaps)
    if (g.row == row) gap_ends.insert(gap_ends.end(), {g.start_m, g.end_m});
  const auto near_gap_end = [&](double s) {
    return std::any_of(gap_ends.begin(), gap_ends.end(), [&](double e) { return std::abs(s - e) <= kStationMerge_m; });
  };
  const double length_m = params_.row_length_m;
  const auto n = static_cast<std::size_t>(std::ceil(length_m / step_m));
  std::vector<double> stations = gap_ends;
  for (std::size_t i = 0; i <= n; ++i) {
    const double s = length_m * static_cast<double>(i) / static_cast<double>(n);
    if (!near_gap_end(s)) stations.push_back(s);
  }
  std::sort(stations.begin(), stations.end());
  stations.erase(std::unique(stations.begin(), stations.end()), stations.end());
  return stations;
}

std::vector<OutlinePart> RowWorld::OutlineAt(double height_m, double step_m) const {
  if (!Finite(height_m)) throw std::invalid_argument("RowWorld::OutlineAt: height is not finite");
  if (!(step_m >= 1e-4 && step_m <= 10.0))
    throw std::invalid_argument("RowWorld::OutlineAt: step must be in [1e-4, 10] m");
  const double stations = (std::ceil(params_.row_length_m / step_m) + 1.0) * params_.row_count;
  if (stations > kMaxOutlineStations)
    throw std::invalid_argument("RowWorld::OutlineAt: step " + std::to_string(step_m) + " m would need " +
                                std::to_string(stations) + " stations (limit 2e7); use a larger step");
  std::vector<OutlinePart> parts;
  for (int k = 0; k < params_.row_count; ++k) {
    int part_index = 0;
    std::vector<double> run;
    auto flush = [&] {
      if (run.size() >= 2) {
        OutlinePart part{k, part_index++, {}};
        for (double s : run) part.polygon_m.push_back(RowCentre(k, s) + LeftHalfWidth(k, s) * ReferenceNormal(s));
        for (auto it = run.rbegin(); it != run.rend(); ++it)
          part.polygon_m.push_back(RowCentre(k, *it) - RightHalfWidth(k, *it) * ReferenceNormal(*it));
        parts.push_back(std::move(part));
      }
      run.clear();
    };
    for (double s : Stations(k, step_m)) {
      if (HasCanopy(k, s, height_m)) {
        run.push_back(s);
      } else {
        flush();
      }
    }
    flush();
  }
  return parts;
}

double RowWorld::OutlineCurvatureBound() const {
  const CanopyParams& c = params_.canopy;
  const double kappa = params_.curvature == RowCurvature::kStraight ? 0.0 : 1.0 / std::abs(params_.curvature_radius_m);
  const double k_width = kTwoPi / c.width_wavelength_m;  // the shorter of the two width wavelengths
  const double k_rough = kTwoPi / c.roughness_min_wavelength_m;
  const double e_max = (params_.row_count - 1) * params_.row_spacing_m + c.half_width_m + c.half_width_variation_m +
                       c.roughness_amplitude_m;
  const double de_max = c.half_width_variation_m * k_width + c.roughness_amplitude_m * k_rough;
  const double dde_max = c.half_width_variation_m * k_width * k_width + c.roughness_amplitude_m * k_rough * k_rough;
  return 2.0 * de_max * kappa + (1.0 + e_max * kappa) * kappa + dde_max;
}

double RowWorld::StepForTolerance(double tolerance_m) const {
  if (!(tolerance_m >= 1e-9 && tolerance_m <= 1.0))
    throw std::invalid_argument("RowWorld::StepForTolerance: tolerance must be in [1e-9, 1] m");
  const double bound = OutlineCurvatureBound();
  if (bound <= 0.0) return 1.0;
  const double step_m = std::min(std::sqrt(8.0 * tolerance_m / bound), 1.0);
  if (step_m < 1e-4)
    throw std::invalid_argument("RowWorld::StepForTolerance: tolerance too small for this canopy (step < 0.1 mm)");
  return step_m;
}

geometry::RowMap RowWorld::TrueRowMap(double height_m, double step_m) const {
  const std::vector<OutlinePart> parts = OutlineAt(height_m, step_m);
  if (parts.empty())
    throw std::invalid_argument("RowWorld::TrueRowMap: no canopy at height " + std::to_string(height_m) + " m");
  geometry::RowMap map;
  map.origin = params_.origin;
  for (std::size_t i = 0; i < parts.size(); ++i) {
    const OutlinePart& p = parts[i];
    const bool alone = (i == 0 || parts[i - 1].row != p.row) && (i + 1 == parts.size() || parts[i + 1].row != p.row);
    std::string id = "row-" + std::to_string(p.row + 1);
    if (!alone) id += ".part-" + std::to_string(p.part + 1);
    map.rows.push_back({std::move(id), p.polygon_m, true});
  }
  return map;
}

}  // namespace rowloc::sim
