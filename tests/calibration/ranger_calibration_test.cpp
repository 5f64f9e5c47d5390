// Ranger mount calibration (issue 28): a simulated drive along one lane of the Donati 2021
// vineyard, replayed with a vehicle file whose ranger mounts are off; the calibration must find the
// offsets, leave the right mounts alone, refuse a map of another field, and say why on bad input.
#include "rowloc/calibration/drive_record.hpp"
#include "rowloc/calibration/ranger_calibration.hpp"
#include "one_lane_drive.hpp"
#include "rowloc/sim/row_world.hpp"
#include "rowloc/sim/scenario.hpp"

#include <gmock/gmock.h>
#include <gtest/gtest.h>
#include <nlohmann/json.hpp>

#include <cmath>
#include <fstream>
#include <sstream>

namespace rowloc::calibration {
namespace {

using ::testing::HasSubstr;

using Drive = test::OneLaneDrive;
const Drive& OneLaneDrive() { return test::SimulatedOneLaneDrive(); }
using test::WithRangerMoved;

DriveRecord Record(const std::string& sensors, const mapio::VehicleConfig& vehicle, double knot_interval_s = 0.2) {
  std::istringstream log(sensors);
  return ReadDriveRecord(log, "drive", vehicle, localization::FilterConfig{}, knot_interval_s);
}

RangerMountFit Calibrate(const mapio::VehicleConfig& vehicle, const RangerCalibrationConfig& config = {}) {
  const Drive& drive = OneLaneDrive();
  return CalibrateRangers(Record(drive.sensors, vehicle), drive.map, vehicle, localization::FilterConfig{}, config);
}

const RangerMountEstimate& Ranger(const RangerMountFit& c, const std::string& name) {
  for (const RangerMountEstimate& r : c.rangers) {
    if (r.name == name) return r;
  }
  throw std::out_of_range(name);
}

TEST(RangerCalibration, FindsA5cmMountErrorWithin5mmAndLeavesTheOtherMounts) {
  const mapio::VehicleConfig truth = OneLaneDrive().scenario.vehicle;
  // Configured 5 cm further out than it is: the sensor is 5 cm back along its (+y) beam.
  const RangerMountFit c = Calibrate(WithRangerMoved(truth, "us_front_left", 0.0, 0.05));
  ASSERT_EQ(c.rangers.size(), 4u);
  for (const RangerMountEstimate& r : c.rangers) {
    SCOPED_TRACE(r.name);
    EXPECT_TRUE(r.calibrated);
    EXPECT_GT(r.echoes_used, 500u);
    const double expected = r.name == "us_front_left" ? -0.05 : 0.0;
    EXPECT_NEAR(r.along_beam_m, expected, 0.005);
    EXPECT_EQ(r.across_beam_m, 0.0);  // not estimated by default
    EXPECT_GT(r.along_beam_sigma_m, 0.0);
    EXPECT_LT(r.along_beam_sigma_m, 0.005);
    EXPECT_LT(r.rms_after_m, 0.006);  // 3 mm echo noise: the residuals are white once calibrated
  }
  EXPECT_GT(Ranger(c, "us_front_left").rms_before_m, 0.03);
  // The estimated mount is the simulation's.
  EXPECT_NEAR(Ranger(c, "us_front_left").lever_arm_m.y(), 0.5, 0.005);
  // One ranger off by -5 cm is a mean of -12.5 mm over four.
  EXPECT_NEAR(c.common_along_beam_m, -0.0125, 0.003);
  EXPECT_GT(c.echoes_used, 3500u);
  EXPECT_LT(c.echoes_unassociated, c.echoes_used / 20);
}

TEST(RangerCalibration, RightMountsStayWithin3mm) {
  const RangerMountFit c = Calibrate(OneLaneDrive().scenario.vehicle);
  for (const RangerMountEstimate& r : c.rangers) {
    SCOPED_TRACE(r.name);
    EXPECT_NEAR(r.along_beam_m, 0.0, 0.003);
  }
  EXPECT_NEAR(c.common_along_beam_m, 0.0, 0.002);
  // The reference (GNSS, IMU, odometry without the rangers) was centimetres off; the echoes correct it.
  EXPECT_GT(c.position_correction_rms_m, 0.005);
}

TEST(RangerCalibration, FindsAnInwardErrorOnTheRightSide) {
  // us_rear_right (beam -y) configured at y = -0.45: 5 cm inward; its sensor is 5 cm further along the beam.
  const RangerMountFit c = Calibrate(WithRangerMoved(OneLaneDrive().scenario.vehicle, "us_rear_right", 0.0, 0.05));
  EXPECT_NEAR(Ranger(c, "us_rear_right").along_beam_m, 0.05, 0.005);
  EXPECT_NEAR(Ranger(c, "us_rear_right").lever_arm_m.y(), -0.5, 0.005);
  EXPECT_NEAR(Ranger(c, "us_front_left").along_beam_m, 0.0, 0.005);
}

TEST(RangerCalibration, AcrossTheBeamOnRequestWithItsUncertainty) {
  RangerCalibrationConfig config;
  config.fit.estimate_across_beam = true;
  const RangerMountFit c = Calibrate(OneLaneDrive().scenario.vehicle, config);
  for (const RangerMountEstimate& r : c.rangers) {
    SCOPED_TRACE(r.name);
    EXPECT_NEAR(r.along_beam_m, 0.0, 0.003);
    // Along the rows only row ends inform: weakly observable, but bounded and with a sigma.
    EXPECT_NEAR(r.across_beam_m, 0.0, 0.02);
    EXPECT_GT(r.across_beam_sigma_m, 0.0);
    EXPECT_TRUE(std::isfinite(r.across_beam_sigma_m));
  }
}

TEST(RangerCalibration, RefusesTheMapOfAnotherField) {
  sim::Scenario curved = sim::LoadScenario(test::SourceDir() / "config/scenarios/vineyard-curved-4us.json");
  const sim::RowWorld world(*curved.world);
  const geometry::RowMap other = world.TrueRowMap(1.0, world.StepForTolerance(1e-3));
  const Drive& drive = OneLaneDrive();
  const mapio::VehicleConfig& vehicle = drive.scenario.vehicle;
  try {
    (void)CalibrateRangers(Record(drive.sensors, vehicle), other, vehicle, localization::FilterConfig{});
    FAIL() << "a map of another field was accepted";
  } catch (const RangerCalibrationError& e) {
    EXPECT_THAT(e.what(), HasSubstr("not of this field"));
  }
}

TEST(RangerCalibration, AppliesOnlyCalibratedMountsAndKeepsHeightAndYaw) {
  const mapio::VehicleConfig vehicle = OneLaneDrive().scenario.vehicle;
  RangerMountFit c;
  RangerMountEstimate moved;
  moved.name = "us_front_left";
  moved.calibrated = true;
  moved.lever_arm_m = {0.7, 0.45};
  RangerMountEstimate kept = moved;
  kept.name = "us_rear_left";
  kept.calibrated = false;
  c.rangers = {moved, kept};
  const mapio::VehicleConfig out = ApplyRangerCalibration(vehicle, c);
  EXPECT_EQ(out.ultrasonic[0].position_m, Eigen::Vector3d(0.7, 0.45, vehicle.ultrasonic[0].position_m.z()));
  EXPECT_EQ(out.ultrasonic[0].yaw_rad, vehicle.ultrasonic[0].yaw_rad);
  EXPECT_EQ(out.ultrasonic[1], vehicle.ultrasonic[1]);
}

TEST(DriveRecord, HoldsEveryEchoAndASmoothedReference) {
  const Drive& drive = OneLaneDrive();
  const DriveRecord record = Record(drive.sensors, drive.scenario.vehicle);
  std::size_t echoes = 0, silent = 0;
  std::istringstream lines(drive.sensors);
  for (std::string line; std::getline(lines, line);) {
    if (line.find("\"type\":\"ultrasonic\"") == std::string::npos) continue;
    (line.find("\"range_m\":null") == std::string::npos ? echoes : silent) += 1;
  }
  EXPECT_EQ(record.echoes.size(), echoes);
  EXPECT_EQ(record.pings_without_echo, silent);
  EXPECT_EQ(record.refused_messages, 0u);
  ASSERT_GT(record.knots.size(), 400u);
  for (std::size_t k = 1; k < record.knots.size(); ++k) {
    EXPECT_GE(record.knots[k].time_s - record.knots[k - 1].time_s, 0.2 - 1e-9);
  }
  for (std::size_t j = 1; j < record.echoes.size(); ++j) EXPECT_GE(record.echoes[j].time_s, record.echoes[j - 1].time_s);
}

TEST(DriveRecord, RefusesWhatCannotBeCalibratedWithAReason) {
  const Drive& drive = OneLaneDrive();
  const mapio::VehicleConfig& vehicle = drive.scenario.vehicle;
  const auto message = [&](const std::string& sensors, const mapio::VehicleConfig& v, double knot_s = 0.2) {
    try {
      (void)Record(sensors, v, knot_s);
    } catch (const DriveRecordError& e) {
      return std::string(e.what());
    }
    return std::string("(accepted)");
  };
  EXPECT_THAT(message(drive.sensors, mapio::AgrimaroSwerveConfig()), HasSubstr("no ultrasonic sensor"));
  EXPECT_THAT(message(drive.sensors, vehicle, 0.0), HasSubstr("knot_interval_s"));
  EXPECT_THAT(message(drive.sensors, vehicle, std::nan("")), HasSubstr("knot_interval_s"));
  mapio::VehicleConfig renamed = vehicle;
  renamed.ultrasonic[2].name = "us_somewhere_else";
  EXPECT_THAT(message(drive.sensors, renamed), HasSubstr("'us_front_right' is not in the vehicle file"));
  // The first 2000 lines: about 5 s, before the GNSS baseline initialises the filter.
  std::istringstream all(drive.sensors);
  std::string head, without_echoes, line;
  for (int i = 0; i < 2000 && std::getline(all, line); ++i) head += line + "\n";
  EXPECT_THAT(message(head, vehicle), HasSubstr("never initialised"));
  std::istringstream again(drive.sensors);
  while (std::getline(again, line)) {
    if (line.find("\"type\":\"ultrasonic\"") == std::string::npos) without_echoes += line + "\n";
  }
  EXPECT_THAT(message(without_echoes, vehicle), HasSubstr("no ultrasonic echo"));
}

TEST(DriveRecord, AMalformedLineIsCountedAndTheRestUsed) {
  const Drive& drive = OneLaneDrive();
  std::string sensors = drive.sensors;
  const std::size_t second_line = sensors.find('\n') + 1;
  sensors.insert(second_line, "{\"type\":\"gps\",\"t\":\"soon\"}\n");
  const DriveRecord record = Record(sensors, drive.scenario.vehicle);
  EXPECT_EQ(record.refused_messages, 1u);
  EXPECT_EQ(record.echoes.size(), Record(drive.sensors, drive.scenario.vehicle).echoes.size());
}

TEST(RangerCalibrationConfig, OverlayOnTheDefaultsWithClearErrors) {
  const RangerCalibrationConfig defaults;
  const RangerCalibrationConfig c =
      ParseRangerCalibrationConfig(R"({"range_sigma_m": 0.01, "estimate_across_beam": true})", "cal.json");
  EXPECT_EQ(c.fit.range_sigma_m, 0.01);
  EXPECT_TRUE(c.fit.estimate_across_beam);
  EXPECT_EQ(c.knot_interval_s, defaults.knot_interval_s);
  const auto error = [](const std::string& text) {
    try {
      (void)ParseRangerCalibrationConfig(text, "cal.json");
    } catch (const RangerCalibrationError& e) {
      return std::string(e.what());
    }
    return std::string("(accepted)");
  };
  EXPECT_THAT(error(R"({"range_sigma": 0.01})"), HasSubstr("cal.json: range_sigma: unknown key (known: knot_interval_s"));
  EXPECT_THAT(error(R"({"range_sigma_m": "small"})"), HasSubstr("range_sigma_m: a number is expected"));
  EXPECT_THAT(error(R"({"range_sigma_m": -1})"), HasSubstr("range_sigma_m must be positive"));
  EXPECT_THAT(error(R"({"outer_iterations": 0})"), HasSubstr("outer_iterations must be from 1"));
  EXPECT_THAT(error(R"({"outer_iterations": 1.5})"), HasSubstr("an integer is expected"));
  EXPECT_THAT(error(R"({"min_echoes_per_ranger": -3})"), HasSubstr("non-negative integer"));
  EXPECT_THAT(error(R"({"refined_gate_m": 0.5})"), HasSubstr("refined_gate_m must not exceed"));
  EXPECT_THAT(error(R"({"estimate_across_beam": 1})"), HasSubstr("true or false"));
  EXPECT_THAT(error(R"({"min_associated_fraction": 2})"), HasSubstr("from 0 to 1"));
  EXPECT_THAT(error("[1, 2]"), HasSubstr("a JSON object is expected"));
  EXPECT_THAT(error("{"), HasSubstr("cal.json: not JSON"));
  EXPECT_THROW(CalibrateRangers({}, {}, OneLaneDrive().scenario.vehicle, {}, RangerCalibrationConfig{.knot_interval_s = 0, .fit = {}}),
               RangerCalibrationError);
}

}  // namespace
}  // namespace rowloc::calibration
