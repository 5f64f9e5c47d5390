#include "rowloc/sim/canopy_surface_sampler.hpp"

#include <Eigen/Geometry>

#include <algorithm>
#include <cmath>
#include <numbers>
#include <random>
#include <sstream>
#include <stdexcept>
#include <utility>

namespace rowloc::sim {
namespace {

constexpr double kTwoPi = 2.0 * std::numbers::pi;
/// Seed of the noise/dropout stream: seed XOR this constant (see the header).
constexpr std::uint64_t kNoiseStreamXor = 0x5DEECE66DA3B2C1FULL;
/// Seed of the outlier stream: seed XOR this constant (see the header).
constexpr std::uint64_t kOutlierStreamXor = 0x2545F4914F6CDD1DULL;
/// Half-width of the central differences that give surface tangents (metres of station).
constexpr double kDerivativeStep_m = 1e-5;
/// Lateral deviation tolerated between the chords and the true curves when measuring arc length.
constexpr double kChordTolerance_m = 1e-4;
/// Smallest fine station step (bounds the work for extreme roughness), metres.
constexpr double kMinFineStep_m = 1e-4;

double Uniform01(std::mt19937_64& rng) { return static_cast<double>(rng() >> 11) * 0x1.0p-53; }

/// Standard normal by Box-Muller from two uniform draws (platform independent).
double StandardNormal(std::mt19937_64& rng) {
  const double u1 = 1.0 - Uniform01(rng);  // (0, 1]
  const double u2 = Uniform01(rng);
  return std::sqrt(-2.0 * std::log(u1)) * std::cos(kTwoPi * u2);
}

/// d f / ds at s (up to a positive factor, 2 eps), from samples of f in [0, length]: central
/// difference inside, second-order one-sided difference at the ends (RowWorld clamps stations).
template <typename F>
auto Derivative(const F& f, double s, double length_m) {
  const double eps = kDerivativeStep_m;
  if (s - eps < 0.0) return (4.0 * f(s + eps) - 3.0 * f(s) - f(s + 2.0 * eps)).eval();
  if (s + eps > length_m) return (3.0 * f(s) - 4.0 * f(s - eps) + f(s - 2.0 * eps)).eval();
  return (f(s + eps) - f(s - eps)).eval();
}

std::string RangeProblem(const char* field, double value, double lo, double hi, bool hi_open, const char* unit) {
  const bool ok = std::isfinite(value) && value >= lo && (hi_open ? value < hi : value <= hi);
  if (ok) return {};
  std::ostringstream out;
  out << field << " must be in [" << lo << ", " << hi << (hi_open ? ")" : "]") << unit << ", got " << value;
  return out.str();
}

/// A closed interval of stations of one row that carries canopy (between gaps).
struct Run {
  double start_m;
  double end_m;
};

std::vector<Run> CanopyRuns(const RowWorld& world, int row) {
  std::vector<RowGap> gaps;
  for (const RowGap& g : world.params().gaps)
    if (g.row == row) gaps.push_back(g);
  std::sort(gaps.begin(), gaps.end(), [](const RowGap& a, const RowGap& b) { return a.start_m < b.start_m; });
  std::vector<Run> runs;
  double cursor_m = 0.0;
  for (const RowGap& g : gaps) {
    if (g.start_m > cursor_m) runs.push_back({cursor_m, g.start_m});
    cursor_m = g.end_m;
  }
  if (world.params().row_length_m > cursor_m) runs.push_back({cursor_m, world.params().row_length_m});
  return runs;
}

/// Emits the samples of one world; owns the two random streams.
class Sampler {
 public:
  Sampler(const RowWorld& world, const SurveyParams& params, const std::function<void(const SurveySample&)>& visit)
      : world_(world),
        params_(params),
        visit_(visit),
        positions_(params.seed),
        noise_(params.seed ^ kNoiseStreamXor),
        fine_step_m_(FineStep(params.spacing_m, world.OutlineCurvatureBound())),
        terrain_fine_step_m_(FineStep(params.terrain_spacing_m, TerrainStripCurvatureBound(world.params()))) {}

  void Row(int row) {
    for (const Run& run : CanopyRuns(world_, row)) {
      Face(row, run, SurveySurface::kLeftFace);
      if (!params_.one_sided) Face(row, run, SurveySurface::kRightFace);
      Top(row, run);
      EndCap(row, run.start_m, -1.0);
      EndCap(row, run.end_m, +1.0);
    }
  }

