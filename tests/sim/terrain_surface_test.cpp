// TerrainSurface: slope plane plus bounded, seeded undulation, with its exact gradient.
#include "rowloc/sim/terrain_surface.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <limits>
#include <stdexcept>

namespace rowloc::sim {
namespace {

TEST(TerrainSurface, FlatByDefault) {
  const TerrainSurface t(TerrainParams{}, 1);
  for (double x = -50; x <= 50; x += 7.3) {
    EXPECT_EQ(t.HeightAt({x, 0.7 * x}), 0.0);
    EXPECT_EQ(t.GradientAt({x, -x}), Eigen::Vector2d::Zero());
  }
}

TEST(TerrainSurface, PlaneHasItsGrades) {
  TerrainParams p;
  p.grade_east = 0.05;
  p.grade_north = -0.12;
  const TerrainSurface t(p, 9);
  EXPECT_NEAR(t.HeightAt({10.0, 5.0}), 0.5 - 0.6, 1e-12);
  EXPECT_NEAR(t.HeightAt({-3.0, 2.0}), -0.15 - 0.24, 1e-12);
  EXPECT_TRUE(t.GradientAt({1.0, 2.0}).isApprox(Eigen::Vector2d(0.05, -0.12), 1e-12));
}

TEST(TerrainSurface, UndulationIsBoundedAndReachesItsScale) {
  TerrainParams p;
  p.grade_east = 0.03;
  p.undulation_amplitude_m = 0.2;
  p.undulation_wavelength_m = 10.0;
  const TerrainSurface t(p, 4);
  double max_abs = 0.0;
  for (double x = 0; x < 100; x += 0.37)
    for (double y = 0; y < 100; y += 0.53) {
      const double undulation = t.HeightAt({x, y}) - 0.03 * x;
      EXPECT_LE(std::abs(undulation), 0.2 + 1e-12);
      max_abs = std::max(max_abs, std::abs(undulation));
    }
  EXPECT_GT(max_abs, 0.1);  // the waves are not all cancelled
}

TEST(TerrainSurface, GradientIsTheDerivative) {
  TerrainParams p;
  p.grade_north = 0.1;
  p.undulation_amplitude_m = 0.3;
  p.undulation_wavelength_m = 5.0;
  p.undulation_components = 5;
  const TerrainSurface t(p, 77);
  const double h = 1e-5;
  for (double x = -20; x < 20; x += 3.1) {
    const Eigen::Vector2d q(x, 0.4 * x + 1.0);
    const Eigen::Vector2d numeric((t.HeightAt(q + Eigen::Vector2d(h, 0)) - t.HeightAt(q - Eigen::Vector2d(h, 0))) / (2 * h),
                                  (t.HeightAt(q + Eigen::Vector2d(0, h)) - t.HeightAt(q - Eigen::Vector2d(0, h))) / (2 * h));
    EXPECT_LT((t.GradientAt(q) - numeric).norm(), 1e-8);
  }
}

TEST(TerrainSurface, SameSeedSameSurfaceOtherSeedOther) {
  TerrainParams p;
  p.undulation_amplitude_m = 0.3;
  const TerrainSurface a(p, 5), b(p, 5), c(p, 6);
  EXPECT_EQ(a.HeightAt({3.0, 4.0}), b.HeightAt({3.0, 4.0}));
  EXPECT_NE(a.HeightAt({3.0, 4.0}), c.HeightAt({3.0, 4.0}));
}

TEST(TerrainSurface, RejectsBadParametersNamingTheField) {
  const auto message = [](TerrainParams p) {
    try {
      TerrainSurface t(p, 1);
    } catch (const std::invalid_argument& e) {
      return std::string(e.what());
    }
    return std::string("no error");
  };
  TerrainParams p;
  p.grade_east = 1.0;
  EXPECT_NE(message(p).find("grade_east"), std::string::npos);
  p = {};
  p.grade_north = std::numeric_limits<double>::quiet_NaN();
  EXPECT_NE(message(p).find("grade_north"), std::string::npos);
  p = {};
  p.undulation_amplitude_m = -0.1;
  EXPECT_NE(message(p).find("undulation_amplitude_m"), std::string::npos);
  p = {};
  p.undulation_wavelength_m = 0.0;
  EXPECT_NE(message(p).find("undulation_wavelength_m"), std::string::npos);
  p = {};
  p.undulation_components = 0;
  EXPECT_NE(message(p).find("undulation_components"), std::string::npos);
}

TEST(TerrainSurface, RejectsNonFinitePositions) {
  const TerrainSurface t(TerrainParams{}, 1);
  const double nan = std::numeric_limits<double>::quiet_NaN();
  EXPECT_THROW(t.HeightAt({nan, 0.0}), std::invalid_argument);
  EXPECT_THROW(t.GradientAt({0.0, INFINITY}), std::invalid_argument);
}

}  // namespace
}  // namespace rowloc::sim
