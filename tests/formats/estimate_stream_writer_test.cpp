// Tests of the estimate-stream writer of docs/protocol.md §3 (formats/estimate_stream_writer.hpp):
// the documented lines, what it refuses (writing nothing for it), and a round trip through the
// reader of trajectory_streams.hpp.
#include "rowloc/formats/estimate_stream_writer.hpp"

#include "rowloc/formats/trajectory_streams.hpp"

#include <gmock/gmock.h>
#include "json_lines.hpp"

#include <gtest/gtest.h>
#include <nlohmann/json.hpp>

#include <limits>
#include <sstream>
#include <string>
#include <vector>

namespace rowloc::formats {
namespace {

using nlohmann::json;

std::vector<json> Lines(const std::string& text) { return rowloc::test::ParseJsonLines(text); }

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
}  // namespace rowloc::formats

namespace rowloc::formats {
namespace {

// Issue 26: the estimates name the sensors the filter distrusts (docs/protocol.md §3, sensor_health),
// an optional key the stream's reader skips; a bad state or name is refused, nothing written.
TEST(EstimateLogWriter, SensorHealthIsWrittenPerSensorAndReadersKeepWorking) {
  std::ostringstream out;
  EstimateLogWriter writer(out, "test", "diff", geometry::GeoOrigin{});
  EstimateRecord r;
  r.time_s = 1.0;
  r.heading_rad = 0.1;
  writer.Write(r);  // all sensors ok: no key
  r.time_s = 2.0;
  r.sensor_health = {{"imu", "excluded", "readings identical", 10, 2, 300, 0}, {"gnss", "suspect", "12 of 20 gated", 8, 12, 0, 1}};
  writer.Write(r);
  const std::vector<json> lines = Lines(out.str());
  ASSERT_EQ(lines.size(), 3u);
  EXPECT_FALSE(lines[1].contains("sensor_health"));
  const json& health = lines[2]["sensor_health"];
  EXPECT_EQ(health["imu"]["state"], "excluded");
  EXPECT_EQ(health["imu"]["reason"], "readings identical");
  EXPECT_EQ(health["imu"]["skipped"], 300);
  EXPECT_EQ(health["gnss"]["gated"], 12);
  EXPECT_EQ(health["gnss"]["refused"], 1);
  std::istringstream in(out.str());
  const EstimateStream stream = ParseEstimateStream(in, "health");
  EXPECT_EQ(stream.estimates.size(), 2u);
  const std::string before = out.str();
  r.time_s = 3.0;
  r.sensor_health = {{"imu", "broken", "", 0, 0, 0, 0}};
  EXPECT_THROW(writer.Write(r), std::invalid_argument);
  r.sensor_health = {{"imu", "ok", "", 0, 0, 0, 0}, {"imu", "ok", "", 0, 0, 0, 0}};
  EXPECT_THROW(writer.Write(r), std::invalid_argument);
  r.sensor_health = {{"", "ok", "", 0, 0, 0, 0}};
  EXPECT_THROW(writer.Write(r), std::invalid_argument);
  EXPECT_EQ(out.str(), before);
}

}  // namespace
}  // namespace rowloc::formats
