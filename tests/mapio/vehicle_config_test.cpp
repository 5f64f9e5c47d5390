#include "rowloc/mapio/vehicle_config.hpp"

#include "test_support.hpp"

#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include <cctype>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <limits>
#include <numbers>
#include <string>

namespace rowloc::mapio {
namespace {

using ::testing::AllOf;
using ::testing::HasSubstr;

std::string ValidJson() {
  return R"({
  "name": "test-4ws", "kind": "four_wheel_steer", "mass_kg": 120.0, "max_steering_angle_rad": 1.0,
  "wheels": [
    {"name": "front_left", "position_m": [0.5, 0.4], "nominal_radius_m": 0.254, "steerable": true},
    {"name": "front_right", "position_m": [0.5, -0.4], "nominal_radius_m": 0.254, "steerable": true},
    {"name": "rear_left", "position_m": [-0.5, 0.4], "nominal_radius_m": 0.254, "steerable": true},
    {"name": "rear_right", "position_m": [-0.5, -0.4], "nominal_radius_m": 0.254, "steerable": true}],
  "tracks": null,
  "gnss_antenna": {"name": "gnss", "position_m": [0.0, 0.0, 1.2], "yaw_rad": 0.0},
  "imu": {"name": "imu", "position_m": [0.0, 0.0, 0.25], "yaw_rad": 0.0},
  "ultrasonic": [{"name": "us_front_left", "position_m": [0.75, 0.5, 0.5], "yaw_rad": 1.5}]})";
}

std::string ValidJsonWith(const std::string& from, const std::string& to) {
  std::string text = ValidJson();
  const auto at = text.find(from);
  EXPECT_NE(at, std::string::npos) << from;
  if (at == std::string::npos) return text;
  return text.replace(at, from.size(), to);
}

/// The error of ParseVehicleConfig (or with `as_vehicle_file`, of ParseVehicleFile) for `text`.
std::string ErrorOf(const std::string& text, const char* as_vehicle_file = nullptr) {
  try {
    if (as_vehicle_file) {
      ParseVehicleFile(text, as_vehicle_file);
    } else {
      ParseVehicleConfig(text, "test.json");
    }
  } catch (const VehicleConfigError& e) {
    return e.what();
  }
  ADD_FAILURE() << "no VehicleConfigError for:\n" << text;
  return "";
}

TEST(VehicleKindName, RoundTripsEveryKind) {
  for (const VehicleKind kind : {VehicleKind::kSwerveDrive, VehicleKind::kFourWheelSteer,
                                 VehicleKind::kDifferentialDrive, VehicleKind::kSkidSteer}) {
    EXPECT_EQ(VehicleKindFromName(VehicleKindName(kind)), kind);
  }
  EXPECT_EQ(VehicleKindName(VehicleKind::kSkidSteer), "skid_steer");
  EXPECT_FALSE(VehicleKindFromName("hovercraft").has_value());
}

TEST(ParseVehicleConfig, ReadsEveryField) {
  const VehicleConfig config = ParseVehicleConfig(ValidJson(), "test.json");
  EXPECT_EQ(config.name, "test-4ws");
  EXPECT_EQ(config.kind, VehicleKind::kFourWheelSteer);
  EXPECT_EQ(config.mass_kg, 120.0);
  ASSERT_EQ(config.wheels.size(), 4u);
  EXPECT_EQ(config.wheels[1].name, "front_right");
  EXPECT_EQ(config.wheels[1].position_m, Eigen::Vector2d(0.5, -0.4));
  EXPECT_EQ(config.wheels[1].nominal_radius_m, 0.254);
  EXPECT_TRUE(config.wheels[1].steerable);
  EXPECT_FALSE(config.tracks.has_value());
  EXPECT_EQ(config.imu.position_m, Eigen::Vector3d(0.0, 0.0, 0.25));
  ASSERT_EQ(config.ultrasonic.size(), 1u);
  EXPECT_EQ(config.ultrasonic[0].yaw_rad, 1.5);
}

struct ErrorCase {
  const char* what;
  const char* from;
  const char* to;
  const char* key_path;
  const char* reason;
};

class ParseVehicleConfigError : public ::testing::TestWithParam<ErrorCase> {};

