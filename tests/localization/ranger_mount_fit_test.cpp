// The ranger mount fit (ranger_mount_fit.hpp) on exact synthetic data: a drive along a straight
// lane whose reference trajectory is off by a slowly varying error (as GNSS leaves it), echoes
// computed from the true mounts; the fit must find the one mount that is off and no other, and its
// mount Jacobian must match central differences of the range model.
#include "rowloc/localization/ranger_mount_fit.hpp"
#include "synthetic_row_drive.hpp"

#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include <cmath>

namespace rowloc::localization {
namespace {

using ::testing::HasSubstr;
using test::kCone;
using test::Rangers;
using test::StraightRows;
using test::SyntheticDrive;

const RangerMountEstimate& Ranger(const RangerMountFit& fit, const std::string& name) {
  for (const RangerMountEstimate& r : fit.rangers) {
    if (r.name == name) return r;
  }
  throw std::out_of_range(name);
}

/// The drive's reference with or without the body rates: the motion dead-reckoned from them (a
/// filtered reference) or the reference's own displacement (a smoothed one).
std::vector<ReferenceKnot> Reference(const SyntheticDrive& drive, bool with_rates) {
  std::vector<ReferenceKnot> knots = drive.reference;
  if (!with_rates) {
    for (ReferenceKnot& k : knots) k.body_rates.reset();
  }
  return knots;
}

TEST(RangerMountFit, FindsTheOneMountThatIsOffAndNoOther) {
  const geometry::RowMap map = StraightRows();
  const RowMapRanging ranging(map, map.origin, 2.0);
  const SyntheticDrive drive = test::Drive(ranging, Rangers());
  std::vector<mapio::SensorMount> configured = Rangers();
  configured[0].position_m.y() = 0.55;  // written 5 cm further out than it is
  for (const bool with_rates : {false, true}) {
    SCOPED_TRACE(with_rates ? "dead-reckoned motion" : "the reference's displacement");
    const RangerMountFit fit =
        FitRangerMounts(ranging, configured, kCone, 4.0, Reference(drive, with_rates), drive.echoes);
    ASSERT_EQ(fit.rangers.size(), 4u);
    // Within 2.5 mm, not exactly: the front pair's split (front left vs front right) rests on the
    // kinematics alone (a heading error drifts across at v dphi, against a walk of q_p sqrt(t): 2 mrad
    // takes about 100 s to show), and this drive is 92 s.
    EXPECT_NEAR(Ranger(fit, "us_front_left").along_beam_m, -0.05, 0.0025);
    EXPECT_NEAR(Ranger(fit, "us_front_left").lever_arm_m.y(), 0.50, 0.0025);
    for (const char* name : {"us_rear_left", "us_front_right", "us_rear_right"}) {
      SCOPED_TRACE(name);
      EXPECT_NEAR(Ranger(fit, name).along_beam_m, 0.0, 0.0025);
    }
    for (const RangerMountEstimate& r : fit.rangers) {
      EXPECT_TRUE(r.calibrated);
      EXPECT_EQ(r.echoes_used, r.echoes);  // exact echoes: all associated
      EXPECT_LT(r.rms_after_m, 0.001);
    }
    EXPECT_GT(Ranger(fit, "us_front_left").rms_before_m, 0.04);
    // The reference's 5 cm across error was taken out by the pose corrections.
    EXPECT_GT(fit.position_correction_rms_m, 0.04);
  }
}

TEST(RangerMountFit, ExactMountsAndExactReferenceGiveNoCorrection) {
  const geometry::RowMap map = StraightRows();
  const RowMapRanging ranging(map, map.origin, 2.0);
  SyntheticDrive drive = test::Drive(ranging, Rangers());
  // The reference without its error.
  for (ReferenceKnot& knot : drive.reference) knot.pose -= test::ReferenceError(knot.time_s);
  const RangerMountFit fit = FitRangerMounts(ranging, Rangers(), kCone, 4.0, drive.reference, drive.echoes);
  for (const RangerMountEstimate& r : fit.rangers) {
    EXPECT_NEAR(r.along_beam_m, 0.0, 1e-4);
    EXPECT_EQ(r.lever_arm_m, r.lever_arm_m);  // finite
  }
  EXPECT_NEAR(fit.common_along_beam_m, 0.0, 1e-4);
}

TEST(RangerMountFit, RefusesBadInputWithAReason) {
  const geometry::RowMap map = StraightRows();
  const RowMapRanging ranging(map, map.origin, 2.0);
  const SyntheticDrive drive = test::Drive(ranging, Rangers());
  const std::vector<ReferenceKnot> one(drive.reference.begin(), drive.reference.begin() + 1);
  EXPECT_THROW(FitRangerMounts(ranging, Rangers(), kCone, 4.0, one, drive.echoes), RangerMountFitError);
  EXPECT_THROW(FitRangerMounts(ranging, {}, kCone, 4.0, drive.reference, drive.echoes), RangerMountFitError);
  std::vector<EchoRecord> stray = drive.echoes;
  stray.push_back({1.0, 7, 1.0});
  EXPECT_THROW(FitRangerMounts(ranging, Rangers(), kCone, 4.0, drive.reference, stray), std::invalid_argument);
  RangerMountFitConfig config;
  config.range_sigma_m = std::nan("");
  try {
    (void)FitRangerMounts(ranging, Rangers(), kCone, 4.0, drive.reference, drive.echoes, config);
    FAIL() << "a NaN sigma was accepted";
  } catch (const RangerMountFitError& e) {
    EXPECT_THAT(e.what(), HasSubstr("range_sigma_m must be positive and finite"));
  }
  // Echoes 1 m longer than any row: none associates; the map is not of this field.
  std::vector<EchoRecord> far = drive.echoes;
  for (EchoRecord& e : far) e.range_m += 1.0;
  try {
    (void)FitRangerMounts(ranging, Rangers(), kCone, 4.0, drive.reference, far);
    FAIL() << "echoes that meet no row were accepted";
  } catch (const RangerMountFitError& e) {
    EXPECT_THAT(e.what(), HasSubstr("not of this field"));
  }
}

TEST(RangerMountFit, MountJacobianMatchesCentralDifferencesOfTheRangeModel) {
  const geometry::RowMap map = StraightRows();
  const RowMapRanging ranging(map, map.origin, 2.0);
  const double h = 1e-6;
  // Inside the lane, straight and turned: perpendicular (|phi| below the cone's half aperture) and
  // cone-edge geometries (0.3 rad), for each of the four mounts, along and across each beam.
  for (const double phi : {0.0, 0.05, 0.3, -0.3}) {
    const Eigen::Vector3d pose(20.0, 1.25, phi);
    for (const mapio::SensorMount& m : Rangers()) {
      SCOPED_TRACE(m.name + " phi " + std::to_string(phi));
      const RangeSensorMount mount{m.position_m.head<2>(), m.yaw_rad, kCone};
      const auto range = [&](const Eigen::Vector2d& lever_arm) {
        auto moved = mount;
        moved.lever_arm_m = lever_arm;
        const auto candidates = ranging.Candidates(pose, moved, 4.0, 0.01);
        EXPECT_FALSE(candidates.empty());
        return candidates.empty() ? std::nan("") : candidates.front().predicted_range_m;
      };
      const auto at = ranging.Candidates(pose, mount, 4.0, 0.01);
      ASSERT_FALSE(at.empty());
      const Eigen::RowVector2d jacobian = MountRangeJacobian(at.front().jacobian, phi, m.yaw_rad);
      const Eigen::Vector2d beam(std::cos(m.yaw_rad), std::sin(m.yaw_rad));
      const Eigen::Vector2d across(-beam.y(), beam.x());
      for (int k = 0; k < 2; ++k) {
        const Eigen::Vector2d step = h * (k == 0 ? beam : across);
        const double numeric = (range(mount.lever_arm_m + step) - range(mount.lever_arm_m - step)) / (2.0 * h);
        EXPECT_NEAR(jacobian[k], numeric, 1e-6);
      }
      // The normal inside the cone: the echo comes back along the normal, so a step along the beam
      // shortens the range by cos(angle between beam and normal) = cos(phi) here.
      if (std::abs(phi) < 0.1) {
        EXPECT_NEAR(jacobian[0], -std::cos(phi), 1e-9);
      }
    }
  }
}

}  // namespace
}  // namespace rowloc::localization