  void Terrain() {
    const RowWorldParams& p = world_.params();
    const double spacing_m = p.row_spacing_m;
    const double lo_m = -0.5 * spacing_m;
    const double hi_m = (p.row_count - 0.5) * spacing_m;
    const double cell_m = params_.terrain_spacing_m;
    for (double j = 0.0; lo_m + j * cell_m < hi_m; j += 1.0) {
      const double strip_m = lo_m + j * cell_m;
      const double mid_m = std::min(strip_m + 0.5 * cell_m, hi_m);
      const auto curve = [&](double s) -> Eigen::Vector2d {
        return world_.ReferencePoint(s) + mid_m * world_.ReferenceNormal(s);
      };
      Walk(curve, 0.0, p.row_length_m, cell_m, terrain_fine_step_m_, [&](double s) {
        const double e_m = strip_m + cell_m * Uniform01(positions_);
        if (e_m >= hi_m || UnderCanopy(s, e_m)) return;
        const Eigen::Vector2d xy = world_.ReferencePoint(s) + e_m * world_.ReferenceNormal(s);
        const Eigen::Vector2d gradient = world_.terrain().GradientAt(xy);
        const Eigen::Vector3d normal = Eigen::Vector3d(-gradient.x(), -gradient.y(), 1.0).normalized();
        Emit({xy.x(), xy.y(), world_.terrain().HeightAt(xy)}, normal, SurveySurface::kTerrain, -1, s);
      });
    }
  }

  /// The outliers (see the header), once the rows and the terrain are emitted.
  void Outliers() {
    if (params_.outlier_fraction <= 0.0 || kept_ == 0) return;
    const auto count = static_cast<std::size_t>(std::llround(params_.outlier_fraction * static_cast<double>(kept_)));
    const Eigen::Vector3d lo = lo_.array() - 1.0;
    const Eigen::Vector3d span = (hi_ - lo_).array() + 2.0;
    std::mt19937_64 outliers(params_.seed ^ kOutlierStreamXor);
    for (std::size_t k = 0; k < count; ++k) {
      const Eigen::Vector3d u(Uniform01(outliers), Uniform01(outliers), Uniform01(outliers));
      visit_(SurveySample{lo + span.cwiseProduct(u), Eigen::Vector3d::UnitZ(), 0.0, SurveySurface::kOutlier, -1, 0.0});
    }
  }


 private:
  /// A station step <= cell / 4 whose chords stay within kChordTolerance_m of curves with
  /// |p''| <= curvature_bound (chord deviation <= |p''| step^2 / 8), and >= kMinFineStep_m.
  static double FineStep(double cell_m, double curvature_bound) {
    double step_m = 0.25 * cell_m;
    if (curvature_bound > 0.0) step_m = std::min(step_m, std::sqrt(8.0 * kChordTolerance_m / curvature_bound));
    return std::max(step_m, kMinFineStep_m);
  }

  /// |p''| of a terrain strip's offset curve c + e n: |kappa| (1 + |kappa| |e|), |e| <= count spacing.
  static double TerrainStripCurvatureBound(const RowWorldParams& p) {
    if (p.curvature == RowCurvature::kStraight) return 0.0;
    const double kappa = 1.0 / std::abs(p.curvature_radius_m);
    return kappa * (1.0 + kappa * p.row_count * p.row_spacing_m);
  }

  /// Calls at_station(s) once per arc-length cell [j h, (j + 1) h) of curve_xy over stations
  /// [a, b], at a uniform arc position inside the cell (cells past the end are skipped).
  template <typename Curve, typename AtStation>
  void Walk(const Curve& curve_xy, double a_m, double b_m, double cell_m, double fine_step_m,
            const AtStation& at_station) {
    const double steps = std::max(1.0, std::ceil((b_m - a_m) / fine_step_m));
    const auto count = static_cast<std::size_t>(steps);
    Eigen::Vector2d p0 = curve_xy(a_m);
    double s0_m = a_m;
    double arc0_m = 0.0;
    double cell = 0.0;
    double next_m = cell_m * Uniform01(positions_);
    for (std::size_t i = 1; i <= count; ++i) {
      const double s1_m = i == count ? b_m : a_m + (b_m - a_m) * static_cast<double>(i) / steps;
      const Eigen::Vector2d p1 = curve_xy(s1_m);
      const double chord_m = (p1 - p0).norm();
      while (next_m < arc0_m + chord_m) {  // never true for chord 0 (next >= arc0 holds)
        at_station(s0_m + (next_m - arc0_m) / chord_m * (s1_m - s0_m));
        cell += 1.0;
        next_m = (cell + Uniform01(positions_)) * cell_m;
      }
      arc0_m += chord_m;
      p0 = p1;
      s0_m = s1_m;
    }
  }

