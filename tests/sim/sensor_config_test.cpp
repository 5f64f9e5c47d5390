// Sensor profile files: the shipped file equals the in-code defaults; missing keys, wrong types,
// unknown keys and out-of-range values give errors naming the file, the key and the reason.
#include "rowloc/sim/sensor_config.hpp"

#include "test_support.hpp"

#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include <fstream>
#include <sstream>
#include <string>

namespace rowloc::sim {
namespace {

using ::testing::AllOf;
using ::testing::HasSubstr;

std::filesystem::path ShippedFile() { return rowloc::test::SourceDir() / "config" / "sensors.json"; }

std::string ShippedText() {
  std::ifstream in(ShippedFile());
  std::ostringstream text;
  text << in.rdbuf();
  return text.str();
}

/// The shipped text with the first occurrence of `from` replaced by `to` (which must exist).
std::string Edited(const std::string& from, const std::string& to) {
  std::string text = ShippedText();
  const auto at = text.find(from);
  EXPECT_NE(at, std::string::npos) << from;
  if (at != std::string::npos) text.replace(at, from.size(), to);
  return text;
}

/// The message of the SensorConfigError thrown when parsing text ("" if none was thrown).
std::string ErrorOf(const std::string& text) {
  try {
    ParseSensorProfiles(text, "edited.json");
  } catch (const SensorConfigError& e) {
    return e.what();
  }
  return "";
}

TEST(SensorConfig, ShippedFileEqualsInCodeDefaults) {
  const SensorProfiles loaded = LoadSensorProfiles(ShippedFile());
  EXPECT_EQ(loaded, DefaultSensorProfiles());
  EXPECT_EQ(FindGnssProfile(loaded, "gnss_rtk"), DefaultGnssRtkConfig());
  EXPECT_EQ(FindGnssProfile(loaded, "gnss_sbas"), DefaultGnssSbasConfig());
  EXPECT_EQ(FindImuProfile(loaded, "imu_mems"), DefaultImuConfig());
  EXPECT_EQ(FindWheelEncoderProfile(loaded, "wheel_encoder_1024"), DefaultWheelEncoderConfig());
  EXPECT_EQ(FindWheelEncoderProfile(loaded, "wheel_encoder_white"), WhiteWheelEncoderConfig());
  EXPECT_EQ(FindSteeringEncoderProfile(loaded, "steering_encoder_12bit"), DefaultSteeringEncoderConfig());
}

TEST(SensorConfig, ProfilesHaveTheIssueSigmas) {
  EXPECT_EQ(DefaultGnssRtkConfig().sigma_horizontal_m, 0.01);
  EXPECT_EQ(DefaultGnssRtkConfig().nominal_fix, formats::GnssFixQuality::kRtkFixed);
  EXPECT_EQ(DefaultGnssSbasConfig().sigma_horizontal_m, 0.6);
  EXPECT_EQ(DefaultGnssSbasConfig().nominal_fix, formats::GnssFixQuality::kSbas);
}

TEST(SensorConfig, EveryShippedProfileBuildsItsModel) {
  const SensorProfiles p = DefaultSensorProfiles();
  for (const auto& [name, c] : p.gnss) EXPECT_NO_THROW(GnssModel(c, 1)) << name;
  for (const auto& [name, c] : p.imu) EXPECT_NO_THROW(ImuModel(c, 1)) << name;
  for (const auto& [name, c] : p.wheel_encoder) EXPECT_NO_THROW(WheelEncoderModel(c, 1)) << name;
  for (const auto& [name, c] : p.steering_encoder) EXPECT_NO_THROW(SteeringEncoderModel(c, 1)) << name;
}

TEST(SensorConfig, MissingKeyIsNamed) {
  EXPECT_THAT(ErrorOf(Edited("\"sigma_vertical_m\": 0.02,", "")),
              AllOf(HasSubstr("edited.json"), HasSubstr("gnss.gnss_rtk.sigma_vertical_m"), HasSubstr("missing key")));
  EXPECT_THAT(ErrorOf(Edited(", \"mean_duration_s\": 5.0 ", "")),
              AllOf(HasSubstr("gnss.gnss_rtk.dropout.mean_duration_s"), HasSubstr("missing key")));
  EXPECT_THAT(ErrorOf(Edited("\"imu\":", "\"imus\":")), AllOf(HasSubstr("imu"), HasSubstr("missing key")));
}

TEST(SensorConfig, WrongTypeIsNamed) {
  EXPECT_THAT(ErrorOf(Edited("\"rate_hz\": 10.0", "\"rate_hz\": \"ten\"")),
              AllOf(HasSubstr("gnss.gnss_rtk.rate_hz"), HasSubstr("must be a number"), HasSubstr("string")));
  EXPECT_THAT(ErrorOf(Edited("\"nominal_fix\": \"sbas\"", "\"nominal_fix\": 2")),
              AllOf(HasSubstr("gnss.gnss_sbas.nominal_fix"), HasSubstr("must be a string")));
  EXPECT_THAT(ErrorOf(Edited("\"accel_y\": {", "\"accel_y\": 3, \"unused\": {")),
              AllOf(HasSubstr("imu.imu_mems.accel_y"), HasSubstr("must be an object")));
  EXPECT_THAT(ErrorOf("[1, 2]"), HasSubstr("must be an object"));
}

TEST(SensorConfig, OutOfRangeValuesAreRejected) {
  EXPECT_THAT(ErrorOf(Edited("\"sigma_horizontal_m\": 0.6", "\"sigma_horizontal_m\": -0.6")),
              AllOf(HasSubstr("gnss.gnss_sbas"), HasSubstr("sigma_horizontal_m must be finite and >= 0")));
  EXPECT_THAT(ErrorOf(Edited("\"noise_density\": 0.0002", "\"noise_density\": -0.0002")),
              AllOf(HasSubstr("imu.imu_mems"), HasSubstr("gyro_z.noise_density")));
  EXPECT_THAT(ErrorOf(Edited("\"ticks_per_revolution\": 1024.0", "\"ticks_per_revolution\": 0")),
              AllOf(HasSubstr("wheel_encoder.wheel_encoder_1024"), HasSubstr("ticks_per_revolution")));
  EXPECT_THAT(ErrorOf(Edited("\"noise_sigma_rad\": 0.0005", "\"noise_sigma_rad\": -1")),
              AllOf(HasSubstr("steering_encoder.steering_encoder_12bit"), HasSubstr("noise_sigma_rad")));
  EXPECT_THAT(ErrorOf(Edited("\"nominal_fix\": \"rtk_fixed\"", "\"nominal_fix\": \"rtk\"")),
              AllOf(HasSubstr("gnss.gnss_rtk.nominal_fix"), HasSubstr("must be one of")));
}

TEST(SensorConfig, UnknownKeysAreRejected) {
  EXPECT_THAT(ErrorOf(Edited("\"canopy_sigma_gain\": 4.0,", "\"canopy_sigma_gain\": 4.0, \"canopy_gain\": 1,")),
              AllOf(HasSubstr("gnss.gnss_rtk.canopy_gain"), HasSubstr("unknown key")));
  EXPECT_THAT(ErrorOf(Edited("\"initial_bias\": 0.02", "\"initial_bias\": 0.02, \"scale\": 1")),
              AllOf(HasSubstr("imu.imu_mems.accel_x.scale"), HasSubstr("unknown key")));
  EXPECT_THAT(ErrorOf(Edited("\"gnss\":", "\"lidar\": {}, \"gnss\":")),
              AllOf(HasSubstr("lidar"), HasSubstr("unknown key")));
}

TEST(SensorConfig, InvalidJsonAndMissingFileAreClearErrors) {
  EXPECT_THAT(ErrorOf("{ \"gnss\": "), AllOf(HasSubstr("edited.json"), HasSubstr("invalid JSON")));
  EXPECT_THAT(ErrorOf(Edited("\"rate_hz\": 10.0", "\"rate_hz\": 1e999")),
              AllOf(HasSubstr("edited.json"), HasSubstr("invalid JSON")));
  rowloc::test::ScratchDir dir;
  const auto missing = dir / "nonexistent.json";
  try {
    LoadSensorProfiles(missing);
    ADD_FAILURE() << "no error for a missing file";
  } catch (const SensorConfigError& e) {
    EXPECT_THAT(e.what(), AllOf(HasSubstr("nonexistent.json"), HasSubstr("cannot open")));
  }
}

TEST(SensorConfig, LoadsAnEditedFileFromDisk) {
  rowloc::test::ScratchDir dir;
  const auto path = dir / "sensors.json";
  std::ofstream(path) << Edited("\"sigma_horizontal_m\": 0.6", "\"sigma_horizontal_m\": 0.8");
  const SensorProfiles p = LoadSensorProfiles(path);
  EXPECT_EQ(FindGnssProfile(p, "gnss_sbas").sigma_horizontal_m, 0.8);
  EXPECT_EQ(FindGnssProfile(p, "gnss_rtk"), DefaultGnssRtkConfig());
}

TEST(SensorConfig, UnknownProfileNameListsTheKnownOnes) {
  try {
    FindGnssProfile(DefaultSensorProfiles(), "gnss_ppp");
    ADD_FAILURE() << "no error for an unknown profile";
  } catch (const SensorConfigError& e) {
    EXPECT_THAT(e.what(), AllOf(HasSubstr("gnss_ppp"), HasSubstr("gnss_rtk"), HasSubstr("gnss_sbas")));
  }
  EXPECT_THROW(FindImuProfile(DefaultSensorProfiles(), "imu_tactical"), SensorConfigError);
}

}  // namespace
}  // namespace rowloc::sim
