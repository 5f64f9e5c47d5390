// LocalFrame: ENU axes and scale against the WGS84 radii of curvature (independent formulas),
// exact inversion, and rejection of invalid input.
#include "rowloc/mapio/local_frame.hpp"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <limits>
#include <random>
#include <stdexcept>

namespace rowloc::mapio {
namespace {

using geometry::GeoOrigin;

constexpr double kPi = 3.14159265358979323846;
constexpr double kDegToRad = kPi / 180.0;
// WGS84 defining constants.
constexpr double kA = 6378137.0;
constexpr double kF = 1.0 / 298.257223563;
constexpr double kE2 = kF * (2.0 - kF);

/// Meridian radius of curvature M(lat) = a (1 - e^2) / (1 - e^2 sin^2 lat)^(3/2).
double MeridianRadius(double latitude_deg) {
  const double s = std::sin(latitude_deg * kDegToRad);
  return kA * (1.0 - kE2) / std::pow(1.0 - kE2 * s * s, 1.5);
}
/// Prime vertical radius of curvature N(lat) = a / sqrt(1 - e^2 sin^2 lat).
double PrimeVerticalRadius(double latitude_deg) {
  const double s = std::sin(latitude_deg * kDegToRad);
  return kA / std::sqrt(1.0 - kE2 * s * s);
}

const GeoOrigin kTurin{45.0703, 7.6869, 240.0};

TEST(LocalFrame, OriginMapsToZero) {
  const LocalFrame frame(kTurin);
  const Eigen::Vector3d enu = frame.ToEnu(kTurin.latitude_deg, kTurin.longitude_deg, kTurin.altitude_m);
  EXPECT_NEAR(enu.norm(), 0.0, 1e-9);
  EXPECT_EQ(frame.origin().latitude_deg, kTurin.latitude_deg);
  EXPECT_EQ(frame.origin().longitude_deg, kTurin.longitude_deg);
  EXPECT_EQ(frame.origin().altitude_m, kTurin.altitude_m);
}

TEST(LocalFrame, NorthIsPlusYWithMeridianScale) {
  const LocalFrame frame(kTurin);
  const double dlat_deg = 1e-3;
  const Eigen::Vector3d enu = frame.ToEnu(kTurin.latitude_deg + dlat_deg, kTurin.longitude_deg, kTurin.altitude_m);
  // Arc length along the meridian, with M at the mid latitude (error ~1e-8 m over 111 m).
  const double expected_north_m = (MeridianRadius(kTurin.latitude_deg + 0.5 * dlat_deg) + kTurin.altitude_m) *
                                  dlat_deg * kDegToRad;
  EXPECT_NEAR(expected_north_m, 111.13, 0.05);  // the textbook "111 m per millidegree of latitude"
  EXPECT_NEAR(enu.y(), expected_north_m, 1e-5);
  EXPECT_NEAR(enu.x(), 0.0, 1e-9);
  // The ellipsoid curves below the tangent plane: z = -d^2 / (2 M).
  EXPECT_NEAR(enu.z(), -expected_north_m * expected_north_m / (2.0 * MeridianRadius(kTurin.latitude_deg)), 1e-6);
}

TEST(LocalFrame, EastIsPlusXWithParallelScale) {
  const LocalFrame frame(kTurin);
  const double dlon_deg = 1e-3;
  const Eigen::Vector3d enu = frame.ToEnu(kTurin.latitude_deg, kTurin.longitude_deg + dlon_deg, kTurin.altitude_m);
  const double parallel_radius_m =
      (PrimeVerticalRadius(kTurin.latitude_deg) + kTurin.altitude_m) * std::cos(kTurin.latitude_deg * kDegToRad);
  EXPECT_NEAR(enu.x(), parallel_radius_m * dlon_deg * kDegToRad, 1e-5);
  EXPECT_GT(enu.y(), 0.0);  // a parallel curves towards the pole in the tangent plane...
  EXPECT_LT(enu.y(), 1e-3);  // ...by a millimetre over 79 m
}

TEST(LocalFrame, UpIsPlusZ) {
  const LocalFrame frame(kTurin);
  const Eigen::Vector3d enu = frame.ToEnu(kTurin.latitude_deg, kTurin.longitude_deg, kTurin.altitude_m + 12.5);
  EXPECT_NEAR(enu.x(), 0.0, 1e-9);
  EXPECT_NEAR(enu.y(), 0.0, 1e-9);
  EXPECT_NEAR(enu.z(), 12.5, 1e-9);
}

// Property: ToGeodetic inverts ToEnu and vice versa, at origins all over the globe.
TEST(LocalFrame, ToGeodeticInvertsToEnu) {
  const GeoOrigin origins[] = {kTurin, {-33.9, 18.4, 50.0}, {0.0, 0.0, 0.0}, {69.6, 18.9, -20.0},
                               {-10.0, 179.99, 5.0}, {40.0, -179.99, 1000.0}, {89.9, 45.0, 0.0}};
  std::mt19937 rng(20261122);
  std::uniform_real_distribution<double> offset_deg(-0.1, 0.1), altitude_m(-300.0, 300.0);
  for (const GeoOrigin& origin : origins) {
    const LocalFrame frame(origin);
    for (int i = 0; i < 200; ++i) {
      const double lat = std::clamp(origin.latitude_deg + offset_deg(rng), -90.0, 90.0);
      double lon = origin.longitude_deg + offset_deg(rng);
      if (lon > 180.0) lon -= 360.0;
      if (lon < -180.0) lon += 360.0;
      const double alt = origin.altitude_m + altitude_m(rng);
      const GeoOrigin back = frame.ToGeodetic(frame.ToEnu(lat, lon, alt));
      EXPECT_NEAR(back.latitude_deg, lat, 1e-11);
      if (std::abs(lat) < 89.99) {
        EXPECT_NEAR(back.longitude_deg, lon, 1e-9);
      }
      EXPECT_NEAR(back.altitude_m, alt, 1e-6);

      const Eigen::Vector3d enu(offset_deg(rng) * 1e5, offset_deg(rng) * 1e5, altitude_m(rng));
      const GeoOrigin g = frame.ToGeodetic(enu);
      EXPECT_LE(std::abs(g.longitude_deg), 180.0);
      EXPECT_NEAR((frame.ToEnu(g.latitude_deg, g.longitude_deg, g.altitude_m) - enu).norm(), 0.0, 1e-7);
    }
  }
}

TEST(LocalFrame, CopiesAreEquivalent) {
  const LocalFrame frame(kTurin);
  const LocalFrame copy = frame;
  EXPECT_EQ(copy.ToEnu(45.08, 7.69, 250.0), frame.ToEnu(45.08, 7.69, 250.0));
}

TEST(LocalFrame, AcceptsBoundaryOrigins) {
  EXPECT_NO_THROW(LocalFrame(GeoOrigin{90.0, 180.0, 0.0}));
  EXPECT_NO_THROW(LocalFrame(GeoOrigin{-90.0, -180.0, -100.0}));
}

TEST(LocalFrame, RejectsInvalidOrigins) {
  const double nan = std::numeric_limits<double>::quiet_NaN();
  const double inf = std::numeric_limits<double>::infinity();
  for (const GeoOrigin& bad : {GeoOrigin{90.0001, 0.0, 0.0}, GeoOrigin{-91.0, 0.0, 0.0}, GeoOrigin{0.0, 180.5, 0.0},
                               GeoOrigin{0.0, -181.0, 0.0}, GeoOrigin{nan, 0.0, 0.0}, GeoOrigin{0.0, nan, 0.0},
                               GeoOrigin{0.0, 0.0, inf}, GeoOrigin{0.0, 0.0, nan}}) {
    EXPECT_THROW(LocalFrame{bad}, std::invalid_argument) << bad.latitude_deg << " " << bad.longitude_deg;
  }
  try {
    LocalFrame{GeoOrigin{95.0, 0.0, 0.0}};
    FAIL() << "no exception";
  } catch (const std::invalid_argument& e) {
    EXPECT_NE(std::string(e.what()).find("latitude 95"), std::string::npos) << e.what();
  }
}

TEST(LocalFrame, RejectsInvalidPositions) {
  const LocalFrame frame(kTurin);
  const double nan = std::numeric_limits<double>::quiet_NaN();
  EXPECT_THROW(frame.ToEnu(91.0, 7.0, 0.0), std::invalid_argument);
  EXPECT_THROW(frame.ToEnu(45.0, 200.0, 0.0), std::invalid_argument);
  EXPECT_THROW(frame.ToEnu(nan, 7.0, 0.0), std::invalid_argument);
  EXPECT_THROW(frame.ToEnu(45.0, 7.0, nan), std::invalid_argument);
  EXPECT_THROW(frame.ToGeodetic(Eigen::Vector3d(0.0, nan, 0.0)), std::invalid_argument);
  EXPECT_THROW(frame.ToGeodetic(Eigen::Vector3d(std::numeric_limits<double>::infinity(), 0.0, 0.0)),
               std::invalid_argument);
}

}  // namespace
}  // namespace rowloc::mapio