TEST_P(ParseVehicleConfigError, NamesSourceKeyPathAndReason) {
  const ErrorCase& c = GetParam();
  EXPECT_THAT(ErrorOf(ValidJsonWith(c.from, c.to)), AllOf(HasSubstr("test.json"), HasSubstr(c.key_path),
                                                          HasSubstr(c.reason)))
      << c.what;
}

INSTANTIATE_TEST_SUITE_P(
    Cases, ParseVehicleConfigError,
    ::testing::Values(
        ErrorCase{"missing key", R"("mass_kg": 120.0,)", "", "mass_kg", "missing key"},
        ErrorCase{"unknown key", R"("mass_kg": 120.0,)", R"("mass_kg": 120.0, "colour": 1,)", "colour",
                  "unknown key"},
        ErrorCase{"unknown nested key", R"("steerable": true}],)", R"("steerable": true, "x": 1}],)",
                  "wheels[3].x", "unknown key"},
        ErrorCase{"wrong type", R"("mass_kg": 120.0)", R"("mass_kg": "heavy")", "mass_kg", "must be a number"},
        ErrorCase{"wrong bool type", R"("steerable": true})", R"("steerable": 1})", "wheels[0].steerable",
                  "must be true or false"},
        ErrorCase{"short vector", R"([0.5, -0.4])", "[0.5]", "wheels[1].position_m", "array of 2"},
        ErrorCase{"wheels not array", R"("wheels": [)", R"("wheels": {"a": 1}, "x": [)", "wheels",
                  "must be an array"},
        ErrorCase{"negative radius", R"("nominal_radius_m": 0.254, "steerable": true},
    {"name": "front_right")",
                  R"("nominal_radius_m": -0.254, "steerable": true},
    {"name": "front_right")",
                  "wheels[0].nominal_radius_m", "must be in [0.005, 5], got -0.254"},
        ErrorCase{"mass zero", R"("mass_kg": 120.0)", R"("mass_kg": 0.0)", "mass_kg", "must be in [0.1, 100000], got 0"},
        ErrorCase{"unknown kind", R"("four_wheel_steer")", R"("hovercraft")", "kind", "hovercraft"},
        ErrorCase{"yaw out of range", R"("yaw_rad": 1.5})", R"("yaw_rad": 7.0})", "ultrasonic[0].yaw_rad",
                  "must be in"},
        ErrorCase{"mount not object", R"("imu": {"name": "imu", "position_m": [0.0, 0.0, 0.25], "yaw_rad": 0.0})",
                  R"("imu": 3)", "imu", "must be an object"},
        ErrorCase{"steering limit", R"("max_steering_angle_rad": 1.0)", R"("max_steering_angle_rad": 4.0)",
                  "max_steering_angle_rad", "must be in [0, 3.14159], got 4"},
        ErrorCase{"fixed wheel on 4WS", R"("position_m": [-0.5, -0.4], "nominal_radius_m": 0.254, "steerable": true)",
                  R"("position_m": [-0.5, -0.4], "nominal_radius_m": 0.254, "steerable": false)",
                  "wheels[3].steerable", "must be true"},
        ErrorCase{"wheel count", R"(,
    {"name": "rear_right", "position_m": [-0.5, -0.4], "nominal_radius_m": 0.254, "steerable": true})",
                  "", "four_wheel_steer", "exactly 4 wheels"},
        ErrorCase{"duplicate wheel name", R"("name": "rear_right")", R"("name": "rear_left")", "wheels[3].name",
                  "used twice"},
        ErrorCase{"tracks on a wheeled vehicle", R"("tracks": null)",
                  R"("tracks": {"contact_length_m": 1.0, "turning_resistance_coefficient": 0.3})", "tracks",
                  "must be null"},
        ErrorCase{"invalid JSON", R"("mass_kg": 120.0,)", R"("mass_kg": 120.0,,)", "test.json", "invalid JSON"}),
    [](const ::testing::TestParamInfo<ErrorCase>& case_info) {
      std::string name = case_info.param.what;
      for (char& c : name) {
        if (!std::isalnum(static_cast<unsigned char>(c))) c = '_';
      }
      return name;
    });

