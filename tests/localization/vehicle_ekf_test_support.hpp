// Shared helpers of the VehicleEkf tests (vehicle_ekf_test.cpp, vehicle_ekf_property_test.cpp):
// synthetic drives with exact readings, GNSS fixes, snapshots and the rejection check. Each test
// file includes it once (anonymous namespace: one private copy per test executable).
#pragma once

#include "rowloc/formats/sensor_log_reader.hpp"
#include "rowloc/formats/trajectory_streams.hpp"
#include "rowloc/localization/measurement_models.hpp"
#include "rowloc/localization/vehicle_ekf.hpp"
#include "rowloc/mapio/local_frame.hpp"
#include "rowloc/sim/scenario.hpp"
#include "rowloc/sim/simulation.hpp"
#include "test_support.hpp"

#include <Eigen/Cholesky>
#include <Eigen/Eigenvalues>
#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include <chrono>
#include <cmath>
#include <cstdlib>
#include <cstring>
#include <functional>
#include <iostream>
#include <limits>
#include <map>
#include <numbers>
#include <random>
#include <sstream>


namespace rowloc::localization {
namespace {


using mapio::VehicleConfig;
using ::testing::HasSubstr;
constexpr double kPi = std::numbers::pi;
constexpr double kNaN = std::numeric_limits<double>::quiet_NaN();
constexpr double kInf = std::numeric_limits<double>::infinity();
const geometry::GeoOrigin kOrigin{45.0628, 7.6621, 240.0};

std::vector<std::string> WheelNames(const VehicleConfig& v) {
  std::vector<std::string> names;
  for (const auto& w : v.wheels) names.push_back(w.name);
  return names;
}

[[maybe_unused]] VehicleEkf MakeEkf(const VehicleConfig& v, bool slip_aware = false) {
  FilterConfig config;
  config.slip_aware_odometry.enabled = slip_aware;
  return VehicleEkf(v, config, kOrigin, WheelNames(v));
}

Eigen::Vector2d Rotate(double a, const Eigen::Vector2d& v) {
  return {std::cos(a) * v.x() - std::sin(a) * v.y(), std::sin(a) * v.x() + std::cos(a) * v.y()};
}

/// Exact planar pose; the body twist (vx, vy, r) is constant over a segment.
struct Pose { Eigen::Vector2d p{0, 0}; double phi = 0; };
struct Segment { double duration_s, vx, vy, r; };
struct Sample { double t; Pose pose; };

Pose Advance(const Pose& a, const Segment& s, double t) {
  double sc = t, ss = 0.0;  // integrals of cos(r u), sin(r u) over [0, t]
  if (std::abs(s.r) > 1e-12) sc = std::sin(s.r * t) / s.r, ss = (1.0 - std::cos(s.r * t)) / s.r;
  const Eigen::Vector2d local(s.vx * sc - s.vy * ss, s.vx * ss + s.vy * sc);
  return {a.p + Rotate(a.phi, local), a.phi + s.r * t};
}

/// Exact imu, steering and wheels readings at time t on a constant-twist segment.
struct Readings { formats::ImuMessage imu; formats::SteeringMessage steering; formats::WheelsMessage wheels; };
Readings Exact(const VehicleConfig& v, const Segment& s, double t) {
  const Eigen::Vector2d l = v.imu.position_m.head<2>();
  Readings r{{t, "imu", -s.r * s.vy - s.r * s.r * l.x(), s.r * s.vx - s.r * s.r * l.y(), s.r}, {t, {}}, {t, {}, {}, {}}};
  for (const auto& w : v.wheels) {
    const Eigen::Vector2d c(s.vx - s.r * w.position_m.y(), s.vy + s.r * w.position_m.x());
    double delta = w.steerable ? std::atan2(c.y(), c.x()) : 0.0, speed = w.steerable ? c.norm() : c.x();
    if (std::abs(delta) > kPi / 2) delta -= std::copysign(kPi, delta), speed = -speed;  // reversing
    r.steering.angle_rad.push_back(w.steerable ? std::optional<double>(delta) : std::nullopt);
    r.wheels.speed_radps.push_back(speed / w.nominal_radius_m);
  }
  return r;
}
bool Steers(const VehicleConfig& v) {
  return v.kind == mapio::VehicleKind::kSwerveDrive || v.kind == mapio::VehicleKind::kFourWheelSteer;
}

formats::GpsMessage Fix(const mapio::LocalFrame& frame, double t, const Eigen::Vector2d& antenna, double sigma) {
  const geometry::GeoOrigin g = frame.ToGeodetic({antenna.x(), antenna.y(), 0.0});
  return {t, "gnss", formats::GnssFixQuality::kRtkFixed,
          formats::GpsPosition{g.latitude_deg, g.longitude_deg, g.altitude_m, sigma, 0.02}};
}

/// Messages of a noisy drive: every 0.01 s imu, steering (steerable vehicles), wheels; a GNSS fix
/// (1 cm RTK noise) every 0.1 s first at each instant. `truth` gets the pose at every fix.
struct Drive {
  std::vector<formats::SensorMessage> messages;
  std::vector<Sample> truth;
};

[[maybe_unused]] Drive MakeDrive(const VehicleConfig& v, Pose pose, const std::vector<Segment>& segments, double t0 = 0.0,
                unsigned seed = 1, bool torque = false) {
  const mapio::LocalFrame frame(kOrigin);
  std::mt19937_64 rng(seed);
  std::normal_distribution<double> n01;
  Drive d;
  long k = 0;
  for (const Segment& s : segments) {
    const Pose start = pose;
    const long steps = std::lround(s.duration_s / 0.01);
    for (long j = 0; j < steps; ++j, ++k) {
      const double t = t0 + 0.01 * static_cast<double>(k);
      pose = Advance(start, s, 0.01 * static_cast<double>(j));
      if (k % 10 == 0) {
        const Eigen::Vector2d noise = 0.01 * Eigen::Vector2d(n01(rng), n01(rng));
        d.messages.push_back(Fix(frame, t, pose.p + Rotate(pose.phi, v.gnss_antenna.position_m.head<2>()) + noise, 0.01));
        d.truth.push_back({t, pose});
      }
      Readings r = Exact(v, s, t);
      r.imu.accel_x_mps2 += 0.01 * n01(rng), r.imu.accel_y_mps2 += 0.01 * n01(rng), r.imu.gyro_z_radps += 5e-4 * n01(rng);
      for (double& w : r.wheels.speed_radps) w += 0.01 * n01(rng);
      if (torque) r.wheels.torque_nm = std::vector<double>(v.wheels.size(), 2.0);
      d.messages.push_back(r.imu);
      if (Steers(v)) d.messages.push_back(r.steering);
      d.messages.push_back(r.wheels);
    }
    pose = Advance(start, s, s.duration_s);
  }
  return d;
}

constexpr double kTickRad = 2.0 * kPi / 1024.0;

/// Adds the encoders' cumulative angles to every wheels message: the integral of the message's
/// speeds over the 0.01 s sample period, counted in whole ticks of 2 pi / 1024.
[[maybe_unused]] void AddWheelAngles(Drive& drive) {
  std::vector<double> rolled;
  for (formats::SensorMessage& m : drive.messages) {
    auto* wheels = std::get_if<formats::WheelsMessage>(&m);
    if (!wheels) continue;
    rolled.resize(wheels->speed_radps.size(), 0.0);
    std::vector<double> angles;
    for (std::size_t i = 0; i < rolled.size(); ++i) {
      rolled[i] += 0.01 * wheels->speed_radps[i];
      angles.push_back(std::floor(rolled[i] / kTickRad) * kTickRad);
    }
    wheels->angle_rad = std::move(angles);
  }
}

[[maybe_unused]] std::vector<Segment> StraightThenCircle() { return {{10.0, 1.0, 0.0, 0.0}, {30.0, 1.0, 0.0, 0.2}}; }

struct Snapshot {
  Eigen::VectorXd x;
  Eigen::MatrixXd p;
  double t;
  bool initialised;
};
Snapshot Snap(const VehicleEkf& e) { return {e.state(), e.covariance(), e.time_s(), e.initialised()}; }
bool BitIdentical(const Snapshot& a, const Snapshot& b) {
  return a.x.size() == b.x.size() && a.p.size() == b.p.size() && a.initialised == b.initialised &&
         std::memcmp(&a.t, &b.t, sizeof(double)) == 0 &&
         std::memcmp(a.x.data(), b.x.data(), sizeof(double) * a.x.size()) == 0 &&
         std::memcmp(a.p.data(), b.p.data(), sizeof(double) * a.p.size()) == 0;
}

/// Requires a FilterInputError naming `field` and an unchanged filter.
[[maybe_unused]] void ExpectRejected(VehicleEkf& ekf, const formats::SensorMessage& m, const std::string& field,
                                     const std::string& what) {
  SCOPED_TRACE(what);
  const Snapshot before = Snap(ekf);
  try {
    ekf.Process(m);
    ADD_FAILURE() << "accepted";
  } catch (const FilterInputError& e) {
    EXPECT_THAT(e.what(), HasSubstr(field));
  } catch (const std::exception& e) {
    ADD_FAILURE() << "wrong exception type: " << e.what();
  }
  EXPECT_TRUE(BitIdentical(before, Snap(ekf)));
}

[[maybe_unused]] double HeadingError(double a, double b) { return std::abs(WrapAngle(a - b)); }

/// The largest position (m) and heading (rad) errors at a drive's fixes from settle_s on.
struct WorstErrors {
  double position_m = 0.0;
  double heading_rad = 0.0;
};
/// Processes every message of `d`; `on_result`, if given, sees each message's result.
[[maybe_unused]] WorstErrors ReplayDrive(VehicleEkf& ekf, const Drive& d, double settle_s,
                                         const std::function<void(const ProcessResult&)>& on_result = {}) {
  WorstErrors worst;
  std::size_t fix = 0;
  for (const formats::SensorMessage& m : d.messages) {
    const ProcessResult r = ekf.Process(m);
    if (on_result) on_result(r);
    if (!std::holds_alternative<formats::GpsMessage>(m)) continue;
    const Sample& truth = d.truth[fix++];
    if (truth.t < settle_s) continue;
    worst.position_m = std::max(worst.position_m, (ekf.state().head<2>() - truth.pose.p).norm());
    worst.heading_rad = std::max(worst.heading_rad, HeadingError(ekf.state()(StateLayout::kPhi), truth.pose.phi));
  }
  return worst;
}

// ---------------------------------------------------------------------------------------------

}  // namespace
}  // namespace rowloc::localization