  /// Calls at(v) once per cell [lo + j h, lo + (j + 1) h) with a uniform v inside it, if v < hi.
  template <typename At>
  void Stratify(double lo, double hi, double cell_m, const At& at) {
    for (double j = 0.0; lo + j * cell_m < hi; j += 1.0) {
      const double v = lo + (j + Uniform01(positions_)) * cell_m;
      if (v < hi) at(v);
    }
  }

  Eigen::Vector2d FacePoint(int row, double s, double side) const {
    const double w_m = side > 0 ? world_.LeftHalfWidth(row, s) : world_.RightHalfWidth(row, s);
    return world_.RowCentre(row, s) + side * w_m * world_.ReferenceNormal(s);
  }

  void Face(int row, const Run& run, SurveySurface surface) {
    const double side = surface == SurveySurface::kLeftFace ? 1.0 : -1.0;
    const auto curve = [&](double s) { return FacePoint(row, s, side); };
    Walk(curve, run.start_m, run.end_m, params_.spacing_m, fine_step_m_, [&](double s) {
      const Eigen::Vector2d d = Derivative(curve, s, world_.params().row_length_m);
      const Eigen::Vector3d normal = (side * Eigen::Vector3d(-d.y(), d.x(), 0.0)).normalized();
      const Eigen::Vector2d xy = curve(s);
      const double ground_m = world_.terrain().HeightAt(xy);
      Stratify(world_.BandBottom(row, s), world_.BandTop(row, s), params_.spacing_m, [&](double h) {
        Emit({xy.x(), xy.y(), ground_m + h}, normal, surface, row, s);
      });
    });
  }

  Eigen::Vector3d TopPoint(int row, double s, double u) const {
    const Eigen::Vector2d xy = world_.RowCentre(row, s) + u * world_.ReferenceNormal(s);
    return {xy.x(), xy.y(), world_.terrain().HeightAt(xy) + world_.BandTop(row, s)};
  }

  void Top(int row, const Run& run) {
    const auto centre = [&](double s) { return world_.RowCentre(row, s); };
    Walk(centre, run.start_m, run.end_m, params_.spacing_m, fine_step_m_, [&](double s) {
      const Eigen::Vector2d n = world_.ReferenceNormal(s);
      Stratify(-world_.RightHalfWidth(row, s), world_.LeftHalfWidth(row, s), params_.spacing_m, [&](double u) {
        const Eigen::Vector3d point = TopPoint(row, s, u);
        const Eigen::Vector3d along =
            Derivative([&](double t) { return TopPoint(row, t, u); }, s, world_.params().row_length_m);
        const Eigen::Vector2d xy = point.head<2>();
        const Eigen::Vector3d across(n.x(), n.y(), world_.terrain().GradientAt(xy).dot(n));
        Emit(point, along.cross(across).normalized(), SurveySurface::kTop, row, s);
      });
    });
  }

  /// The cap at station s of a run: direction -1 at its start, +1 at its end.
  void EndCap(int row, double s, double direction) {
    const Eigen::Vector2d n = world_.ReferenceNormal(s);
    const Eigen::Vector3d normal = direction * Eigen::Vector3d(n.y(), -n.x(), 0.0);  // +- tangent
    const Eigen::Vector2d centre = world_.RowCentre(row, s);
    const double bottom_m = world_.BandBottom(row, s);
    const double top_m = world_.BandTop(row, s);
    Stratify(-world_.RightHalfWidth(row, s), world_.LeftHalfWidth(row, s), params_.spacing_m, [&](double u) {
      const Eigen::Vector2d xy = centre + u * n;
      const double ground_m = world_.terrain().HeightAt(xy);
      Stratify(bottom_m, top_m, params_.spacing_m, [&](double h) {
        Emit({xy.x(), xy.y(), ground_m + h}, normal, SurveySurface::kEndCap, row, s);
      });
    });
  }

  /// True if lateral offset e at station s lies in the footprint of a row's canopy (only the
  /// nearest row can cover it: canopies are narrower than half a spacing).
  bool UnderCanopy(double s, double e_m) const {
    const RowWorldParams& p = world_.params();
    const int row = std::clamp(static_cast<int>(std::lround(e_m / p.row_spacing_m)), 0, p.row_count - 1);
    if (!world_.HasCanopy(row, s, world_.BandBottom(row, s))) return false;  // gap or past the end
    const double u_m = e_m - row * p.row_spacing_m;
    return u_m >= -world_.RightHalfWidth(row, s) && u_m <= world_.LeftHalfWidth(row, s);
  }