TEST(ParseVehicleConfig, SkidSteerNeedsSymmetricTracksAndTrackData) {
  const std::string tracked = R"({
  "name": "t", "kind": "skid_steer", "mass_kg": 600.0, "max_steering_angle_rad": 0.0,
  "wheels": [
    {"name": "left_track", "position_m": [0.0, 0.55], "nominal_radius_m": 0.15, "steerable": false},
    {"name": "right_track", "position_m": [0.0, -0.55], "nominal_radius_m": 0.15, "steerable": false}],
  "tracks": {"contact_length_m": 1.0, "turning_resistance_coefficient": 0.3},
  "gnss_antenna": {"name": "gnss", "position_m": [0.0, 0.0, 1.5], "yaw_rad": 0.0},
  "imu": {"name": "imu", "position_m": [0.0, 0.0, 0.4], "yaw_rad": 0.0},
  "ultrasonic": []})";
  EXPECT_NO_THROW(ParseVehicleConfig(tracked, "t.json"));
  const auto with = [&](const std::string& from, const std::string& to) {
    std::string text = tracked;
    return text.replace(text.find(from), from.size(), to);
  };
  EXPECT_THAT(ErrorOf(with(R"({"contact_length_m": 1.0, "turning_resistance_coefficient": 0.3})", "null")),
              HasSubstr("needs \"tracks\""));
  EXPECT_THAT(ErrorOf(with("[0.0, -0.55]", "[0.0, -0.5]")), HasSubstr("y = +B/2 and -B/2"));
  EXPECT_THAT(ErrorOf(with("[0.0, -0.55]", "[0.1, -0.55]")), HasSubstr("same x"));
  EXPECT_THAT(ErrorOf(with(R"("contact_length_m": 1.0)", R"("contact_length_m": 0.0)")),
              HasSubstr("tracks.contact_length_m"));
  EXPECT_THAT(ErrorOf(with(R"("turning_resistance_coefficient": 0.3)", R"("turning_resistance_coefficient": -1)")),
              HasSubstr("tracks.turning_resistance_coefficient"));
  EXPECT_THAT(ErrorOf(with(R"(0.55], "nominal_radius_m": 0.15, "steerable": false)",
                           R"(0.55], "nominal_radius_m": 0.15, "steerable": true)")),
              HasSubstr("wheels[0].steerable must be false"));
  EXPECT_THAT(ErrorOf(with("\"tracks\": {", "\"tracks\": {\"extra\": 1, ")), HasSubstr("tracks.extra: unknown key"));
}

// Issue 26: a wheel radius of 1e300 was accepted and aborted a replay without naming a key. Every
// value has a physical domain, refused at load with the key path and the range printed short.
INSTANTIATE_TEST_SUITE_P(
    Domains, ParseVehicleConfigError,
    ::testing::Values(
        ErrorCase{"huge radius", R"("nominal_radius_m": 0.254, "steerable": true},
    {"name": "front_right")",
                  R"("nominal_radius_m": 1e300, "steerable": true},
    {"name": "front_right")",
                  "test.json: wheels[0].nominal_radius_m", "must be in [0.005, 5], got 1e+300"},
        ErrorCase{"tiny radius", R"("nominal_radius_m": 0.254, "steerable": true},
    {"name": "front_right")",
                  R"("nominal_radius_m": 1e-300, "steerable": true},
    {"name": "front_right")",
                  "wheels[0].nominal_radius_m", "got 1e-300"},
        ErrorCase{"huge mass", R"("mass_kg": 120.0)", R"("mass_kg": 1e300)", "mass_kg", "must be in [0.1, 100000], got 1e+300"},
        ErrorCase{"far wheel", R"([0.5, -0.4])", "[0.5, -1e9]", "wheels[1].position_m[1]", "must be in [-50, 50], got -1e+09"},
        ErrorCase{"far antenna", R"("position_m": [0.0, 0.0, 1.2])", R"("position_m": [0.0, 0.0, 1e300])",
                  "gnss_antenna.position_m[2]", "must be in [-50, 50], got 1e+300"},
        ErrorCase{"negative steering", R"("max_steering_angle_rad": 1.0)", R"("max_steering_angle_rad": -1)",
                  "max_steering_angle_rad", "must be in [0, 3.14159], got -1"}),
    [](const ::testing::TestParamInfo<ErrorCase>& case_info) {
      std::string name = case_info.param.what;
      for (char& c : name) {
        if (!std::isalnum(static_cast<unsigned char>(c))) c = '_';
      }
      return name;
    });

