// Tests of the simulator's sensor-log and truth writers of docs/protocol.md (sim/log_writers.hpp).
#include "rowloc/sim/log_writers.hpp"

#include "json_lines.hpp"

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

formats::LogHeader TwoWheelHeader() {
  formats::LogHeader h;
  h.source = "rowloc simulate";
  h.scenario = "test";
  h.vehicle = "diff";
  h.wheels = {"left", "right"};
  h.ultrasonic = {"us_left"};
  return h;
}

std::vector<json> Lines(const std::string& text) { return rowloc::test::ParseJsonLines(text); }

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
  fix.fix = formats::GnssFixQuality::kRtkFixed;
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
  formats::LogHeader duplicate = TwoWheelHeader();
  duplicate.wheels = {"left", "left"};
  EXPECT_THROW(SensorLogWriter(out, duplicate), std::invalid_argument);
  formats::LogHeader bad_origin = TwoWheelHeader();
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

}  // namespace
}  // namespace rowloc::sim
