// CanopySurfaceSampler: noise-free points lie on the exact canopy solid (checked against an
// independent arc parametrisation), never in a gap, terrain points on the ground outside the
// canopy; count ~ area / spacing^2; determinism; noise along the normal (chi-square); dropout
// (binomial); parameter errors and the point cap.
#include "rowloc/sim/canopy_surface_sampler.hpp"

#include <boost/math/distributions/chi_squared.hpp>
#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include <cmath>
#include <limits>
#include <map>
#include <stdexcept>

namespace rowloc::sim {
namespace {

using ::testing::HasSubstr;

constexpr double kOnSurface_m = 1e-9;

/// Three rows on a left arc of radius 40 m, roughness, two gaps, sloped undulating terrain.
RowWorldParams ArcWorld() {
  RowWorldParams p;
  p.row_count = 3;
  p.row_length_m = 20.0;
  p.heading_rad = 0.3;
  p.curvature = RowCurvature::kArc;
  p.curvature_radius_m = 40.0;
  p.canopy.roughness_amplitude_m = 0.015;
  p.gaps = {{1, 5.0, 7.5}, {2, 0.0, 1.0}};
  p.terrain.grade_east = 0.04;
  p.terrain.grade_north = -0.02;
  p.terrain.undulation_amplitude_m = 0.2;
  return p;
}

/// Straight rows with constant width and band on flat ground: every surface is a plane.
RowWorldParams BoxWorld() {
  RowWorldParams p;
  p.row_count = 2;
  p.row_length_m = 20.0;
  p.canopy.half_width_variation_m = 0.0;
  p.canopy.height_variation_m = 0.0;
  p.canopy.half_width_m = 0.25;
  p.canopy.bottom_m = 0.5;
  p.canopy.top_m = 1.8;
  return p;
}

SurveyParams NoiseFree(double spacing_m) {
  SurveyParams s;
  s.spacing_m = spacing_m;
  s.noise_sigma_m = 0.0;
  s.seed = 7;
  return s;
}

std::vector<SurveySample> Samples(const RowWorld& world, const SurveyParams& params) {
  std::vector<SurveySample> out;
  SampleSurvey(world, params, [&out](const SurveySample& s) { out.push_back(s); });
  return out;
}

/// Station and left offset from the reference curve of a left arc, from the arc's own geometry
/// (centre c(0) + R n(0)), independent of RowWorld's evaluation.
struct ArcCoordinates {
  double station_m;
  double offset_m;
};
ArcCoordinates OnArc(const RowWorldParams& p, const Eigen::Vector2d& xy) {
  const double r = p.curvature_radius_m;
  const Eigen::Vector2d centre = r * Eigen::Vector2d(-std::sin(p.heading_rad), std::cos(p.heading_rad));
  const Eigen::Vector2d v0 = -centre;
  const Eigen::Vector2d v = xy - centre;
  const double angle = std::atan2(v0.x() * v.y() - v0.y() * v.x(), v0.dot(v));
  return {r * angle, r - v.norm()};
}

bool InGap(const RowWorldParams& p, int row, double s) {
  for (const RowGap& g : p.gaps)
    if (g.row == row && s > g.start_m + kOnSurface_m && s < g.end_m - kOnSurface_m) return true;
  return false;
}

/// Distance of a noise-free canopy point to the canopy surface it lies on (the smallest over the
/// faces, the top and the end caps it could belong to), and which one.
std::pair<double, SurveySurface> SurfaceDistance(const RowWorld& world, const Eigen::Vector3d& point) {
  const RowWorldParams& p = world.params();
  const ArcCoordinates a = OnArc(p, point.head<2>());
  const int k = static_cast<int>(std::lround(a.offset_m / p.row_spacing_m));
  const double s = a.station_m;
  const double u = a.offset_m - k * p.row_spacing_m;
  const double h = point.z() - world.terrain().HeightAt(point.head<2>());
  const double w_l = world.LeftHalfWidth(k, s), w_r = world.RightHalfWidth(k, s);
  const double b = world.BandBottom(k, s), t = world.BandTop(k, s);
  const bool in_band = h >= b - kOnSurface_m && h <= t + kOnSurface_m;
  const bool in_width = u >= -w_r - kOnSurface_m && u <= w_l + kOnSurface_m;
  constexpr double kFar = std::numeric_limits<double>::infinity();
  std::vector<std::pair<double, SurveySurface>> candidates = {
      {in_band ? std::abs(u - w_l) : kFar, SurveySurface::kLeftFace},
      {in_band ? std::abs(u + w_r) : kFar, SurveySurface::kRightFace},
      {in_width ? std::abs(h - t) : kFar, SurveySurface::kTop}};
  std::vector<double> ends = {0.0, p.row_length_m};
  for (const RowGap& g : p.gaps)
    if (g.row == k) ends.insert(ends.end(), {g.start_m, g.end_m});
  for (double e : ends) candidates.push_back({in_band && in_width ? std::abs(s - e) : kFar, SurveySurface::kEndCap});
  return *std::min_element(candidates.begin(), candidates.end(),
                           [](const auto& x, const auto& y) { return x.first < y.first; });
}

TEST(CanopySurfaceSampler, NoiseFreePointsLieOnTheExactCanopyOrGround) {
  const RowWorld world(ArcWorld());
  SurveyParams params = NoiseFree(0.05);
  params.include_terrain = true;
  params.terrain_spacing_m = 0.2;
  std::map<SurveySurface, int> counts;
  for (const SurveySample& sample : Samples(world, params)) {
    ++counts[sample.surface];
    const Eigen::Vector2d xy = sample.position_m.head<2>();
    const ArcCoordinates a = OnArc(world.params(), xy);
    ASSERT_NEAR(a.station_m, sample.station_m, 1e-9);
    ASSERT_NEAR(sample.normal.norm(), 1.0, 1e-12);
    if (sample.surface == SurveySurface::kTerrain) {
      ASSERT_NEAR(sample.position_m.z(), world.terrain().HeightAt(xy), kOnSurface_m);
      const int k = std::clamp(static_cast<int>(std::lround(a.offset_m / 2.5)), 0, 2);
      const double u = a.offset_m - 2.5 * k;
      const bool covered = !InGap(world.params(), k, a.station_m) && u > -world.RightHalfWidth(k, a.station_m) + 1e-9 &&
                           u < world.LeftHalfWidth(k, a.station_m) - 1e-9;
      ASSERT_FALSE(covered) << "terrain point under the canopy of row " << k << " at s = " << a.station_m;
      ASSERT_GT(sample.normal.z(), 0.9);
      continue;
    }
    ASSERT_FALSE(InGap(world.params(), sample.row, a.station_m)) << "row " << sample.row << " s " << a.station_m;
    const auto [distance_m, surface] = SurfaceDistance(world, sample.position_m);
    ASSERT_LT(distance_m, kOnSurface_m) << "row " << sample.row << " s " << a.station_m;
    ASSERT_EQ(surface, sample.surface);
    const Eigen::Vector2d n = world.ReferenceNormal(a.station_m);
    switch (sample.surface) {
      case SurveySurface::kLeftFace:
      case SurveySurface::kRightFace: {  // horizontal, outward, perpendicular to the face curve
        const double side = sample.surface == SurveySurface::kLeftFace ? 1.0 : -1.0;
        const auto face = [&](double s) {
          const double w = side > 0 ? world.LeftHalfWidth(sample.row, s) : world.RightHalfWidth(sample.row, s);
          return Eigen::Vector2d(world.RowCentre(sample.row, s) + side * w * world.ReferenceNormal(s));
        };
        const Eigen::Vector2d tangent = (face(a.station_m + 1e-6) - face(a.station_m - 1e-6)).normalized();
        ASSERT_NEAR(sample.normal.z(), 0.0, 1e-12);
        ASSERT_NEAR(sample.normal.head<2>().dot(tangent), 0.0, 1e-6);
        ASSERT_GT(side * sample.normal.head<2>().dot(n), 0.5);
        break;
      }
      case SurveySurface::kTop: {  // upward, perpendicular to the top along and across the row
        const double u = a.offset_m - sample.row * world.params().row_spacing_m;
        const auto top = [&](double s) {
          const Eigen::Vector2d q = world.RowCentre(sample.row, s) + u * world.ReferenceNormal(s);
          return Eigen::Vector3d(q.x(), q.y(), world.terrain().HeightAt(q) + world.BandTop(sample.row, s));
        };
        const Eigen::Vector3d along = (top(a.station_m + 1e-6) - top(a.station_m - 1e-6)).normalized();
        const Eigen::Vector3d across(n.x(), n.y(), world.terrain().GradientAt(xy).dot(n));
        ASSERT_GT(sample.normal.z(), 0.9);
        ASSERT_NEAR(sample.normal.dot(along), 0.0, 1e-6);
        ASSERT_NEAR(sample.normal.dot(across.normalized()), 0.0, 1e-9);
        break;
      }
      default:
        ASSERT_NEAR(std::abs(sample.normal.head<2>().dot(n)), 0.0, 1e-12);
        break;
    }
  }
  for (SurveySurface s : {SurveySurface::kLeftFace, SurveySurface::kRightFace, SurveySurface::kTop,
                          SurveySurface::kEndCap, SurveySurface::kTerrain})
    EXPECT_GT(counts[s], 100) << static_cast<int>(s);
}

TEST(CanopySurfaceSampler, TerrainIsOffByDefault) {
  const RowWorld world(ArcWorld());
  for (const SurveySample& sample : Samples(world, NoiseFree(0.1)))
    ASSERT_NE(sample.surface, SurveySurface::kTerrain);
}

TEST(CanopySurfaceSampler, CountIsTheAreaOverTheSquaredSpacing) {
  const RowWorld box(BoxWorld());
  // Two rows, each: two 20 m x 1.3 m faces, a 20 m x 0.5 m top, two 0.5 m x 1.3 m end caps.
  const double area_m2 = 2.0 * (2.0 * 20.0 * 1.3 + 20.0 * 0.5 + 2.0 * 0.5 * 1.3);
  for (double spacing_m : {0.2, 0.1, 0.05}) {
    SCOPED_TRACE(spacing_m);
    const double count = static_cast<double>(SampleCanopySurface(box, NoiseFree(spacing_m)).size());
    EXPECT_NEAR(count * spacing_m * spacing_m / area_m2, 1.0, 0.01);
  }
  // On curved, rough, gapped rows the count still scales as 1 / spacing^2, and stays below the bound.
  const RowWorld arc(ArcWorld());
  const double coarse = static_cast<double>(SampleCanopySurface(arc, NoiseFree(0.1)).size());
  const double fine = static_cast<double>(SampleCanopySurface(arc, NoiseFree(0.05)).size());
  EXPECT_NEAR(fine / coarse, 4.0, 0.08);
  EXPECT_LE(fine, SurveyPointBound(arc, NoiseFree(0.05)));
  SurveyParams with_terrain = NoiseFree(0.05);
  with_terrain.include_terrain = true;
  EXPECT_LE(static_cast<double>(SampleCanopySurface(arc, with_terrain).size()), SurveyPointBound(arc, with_terrain));
}

TEST(CanopySurfaceSampler, SameSeedSamePointsOtherSeedOtherPoints) {
  const RowWorld world(ArcWorld());
  SurveyParams params;
  params.spacing_m = 0.1;
  params.include_terrain = true;
  params.dropout_fraction = 0.2;
  const auto a = SampleCanopySurface(world, params);
  const auto b = SampleCanopySurface(world, params);
  ASSERT_EQ(a.size(), b.size());
  for (std::size_t i = 0; i < a.size(); ++i) ASSERT_EQ(a[i], b[i]);
  params.seed += 1;
  const auto c = SampleCanopySurface(world, params);
  ASSERT_FALSE(c.empty());
  EXPECT_NE(c.front(), a.front());
}

TEST(CanopySurfaceSampler, NoiseIsGaussianAlongTheNormal) {
  const RowWorld world(ArcWorld());
  constexpr double kSigma_m = 0.01;
  SurveyParams params = NoiseFree(0.05);
  params.include_terrain = true;
  const std::vector<SurveySample> clean = Samples(world, params);
  params.noise_sigma_m = kSigma_m;
  const std::vector<SurveySample> noisy = Samples(world, params);
  ASSERT_EQ(clean.size(), noisy.size());
  const auto n = static_cast<double>(clean.size());
  double sum = 0.0, sum_squares = 0.0;
  for (std::size_t i = 0; i < clean.size(); ++i) {
    const Eigen::Vector3d d = noisy[i].position_m - clean[i].position_m;
    const double offset_m = d.dot(clean[i].normal);
    ASSERT_LT((d - offset_m * clean[i].normal).norm(), 1e-12);  // purely along the normal
    ASSERT_NEAR(offset_m, noisy[i].noise_m, 1e-12);
    sum += offset_m;
    sum_squares += offset_m * offset_m;
  }
  EXPECT_LT(std::abs(sum / n), 4.0 * kSigma_m / std::sqrt(n));
  // sum e^2 / sigma^2 ~ chi-square(n): inside its two-sided 99.9 % band.
  const boost::math::chi_squared chi2(n);
  const double statistic = sum_squares / (kSigma_m * kSigma_m);
  EXPECT_GT(statistic, boost::math::quantile(chi2, 0.0005));
  EXPECT_LT(statistic, boost::math::quantile(chi2, 0.9995));
}

TEST(CanopySurfaceSampler, DropoutKeepsTheConfiguredFractionOfTheSamePoints) {
  const RowWorld world(ArcWorld());
  SurveyParams params = NoiseFree(0.05);
  const auto all = SampleCanopySurface(world, params);
  params.dropout_fraction = 0.3;
  const auto kept = SampleCanopySurface(world, params);
  const auto n = static_cast<double>(all.size());
  EXPECT_NEAR(static_cast<double>(kept.size()) / n, 0.7, 4.0 * std::sqrt(0.3 * 0.7 / n));
  std::size_t j = 0;  // kept is a subsequence of all
  for (std::size_t i = 0; i < all.size() && j < kept.size(); ++i)
    if (all[i] == kept[j]) ++j;
  EXPECT_EQ(j, kept.size());
}

TEST(CanopySurfaceSampler, OneSidedLeavesOutTheRightFacesOnly) {
  const RowWorld world(ArcWorld());
  SurveyParams params = NoiseFree(0.05);
  const auto all = Samples(world, params);
  params.one_sided = true;
  const auto one_sided = Samples(world, params);
  std::size_t right = 0;
  for (const SurveySample& s : all) right += s.surface == SurveySurface::kRightFace ? 1 : 0;
  ASSERT_GT(right, 100U);
  // The other surfaces keep their counts up to the cells at the ends of runs (their positions come
  // from the same random stream, which no longer draws for the right faces).
  EXPECT_NEAR(static_cast<double>(one_sided.size()), static_cast<double>(all.size() - right), 0.001 * all.size());
  for (const SurveySample& s : one_sided) EXPECT_NE(s.surface, SurveySurface::kRightFace);
}

TEST(CanopySurfaceSampler, OutliersAreTheFractionOfKeptPointsInTheGrownBoundingBox) {
  const RowWorld world(ArcWorld());
  SurveyParams params = NoiseFree(0.05);
  params.include_terrain = true;
  const auto clean = Samples(world, params);
  params.outlier_fraction = 0.01;
  const auto noisy = Samples(world, params);
  ASSERT_EQ(noisy.size(), clean.size() + static_cast<std::size_t>(std::llround(0.01 * clean.size())));
  Eigen::Vector3d lo = clean.front().position_m;
  Eigen::Vector3d hi = lo;
  for (const SurveySample& s : clean) {
    lo = lo.cwiseMin(s.position_m);
    hi = hi.cwiseMax(s.position_m);
  }
  std::size_t below_ground = 0;
  for (std::size_t k = 0; k < noisy.size(); ++k) {
    if (k < clean.size()) {
      EXPECT_EQ(noisy[k].position_m, clean[k].position_m);  // the survey itself is unchanged
      continue;
    }
    const SurveySample& s = noisy[k];
    EXPECT_EQ(s.surface, SurveySurface::kOutlier);
    EXPECT_EQ(s.row, -1);
    EXPECT_TRUE((s.position_m.array() >= lo.array() - 1.0).all() && (s.position_m.array() <= hi.array() + 1.0).all());
    below_ground += s.position_m.z() < world.terrain().HeightAt(s.position_m.head<2>()) ? 1 : 0;
  }
  EXPECT_GT(below_ground, 0U);  // the worst case for a terrain model is in the test
}

TEST(CanopySurfaceSampler, RejectsBadParametersNamingTheField) {
  const RowWorld world(BoxWorld());
  const auto expect_error = [&](SurveyParams params, const std::string& field) {
    SCOPED_TRACE(field);
    EXPECT_THAT(SurveyParamsProblem(params).value_or(""), HasSubstr(field));
    try {
      SampleCanopySurface(world, params);
      ADD_FAILURE() << "no exception";
    } catch (const std::invalid_argument& e) {
      EXPECT_THAT(e.what(), HasSubstr(field));
    }
  };
  const double nan = std::numeric_limits<double>::quiet_NaN();
  for (double v : {0.0, -0.1, 11.0, nan}) {
    SurveyParams p;
    p.spacing_m = v;
    expect_error(p, "spacing_m");
  }
  for (double v : {-0.001, 1.5, nan}) {
    SurveyParams p;
    p.noise_sigma_m = v;
    expect_error(p, "noise_sigma_m");
  }
  for (double v : {-0.1, 1.0, nan}) {
    SurveyParams p;
    p.dropout_fraction = v;
    expect_error(p, "dropout_fraction");
  }
  for (double v : {0.0, 101.0, nan}) {
    SurveyParams p;
    p.terrain_spacing_m = v;
    expect_error(p, "terrain_spacing_m");
  }
  for (double v : {-0.01, 0.51, nan}) {
    SurveyParams p;
    p.outlier_fraction = v;
    expect_error(p, "outlier_fraction");
  }
  EXPECT_FALSE(SurveyParamsProblem(SurveyParams{}).has_value());
}

TEST(CanopySurfaceSampler, RefusesMoreThanTheCapOfPoints) {
  RowWorldParams p = BoxWorld();
  p.row_count = 100;
  p.row_length_m = 1000.0;
  const RowWorld world(p);
  SurveyParams params;
  params.spacing_m = 0.01;  // ~ 3e5 m^2 / 1e-4 m^2 = 3e9 points
  EXPECT_GT(SurveyPointBound(world, params), kMaxSurveyPoints);
  try {
    SampleCanopySurface(world, params);
    FAIL() << "no exception";
  } catch (const std::invalid_argument& e) {
    EXPECT_THAT(e.what(), HasSubstr("limit"));
    EXPECT_THAT(e.what(), HasSubstr("spacing_m"));
  }
}

}  // namespace
}  // namespace rowloc::sim