TEST(ParseVehicleConfig, NamesHaveALengthLimit) {
  EXPECT_THAT(ErrorOf(ValidJsonWith(R"("name": "test-4ws")", "\"name\": \"" + std::string(300, 'n') + "\"")),
              HasSubstr("test.json: name: longer than 256 bytes"));
}

TEST(ParseVehicleConfig, TrackValuesHaveDomains) {
  std::string text = R"({
  "name": "t", "kind": "skid_steer", "mass_kg": 600.0, "max_steering_angle_rad": 0.0,
  "wheels": [
    {"name": "left_track", "position_m": [0.0, 0.55], "nominal_radius_m": 0.15, "steerable": false},
    {"name": "right_track", "position_m": [0.0, -0.55], "nominal_radius_m": 0.15, "steerable": false}],
  "tracks": {"contact_length_m": 1e300, "turning_resistance_coefficient": 0.3},
  "gnss_antenna": {"name": "gnss", "position_m": [0.0, 0.0, 1.5], "yaw_rad": 0.0},
  "imu": {"name": "imu", "position_m": [0.0, 0.0, 0.4], "yaw_rad": 0.0},
  "ultrasonic": []})";
  EXPECT_THAT(ErrorOf(text), HasSubstr("tracks.contact_length_m: must be in [0.01, 20], got 1e+300"));
  text.replace(text.find("1e300"), 5, "1.0");
  text.replace(text.find("0.3}"), 3, "1e9");
  EXPECT_THAT(ErrorOf(text), HasSubstr("tracks.turning_resistance_coefficient: must be in [0, 10], got 1e+09"));
}

TEST(ParseVehicleConfig, WheelAndSensorCountsAreBoundedBeforeTheyAreRead) {
  std::string wheels;
  for (int i = 0; i < 17; ++i) {
    wheels += std::string(i ? "," : "") + R"({"name": "w)" + std::to_string(i) +
              R"(", "position_m": [0.5, 0.4], "nominal_radius_m": 0.254, "steerable": true})";
  }
  std::string text = ValidJson();
  const auto begin = text.find("\"wheels\": [") + 10;
  const auto end = text.find("}],", begin) + 2;
  EXPECT_THAT(ErrorOf(text.replace(begin, end - begin, "[" + wheels + "]")),
              HasSubstr("test.json: wheels: must have 1 to 16 elements, got 17"));
  std::string sensors;
  for (int i = 0; i < 65; ++i) sensors += std::string(i ? "," : "") + "1";
  EXPECT_THAT(ErrorOf(ValidJsonWith(R"([{"name": "us_front_left", "position_m": [0.75, 0.5, 0.5], "yaw_rad": 1.5}])",
                                    "[" + sensors + "]")),
              HasSubstr("ultrasonic: must have at most 64 elements, got 65"));
}

TEST(LoadVehicleConfig, DevicesDirectoriesAndOversizedFilesAreRefused) {
  // Issue 26: /dev/zero was read forever; a directory was reported as "invalid JSON".
  const auto error_of = [](const std::filesystem::path& path) {
    try {
      LoadVehicleConfig(path);
    } catch (const VehicleConfigError& e) {
      return std::string(e.what());
    }
    return std::string("no error");
  };
  EXPECT_EQ(error_of("/dev/zero"), "/dev/zero: is a character device, not a regular file");
  const test::ScratchDir dir;
  EXPECT_EQ(error_of(dir.path()), dir.path().string() + ": is a directory, not a regular file");
  const std::filesystem::path big = dir / "big.json";
  std::ofstream(big).close();
  std::filesystem::resize_file(big, (std::uintmax_t{16} << 20) + 1);
  EXPECT_EQ(error_of(big), big.string() + ": is larger than the limit of 16 MiB (vehicle file)");
  EXPECT_EQ(error_of(dir / "none.json"),
            (dir / "none.json").string() + ": cannot open vehicle file: No such file or directory");
}

