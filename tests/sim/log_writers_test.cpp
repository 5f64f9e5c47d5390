// Tests of the NDJSON writers of docs/protocol.md (sim/log_writers.hpp).
#include "rowloc/sim/log_writers.hpp"
#include "rowloc/sim/trajectory_streams.hpp"

#include <gmock/gmock.h>
#include <gtest/gtest.h>
#include <nlohmann/json.hpp>

#include <cmath>
#include <limits>
#include <sstream>
#include <string>
#include <vector>

namespace rowloc::sim {
namespace {

using nlohmann::json;

LogHeader TwoWheelHeader() {
  LogHeader h;
  h.scenario = "test";
  h.vehicle = "diff";
  h.wheels = {"left", "right"};
  h.ultrasonic = {"us_left"};
  return h;
}

std::vector<json> Lines(const std::string& text) {
  std::vector<json> lines;
  std::istringstream in(text);
  std::string line;
  while (std::getline(in, line)) lines.push_back(json::parse(line));
  return lines;
}

TEST(SensorLogWriter, WritesHeaderThenMessagesInDocumentedKeyOrder) {
  std::ostringstream out;
  SensorLogWriter writer(out, TwoWheelHeader());
  writer.Write(ImuMessage{0.01, "imu", 0.1, -0.2, 0.003});
  writer.Write(WheelsMessage{0.02, {{"left", 1.5}, {"right", 1.6}}, {}, {}});
  writer.Write(UltrasonicMessage{0.03, "us_left", std::nullopt});
  writer.Write(UltrasonicMessage{0.04, "us_left", 1.25});
  const std::vector<json> lines = Lines(out.str());
  ASSERT_EQ(lines.size(), 5u);
  EXPECT_EQ(lines[0]["type"], "log_header");
  EXPECT_EQ(lines[0]["protocol"], "rowloc/1");
  EXPECT_EQ(lines[0]["wheels"], json({"left", "right"}));
  EXPECT_EQ(lines[1]["gyro_z_radps"].get<double>(), 0.003);
  EXPECT_EQ(lines[2]["speed_radps"]["right"].get<double>(), 1.6);
  EXPECT_FALSE(lines[2].contains("torque_nm"));
  EXPECT_FALSE(lines[2].contains("angle_rad"));
  EXPECT_TRUE(lines[3]["range_m"].is_null());
  EXPECT_EQ(lines[4]["range_m"].get<double>(), 1.25);
  EXPECT_EQ(writer.messages_written(), 4u);
  // "type" first, "t" second: the documented order, so that logs are easy to grep.
  EXPECT_EQ(out.str().find("{\"type\":\"imu\",\"t\":0.01,"), out.str().find("{\"type\":\"imu\""));
}

TEST(SensorLogWriter, NumbersRoundTripExactly) {
  std::ostringstream out;
  SensorLogWriter writer(out, TwoWheelHeader());
  const double value = 0.1 + 0.2;  // not representable in few digits
  writer.Write(ImuMessage{1.0 / 3.0, "imu", value, std::nextafter(1.0, 2.0), -1e-300});
  const json line = Lines(out.str())[1];
  EXPECT_EQ(line["t"].get<double>(), 1.0 / 3.0);
  EXPECT_EQ(line["accel_x_mps2"].get<double>(), value);
  EXPECT_EQ(line["accel_y_mps2"].get<double>(), std::nextafter(1.0, 2.0));
  EXPECT_EQ(line["gyro_z_radps"].get<double>(), -1e-300);
}

TEST(SensorLogWriter, GpsWithoutFixHasNoPosition) {
  std::ostringstream out;
  SensorLogWriter writer(out, TwoWheelHeader());
  GpsMessage none;
  none.time_s = 1.0;
  writer.Write(none);
  GpsMessage fix;
  fix.time_s = 1.1;
  fix.fix = GnssFixQuality::kRtkFixed;
  fix.latitude_deg = 45.0;
  fix.longitude_deg = 7.0;
  fix.altitude_m = 240.0;
  fix.sigma_horizontal_m = 0.01;
  fix.sigma_vertical_m = 0.02;
  writer.Write(fix);
  const std::vector<json> lines = Lines(out.str());
  EXPECT_EQ(lines[1]["fix"], "none");
  EXPECT_FALSE(lines[1].contains("latitude_deg"));
  EXPECT_EQ(lines[2]["fix"], "rtk_fixed");
  EXPECT_EQ(lines[2]["latitude_deg"].get<double>(), 45.0);
}

TEST(SensorLogWriter, RefusesWhatTheProtocolForbidsAndWritesNothingForIt) {
  std::ostringstream out;
  SensorLogWriter writer(out, TwoWheelHeader());
  writer.Write(ImuMessage{2.0, "imu", 0, 0, 0});
  const std::string before = out.str();
  EXPECT_THROW(writer.Write(ImuMessage{1.0, "imu", 0, 0, 0}), std::invalid_argument);  // time backwards
  EXPECT_THROW(writer.Write(ImuMessage{3.0, "imu", std::nan(""), 0, 0}), std::invalid_argument);
  EXPECT_THROW(writer.Write(ImuMessage{std::numeric_limits<double>::infinity(), "imu", 0, 0, 0}),
               std::invalid_argument);
  EXPECT_THROW(writer.Write(WheelsMessage{3.0, {{"left", 1.0}}, {}, {}}), std::invalid_argument);  // missing wheel
  EXPECT_THROW(writer.Write(WheelsMessage{3.0, {{"left", 1.0}, {"middle", 1.0}}, {}, {}}), std::invalid_argument);
  EXPECT_THROW(writer.Write(WheelsMessage{3.0, {{"left", 1.0}, {"left", 1.0}}, {}, {}}), std::invalid_argument);  // twice
  EXPECT_THROW(writer.Write(WheelsMessage{3.0, {{"left", 1.0}, {"right", 1.0}}, {{"left", 2.0}}, {}}),
               std::invalid_argument);  // torque for only some wheels
  EXPECT_THROW(writer.Write(WheelsMessage{3.0, {{"left", 1.0}, {"right", 1.0}}, {}, {{"right", 2.0}}}),
               std::invalid_argument);  // angles for only some wheels
  EXPECT_THROW(writer.Write(WheelsMessage{3.0, {{"left", 1.0}, {"right", 1.0}}, {}, {{"left", 2.0}, {"right", std::nan("")}}}),
               std::invalid_argument);  // a non-finite angle
  EXPECT_THROW(writer.Write(SteeringMessage{3.0, {{"nose", 0.1}}}), std::invalid_argument);
  EXPECT_THROW(writer.Write(SteeringMessage{3.0, {{"left", 0.1}, {"left", 0.2}}}), std::invalid_argument);
  EXPECT_THROW(writer.Write(UltrasonicMessage{3.0, "us_right", 1.0}), std::invalid_argument);
  EXPECT_THROW(writer.Write(UltrasonicMessage{3.0, "us_left", std::nan("")}), std::invalid_argument);
  EXPECT_EQ(out.str(), before);
  EXPECT_EQ(writer.messages_written(), 1u);
  writer.Write(ImuMessage{2.0, "imu", 0, 0, 0});  // equal time is allowed (non-decreasing)
}

TEST(SensorLogWriter, WritesVisualOdometry) {
  std::ostringstream out;
  SensorLogWriter writer(out, TwoWheelHeader());
  writer.Write(VioMessage{0.5, "camera", 1.0, -0.1, 0.02});
  const json line = Lines(out.str())[1];
  EXPECT_EQ(line["type"], "vio");
  EXPECT_EQ(line["velocity_y_mps"].get<double>(), -0.1);
  EXPECT_EQ(line["sigma_mps"].get<double>(), 0.02);
  EXPECT_THROW(writer.Write(VioMessage{0.6, "camera", std::nan(""), 0.0, 0.02}), std::invalid_argument);
}

TEST(SensorLogWriter, RefusesBadHeaders) {
  std::ostringstream out;
  LogHeader duplicate = TwoWheelHeader();
  duplicate.wheels = {"left", "left"};
  EXPECT_THROW(SensorLogWriter(out, duplicate), std::invalid_argument);
  LogHeader bad_origin = TwoWheelHeader();
  bad_origin.origin.latitude_deg = 91.0;
  EXPECT_THROW(SensorLogWriter(out, bad_origin), std::invalid_argument);
}

TruthRecord TwoWheelTruth(double t) {
  TruthRecord r;
  r.time_s = t;
  r.position_m = {1.0, 2.0, 3.0};
  r.wheels = {{"left", 0.0, 4.0, 0.01, 0.25, 2.0, "grass"}, {"right", 0.0, 4.1, 0.012, 0.25, 2.1, "mud"}};
  return r;
}

TEST(TruthLogWriter, WritesDocumentedRecords) {
  std::ostringstream out;
  TruthLogWriter writer(out, TwoWheelHeader());
  writer.Write(TwoWheelTruth(0.5));
  const std::vector<json> lines = Lines(out.str());
  ASSERT_EQ(lines.size(), 2u);
  EXPECT_EQ(lines[0]["protocol"], "rowloc-truth/1");
  EXPECT_EQ(lines[1]["z_m"].get<double>(), 3.0);
  EXPECT_EQ(lines[1]["wheels"]["right"]["terrain"], "mud");
  EXPECT_EQ(lines[1]["wheels"]["left"]["slip"].get<double>(), 0.01);
  EXPECT_TRUE(lines[1]["gnss_available"].get<bool>());
}

TEST(TruthLogWriter, RefusesWrongWheelsAndBackwardTime) {
  std::ostringstream out;
  TruthLogWriter writer(out, TwoWheelHeader());
  writer.Write(TwoWheelTruth(1.0));
  EXPECT_THROW(writer.Write(TwoWheelTruth(0.5)), std::invalid_argument);
  TruthRecord swapped = TwoWheelTruth(2.0);
  std::swap(swapped.wheels[0], swapped.wheels[1]);
  EXPECT_THROW(writer.Write(swapped), std::invalid_argument);
  TruthRecord missing = TwoWheelTruth(2.0);
  missing.wheels.pop_back();
  EXPECT_THROW(writer.Write(missing), std::invalid_argument);
  TruthRecord nan = TwoWheelTruth(2.0);
  nan.heading_rad = std::nan("");
  EXPECT_THROW(writer.Write(nan), std::invalid_argument);
  EXPECT_EQ(writer.records_written(), 1u);
}

TEST(EstimateLogWriter, WritesCovarianceOfTheGivenDimension) {
  std::ostringstream out;
  EstimateLogWriter writer(out, "test", "diff", geometry::GeoOrigin{});
  EstimateRecord position_only;
  position_only.time_s = 1.0;
  position_only.covariance = Eigen::Matrix3d::Identity() * 0.25;
  writer.Write(position_only);
  EstimateRecord with_heading = position_only;
  with_heading.time_s = 2.0;
  with_heading.heading_rad = 0.5;
  writer.Write(with_heading);
  const std::vector<json> lines = Lines(out.str());
  ASSERT_EQ(lines.size(), 3u);
  EXPECT_EQ(lines[0]["protocol"], "rowloc-estimate/1");
  EXPECT_EQ(lines[1]["covariance_xy_phi"].size(), 4u);
  EXPECT_FALSE(lines[1].contains("phi_rad"));
  EXPECT_EQ(lines[2]["covariance_xy_phi"].size(), 9u);
  EXPECT_EQ(lines[2]["phi_rad"].get<double>(), 0.5);
}

TEST(EstimateLogWriter, RefusesAsymmetricNonFiniteOrIndefiniteCovariance) {
  std::ostringstream out;
  EstimateLogWriter writer(out, "test", "diff", geometry::GeoOrigin{});
  EstimateRecord r;
  r.time_s = 1.0;
  r.heading_rad = 0.0;
  r.covariance = Eigen::Matrix3d::Identity();
  (*r.covariance)(0, 1) = 0.5;
  EXPECT_THROW(writer.Write(r), std::invalid_argument);
  (*r.covariance)(0, 1) = 0.0;
  (*r.covariance)(2, 2) = std::numeric_limits<double>::infinity();
  EXPECT_THROW(writer.Write(r), std::invalid_argument);
  // Symmetric but indefinite (eigenvalues 3 and -1 in the xy block): refused, nothing written.
  const std::string before = out.str();
  r.covariance = Eigen::Matrix3d::Identity();
  (*r.covariance)(0, 1) = (*r.covariance)(1, 0) = 2.0;
  EXPECT_THAT([&] { writer.Write(r); },
              ::testing::ThrowsMessage<std::invalid_argument>(::testing::HasSubstr("not positive semi-definite")));
  EXPECT_EQ(out.str(), before);
  // Semi-definite (a zero heading variance) is accepted.
  r.covariance = Eigen::Vector3d(1.0, 1.0, 0.0).asDiagonal().toDenseMatrix();
  EXPECT_NO_THROW(writer.Write(r));
}

TEST(EstimateLogWriter, SlipAndUpdateLinesRoundTripThroughTheReader) {
  std::ostringstream out;
  EstimateLogWriter writer(out, "test", "diff", geometry::GeoOrigin{});
  UpdateLogRecord u;
  u.time_s = 0.5;
  u.sensor = "gnss";
  u.innovation = Eigen::Vector2d(0.01, -0.02);
  u.innovation_covariance = Eigen::Matrix2d::Identity() * 1e-4;
  u.nis = u.innovation.squaredNorm() / 1e-4;  // S = 1e-4 I
  u.accepted = true;
  writer.WriteUpdate(u);
  EstimateRecord r;
  r.time_s = 0.5;
  r.position_m = Eigen::Vector2d(1.0, 2.0);
  r.slip = {{"left", 0.125}, {"right", -0.05}};
  writer.Write(r);
  std::istringstream in(out.str());
  const EstimateStream stream = ParseEstimateStream(in, "written");
  ASSERT_EQ(stream.updates.size(), 1u);
  EXPECT_EQ(stream.updates[0].sensor, "gnss");
  EXPECT_EQ(stream.updates[0].innovation, u.innovation);
  EXPECT_DOUBLE_EQ(stream.updates[0].nis, u.nis);
  ASSERT_EQ(stream.estimates.size(), 1u);
  EXPECT_DOUBLE_EQ(stream.estimates[0].wheel_slip.at("left"), 0.125);
  EXPECT_DOUBLE_EQ(stream.estimates[0].wheel_slip.at("right"), -0.05);
}

TEST(EstimateLogWriter, WheelCalibrationIsWrittenPerWheelAndBadValuesAreRefused) {
  std::ostringstream out;
  EstimateLogWriter writer(out, "test", "diff", geometry::GeoOrigin{});
  EstimateRecord r;
  r.time_s = 1.0;
  r.wheel_calibration = {{"left", 0.16, 0.002, 1.1, 0.3}, {"right", 0.17, 0.003, 0.9, 0.2}};
  writer.Write(r);
  const std::vector<json> lines = Lines(out.str());
  ASSERT_EQ(lines.size(), 2u);
  const json& c = lines[1].at("wheel_calibration");
  EXPECT_EQ(c.size(), 2u);
  EXPECT_EQ(c.at("left").at("rolling_radius_m").get<double>(), 0.16);
  EXPECT_EQ(c.at("left").at("rolling_radius_sigma_m").get<double>(), 0.002);
  EXPECT_EQ(c.at("right").at("slip_compliance").get<double>(), 0.9);
  EXPECT_EQ(c.at("right").at("slip_compliance_sigma").get<double>(), 0.2);
  std::istringstream in(out.str());
  EXPECT_EQ(ParseEstimateStream(in, "written").estimates.size(), 1u);  // readers skip the key
  const std::string written = out.str();
  const auto refused = [&](WheelCalibrationRecord w, const std::string& reason) {
    EstimateRecord bad = r;
    bad.time_s = 2.0;
    bad.wheel_calibration = {w};
    try {
      writer.Write(bad);
      ADD_FAILURE() << "written: " << reason;
    } catch (const std::invalid_argument& e) {
      EXPECT_NE(std::string(e.what()).find(reason), std::string::npos) << e.what();
    }
  };
  refused({"", 0.16, 0.0, 1.0, 0.0}, "unique and non-empty");
  refused({"left", 0.0, 0.0, 1.0, 0.0}, "'left': rolling_radius_m must be > 0");
  refused({"left", 0.16, -0.001, 1.0, 0.0}, "rolling_radius_sigma_m must be >= 0");
  refused({"left", 0.16, 0.0, -0.1, 0.0}, "slip_compliance must be >= 0");
  refused({"left", 0.16, 0.0, 1.0, std::numeric_limits<double>::quiet_NaN()}, "slip_compliance_sigma");
  EstimateRecord twice = r;
  twice.time_s = 2.0;
  twice.wheel_calibration = {{"left", 0.16, 0.0, 1.0, 0.0}, {"left", 0.16, 0.0, 1.0, 0.0}};
  EXPECT_THROW(writer.Write(twice), std::invalid_argument);
  EXPECT_EQ(out.str(), written);
}

TEST(EstimateLogWriter, RefusesBadUpdatesAndSlipAndWritesNothingForThem) {
  std::ostringstream out;
  EstimateLogWriter writer(out, "test", "diff", geometry::GeoOrigin{});
  UpdateLogRecord u;
  u.time_s = 1.0;
  u.sensor = "imu";
  u.innovation = Eigen::Vector3d(0.1, 0.0, 0.0);
  u.innovation_covariance = Eigen::Matrix3d::Identity();
  u.nis = 0.01;
  const std::string header = out.str();
  UpdateLogRecord bad = u;
  bad.sensor.clear();
  EXPECT_THROW(writer.WriteUpdate(bad), std::invalid_argument);
  bad = u;
  bad.innovation_covariance = Eigen::Matrix2d::Identity();  // 3-vector, 2x2 S
  EXPECT_THROW(writer.WriteUpdate(bad), std::invalid_argument);
  bad = u;
  bad.innovation(1) = std::numeric_limits<double>::quiet_NaN();
  EXPECT_THROW(writer.WriteUpdate(bad), std::invalid_argument);
  bad = u;
  bad.nis = std::numeric_limits<double>::infinity();
  EXPECT_THROW(writer.WriteUpdate(bad), std::invalid_argument);
  EstimateRecord r;
  r.time_s = 1.0;
  r.slip = {{"left", 0.1}, {"left", 0.2}};
  EXPECT_THROW(writer.Write(r), std::invalid_argument);
  r.slip = {{"left", std::numeric_limits<double>::quiet_NaN()}};
  EXPECT_THROW(writer.Write(r), std::invalid_argument);
  EXPECT_EQ(out.str(), header);
  writer.WriteUpdate(u);
  u.time_s = 0.5;  // time going backwards
  EXPECT_THROW(writer.WriteUpdate(u), std::invalid_argument);
}

}  // namespace
}  // namespace rowloc::sim