  void Emit(const Eigen::Vector3d& point_m, const Eigen::Vector3d& normal, SurveySurface surface, int row, double s) {
    const double keep = Uniform01(noise_);
    const double noise_m = params_.noise_sigma_m * StandardNormal(noise_);
    if (keep < params_.dropout_fraction) return;
    const Eigen::Vector3d p = point_m + noise_m * normal;
    lo_ = kept_ == 0 ? p : Eigen::Vector3d(lo_.cwiseMin(p));
    hi_ = kept_ == 0 ? p : Eigen::Vector3d(hi_.cwiseMax(p));
    ++kept_;
    visit_(SurveySample{p, normal, noise_m, surface, row, s});
  }

  const RowWorld& world_;
  const SurveyParams& params_;
  const std::function<void(const SurveySample&)>& visit_;
  std::mt19937_64 positions_;
  std::mt19937_64 noise_;
  double fine_step_m_;
  double terrain_fine_step_m_;
  std::size_t kept_ = 0;
  Eigen::Vector3d lo_ = Eigen::Vector3d::Zero();
  Eigen::Vector3d hi_ = Eigen::Vector3d::Zero();
};

void Validate(const SurveyParams& params) {
  if (auto problem = SurveyParamsProblem(params)) throw std::invalid_argument("SurveyParams: " + *problem);
}

}  // namespace

std::optional<std::string> SurveyParamsProblem(const SurveyParams& p) {
  for (const std::string& problem :
       {RangeProblem("spacing_m", p.spacing_m, 1e-3, 10.0, false, " m"),
        RangeProblem("noise_sigma_m", p.noise_sigma_m, 0.0, 1.0, false, " m"),
        RangeProblem("dropout_fraction", p.dropout_fraction, 0.0, 1.0, true, ""),
        RangeProblem("terrain_spacing_m", p.terrain_spacing_m, 1e-3, 100.0, false, " m"),
        RangeProblem("outlier_fraction", p.outlier_fraction, 0.0, 0.5, false, "")})
    if (!problem.empty()) return problem;
  return std::nullopt;
}

double SurveyPointBound(const RowWorld& world, const SurveyParams& params) {
  Validate(params);
  const RowWorldParams& p = world.params();
  const CanopyParams& c = p.canopy;
  const double kappa = p.curvature == RowCurvature::kStraight ? 0.0 : 1.0 / std::abs(p.curvature_radius_m);
  const double w_max = c.half_width_m + c.half_width_variation_m + c.roughness_amplitude_m;
  const double e_max = (p.row_count - 1) * p.row_spacing_m + w_max;
  const double de_max = c.half_width_variation_m * kTwoPi / c.width_wavelength_m +
                        c.roughness_amplitude_m * kTwoPi / c.roughness_min_wavelength_m;
  const double stretch = std::hypot(1.0 + kappa * e_max, de_max);  // >= |d xy / ds| of every sampled curve
  const double band_m = c.top_m - c.bottom_m + 2.0 * c.height_variation_m;
  const double runs = p.row_count + static_cast<double>(p.gaps.size());
  const double h = params.spacing_m;
  // Cells along a run of length l: <= l stretch / h + 1; summed over runs: rows L stretch / h + runs.
  const double columns = p.row_count * p.row_length_m * stretch / h + runs;
  const double across_band = band_m / h + 1.0;
  const double across_width = 2.0 * w_max / h + 1.0;
  double bound = 2.0 * columns * across_band + columns * across_width + 2.0 * runs * across_width * across_band;
  if (params.include_terrain) {
    const double ht = params.terrain_spacing_m;
    const double reach_m = (p.row_count - 0.5) * p.row_spacing_m;
    const double strips = p.row_count * p.row_spacing_m / ht + 1.0;
    bound += strips * (p.row_length_m * (1.0 + kappa * reach_m) / ht + 1.0);
  }
  return bound * (1.0 + params.outlier_fraction);
}

void SampleSurvey(const RowWorld& world, const SurveyParams& params,
                  const std::function<void(const SurveySample&)>& visit) {
  const double bound = SurveyPointBound(world, params);
  if (bound > kMaxSurveyPoints) {
    std::ostringstream out;
    out << "SampleSurvey: these parameters could produce up to " << bound << " points (limit "
        << kMaxSurveyPoints << "); use a larger spacing_m or terrain_spacing_m";
    throw std::invalid_argument(out.str());
  }
  Sampler sampler(world, params, visit);
  for (int row = 0; row < world.params().row_count; ++row) sampler.Row(row);
  if (params.include_terrain) sampler.Terrain();
  sampler.Outliers();
}

std::vector<Eigen::Vector3d> SampleCanopySurface(const RowWorld& world, const SurveyParams& params) {
  std::vector<Eigen::Vector3d> points;
  SampleSurvey(world, params, [&points](const SurveySample& s) { points.push_back(s.position_m); });
  return points;
}

}  // namespace rowloc::sim