TEST(LoadVehicleConfig, MissingFileIsAnError) {
  EXPECT_THROW(LoadVehicleConfig(test::SourceDir() / "config" / "vehicles" / "no-such.json"), VehicleConfigError);
}

TEST(LoadVehicleConfig, ShippedFilesEqualTheInCodeConfigurations) {
  const auto dir = test::SourceDir() / "config" / "vehicles";
  EXPECT_EQ(LoadVehicleConfig(dir / "agrimaro-swerve.json"), AgrimaroSwerveConfig());
  EXPECT_EQ(LoadVehicleConfig(dir / "vineyard-ugv-4ws.json"), VineyardUgv4wsConfig());
  EXPECT_EQ(LoadVehicleConfig(dir / "differential.json"), DifferentialDriveConfig());
  EXPECT_EQ(LoadVehicleConfig(dir / "tracked.json"), TrackedVehicleConfig());
}

TEST(VehicleConfigProblem, ShippedConfigurationsAreValidAndOfTheirKind) {
  EXPECT_EQ(VehicleConfigProblem(AgrimaroSwerveConfig()), std::nullopt);
  EXPECT_EQ(VehicleConfigProblem(VineyardUgv4wsConfig()), std::nullopt);
  EXPECT_EQ(VehicleConfigProblem(DifferentialDriveConfig()), std::nullopt);
  EXPECT_EQ(VehicleConfigProblem(TrackedVehicleConfig()), std::nullopt);
  EXPECT_EQ(AgrimaroSwerveConfig().wheels.size(), 3u);
  EXPECT_EQ(TrackedVehicleConfig().kind, VehicleKind::kSkidSteer);
}

TEST(VehicleConfig, VineyardUltrasonicSensorsAreAtTheCornersLookingSideways) {
  // Donati 2021 Table 5.5 (x right, y forward there) converted to x forward, y left: corners (+-L/2, +-T/2).
  const VehicleConfig config = VineyardUgv4wsConfig();
  ASSERT_EQ(config.ultrasonic.size(), 4u);
  for (const SensorMount& mount : config.ultrasonic) {
    EXPECT_DOUBLE_EQ(std::abs(mount.position_m.x()), 0.75) << mount.name;
    EXPECT_DOUBLE_EQ(std::abs(mount.position_m.y()), 0.5) << mount.name;
    EXPECT_DOUBLE_EQ(mount.yaw_rad, std::copysign(std::numbers::pi / 2.0, mount.position_m.y())) << mount.name;
  }
  for (const WheelGeometry& wheel : config.wheels) EXPECT_EQ(wheel.nominal_radius_m, 0.254);
}

TEST(VehicleConfigProblem, NamesTheField) {
  VehicleConfig config = DifferentialDriveConfig();
  config.wheels[1].position_m.x() = 0.2;
  EXPECT_THAT(VehicleConfigProblem(config).value_or(""), HasSubstr("same x"));
  config = DifferentialDriveConfig();
  config.imu.position_m.z() = std::numeric_limits<double>::quiet_NaN();
  EXPECT_THAT(VehicleConfigProblem(config).value_or(""), HasSubstr("imu.position_m"));
  config = AgrimaroSwerveConfig();
  config.wheels.pop_back();
  EXPECT_THAT(VehicleConfigProblem(config).value_or(""), HasSubstr("at least 3 wheels"));
  config = VineyardUgv4wsConfig();
  config.ultrasonic[1].name = config.ultrasonic[0].name;
  EXPECT_THAT(VehicleConfigProblem(config).value_or(""), HasSubstr("ultrasonic[1].name is used twice"));
  config = VineyardUgv4wsConfig();
  config.name.clear();
  EXPECT_THAT(VehicleConfigProblem(config).value_or(""), HasSubstr("name must not be empty"));
}

// ---- the recommended filter (issue 29): a path relative to the vehicle file

std::string WithRecommendedFilter(const std::string& value) {
  return ValidJsonWith(R"("name": "test-4ws",)", R"("name": "test-4ws", "recommended_filter": )" + value + ",");
}

std::string VehicleFileErrorOf(const std::string& text) { return ErrorOf(text, "config/vehicles/test.json"); }

TEST(ParseVehicleFile, ResolvesTheRecommendedFilterAgainstTheVehicleFilesDirectory) {
  const VehicleFile file = ParseVehicleFile(WithRecommendedFilter(R"("../filters/x.json")"), "config/vehicles/v.json");
  ASSERT_TRUE(file.recommended_filter.has_value());
  EXPECT_EQ(*file.recommended_filter, std::filesystem::path("config/vehicles/../filters/x.json"));
  EXPECT_EQ(file.vehicle, ParseVehicleConfig(ValidJson(), "v.json"));
  // A file in the working directory: the path as written.
  EXPECT_EQ(ParseVehicleFile(WithRecommendedFilter(R"("x.json")"), "v.json").recommended_filter,
            std::filesystem::path("x.json"));
}

TEST(ParseVehicleFile, KeepsAnAbsoluteRecommendedFilter) {
  EXPECT_EQ(ParseVehicleFile(WithRecommendedFilter(R"("/etc/rowloc/filters/x.json")"), "config/vehicles/v.json")
                .recommended_filter,
            std::filesystem::path("/etc/rowloc/filters/x.json"));
}

TEST(ParseVehicleFile, WithoutARecommendedFilterHasNone) {
  EXPECT_EQ(ParseVehicleFile(ValidJson(), "config/vehicles/v.json").recommended_filter, std::nullopt);
}

TEST(ParseVehicleFile, RefusesAnEmptyOrNonStringRecommendedFilterNamingTheKey) {
  EXPECT_THAT(VehicleFileErrorOf(WithRecommendedFilter(R"("")")),
              AllOf(HasSubstr("config/vehicles/test.json"), HasSubstr("recommended_filter"),
                    HasSubstr("must name a filter file")));
  for (const char* value : {"3", "null", "true", R"(["a.json"])", R"({"name": "x"})"}) {
    EXPECT_THAT(VehicleFileErrorOf(WithRecommendedFilter(value)),
                AllOf(HasSubstr("config/vehicles/test.json"), HasSubstr("recommended_filter"), HasSubstr("string")))
        << value;
  }
}

TEST(ParseVehicleFile, StillChecksTheVehicleAndRefusesUnknownKeys) {
  EXPECT_THAT(VehicleFileErrorOf(ValidJsonWith(R"("mass_kg": 120.0)", R"("mass_kg": -1.0)")), HasSubstr("mass_kg"));
  EXPECT_THAT(VehicleFileErrorOf(ValidJsonWith(R"("name": "test-4ws",)", R"("name": "test-4ws", "recommended": "a",)")),
              HasSubstr("recommended"));
}

TEST(ParseVehicleConfig, AcceptsAFileWithARecommendedFilter) {
  EXPECT_EQ(ParseVehicleConfig(WithRecommendedFilter(R"("../filters/x.json")"), "v.json"),
            ParseVehicleConfig(ValidJson(), "v.json"));
  EXPECT_THAT(ErrorOf(WithRecommendedFilter("7")), HasSubstr("recommended_filter"));
}

TEST(LoadVehicleFile, EveryShippedVehicleFileNamesAnExistingFilterFile) {
  const auto dir = test::SourceDir() / "config" / "vehicles";
  std::size_t files = 0;
  for (const auto& entry : std::filesystem::directory_iterator(dir)) {
    if (entry.path().extension() != ".json") continue;
    ++files;
    const VehicleFile file = LoadVehicleFile(entry.path());
    ASSERT_TRUE(file.recommended_filter.has_value()) << entry.path();
    ASSERT_TRUE(std::filesystem::is_regular_file(*file.recommended_filter)) << *file.recommended_filter;
    EXPECT_TRUE(std::filesystem::equivalent(file.recommended_filter->parent_path(), dir.parent_path() / "filters"))
        << entry.path() << ": its filter is not in config/filters";
    EXPECT_EQ(file.vehicle, LoadVehicleConfig(entry.path()));
  }
  EXPECT_GE(files, 5u);
  EXPECT_EQ(LoadVehicleFile(dir / "differential.json").recommended_filter->filename(), "differential.json");
}

TEST(LoadVehicleFile, MissingFileIsAnError) {
  EXPECT_THROW(LoadVehicleFile(test::SourceDir() / "config" / "vehicles" / "no-such.json"), VehicleConfigError);
}

}  // namespace
}  // namespace rowloc::mapio
