// Tests of the sensor log reader (docs/protocol.md §1): real simulator logs read back exactly
// (tests/data/logs/README.md says how they were made), then one test per rule, each checking the
// "<source>:<line>: <key>: <reason>" of the error.
#include "rowloc/formats/sensor_log_reader.hpp"

#include "counting_fill_buffer.hpp"
#include "sensor_log_test_writer.hpp"
#include "test_support.hpp"

#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include <algorithm>
#include <fstream>
#include <map>
#include <sstream>
#include <string>
#include <vector>

namespace rowloc::formats {
namespace {

using ::testing::HasSubstr;
using ::testing::StartsWith;

const std::string kHeader =
    R"({"type":"log_header","protocol":"rowloc/1","source":"test","scenario":"s","vehicle":"v",)"
    R"("origin":{"latitude_deg":45.0,"longitude_deg":7.0,"altitude_m":240.0},)"
    R"("wheels":["left","right"],"ultrasonic":["us_left"]})";
const std::string kWheels = R"({"type":"wheels","t":1.0,"speed_radps":{"left":1.5,"right":1.25}})";

/// Everything a whole log gives: the header, the messages and their count per type.
struct ReadLog {
  LogHeader header;
  std::vector<SensorMessage> messages;
  std::map<std::string, int, std::less<>> count_by_type;
};

ReadLog ReadAll(std::istream& in, const std::string& source) {
  SensorLogReader reader(in, source);
  ReadLog log{reader.header(), {}, {}};
  while (std::optional<SensorMessage> message = reader.Next()) {
    ++log.count_by_type[std::string(TypeOf(*message))];
    log.messages.push_back(std::move(*message));
  }
  EXPECT_EQ(reader.messages_read(), log.messages.size());
  return log;
}

ReadLog ReadText(const std::string& text) {
  std::istringstream in(text);
  return ReadAll(in, "test.ndjson");
}

/// The message of the SensorLogError raised while reading all of `text` ("" and a failure if none).
std::string ErrorOf(const std::string& text) {
  try {
    (void)ReadText(text);
  } catch (const SensorLogError& error) {
    return error.what();
  }
  ADD_FAILURE() << "no SensorLogError for:\n" << text;
  return "";
}

/// A log of kHeader and the given message lines.
std::string Log(const std::vector<std::string>& lines) {
  std::string text = kHeader + "\n";
  for (const std::string& line : lines) text += line + "\n";
  return text;
}

std::filesystem::path Fixture(const std::string& name) {
  return ::rowloc::test::SourceDir() / "tests/data/logs" / name;
}

/// Reads a fixture and checks that writing every message again gives the file's lines back: the same
/// keys in the same order, the same doubles (log_text::SplitNumbers).
ReadLog ReadFixtureRoundTrip(const std::string& name) {
  std::ifstream in(Fixture(name));
  EXPECT_TRUE(in.is_open()) << Fixture(name);
  const ReadLog log = ReadAll(in, name);
  std::ifstream lines_in(Fixture(name));
  std::string line;
  const auto expect_same_json = [&lines_in, &line](const std::string& written) {
    ASSERT_TRUE(std::getline(lines_in, line));
    const log_text::NumbersApart expected = log_text::SplitNumbers(line);
    const log_text::NumbersApart actual = log_text::SplitNumbers(written);
    EXPECT_EQ(actual.skeleton, expected.skeleton);
    EXPECT_EQ(actual.numbers, expected.numbers) << line;  // exactly the same doubles
  };
  expect_same_json(log_text::WriteLine(log.header));
  for (const SensorMessage& message : log.messages) expect_same_json(log_text::WriteLine(log.header, message));
  EXPECT_FALSE(std::getline(lines_in, line)) << "lines left after the last message";
  return log;
}

template <typename T>
std::vector<T> All(const ReadLog& log) {
  std::vector<T> out;
  for (const SensorMessage& m : log.messages) {
    if (const T* typed = std::get_if<T>(&m)) out.push_back(*typed);
  }
  return out;
}

// --- real simulator logs -----------------------------------------------------------------------------

TEST(SensorLogReader, ReadsTheAgrimaroTilesLogBackExactly) {
  const ReadLog log = ReadFixtureRoundTrip("agrimaro-tiles-head.ndjson");
  EXPECT_EQ(log.header.protocol, "rowloc/1");
  EXPECT_EQ(log.header.scenario, "agrimaro-tiles");
  EXPECT_EQ(log.header.vehicle, "agrimaro-swerve");
  EXPECT_EQ(log.header.origin.latitude_deg, 45.0628);
  EXPECT_EQ(log.header.wheels, (std::vector<std::string>{"left_front", "left_rear", "right"}));
  EXPECT_TRUE(log.header.ultrasonic.empty());
  EXPECT_EQ(log.messages.size(), 300u);
  EXPECT_EQ(log.count_by_type, (std::map<std::string, int, std::less<>>{
                                   {"gps", 15}, {"imu", 143}, {"steering", 71}, {"wheels", 71}}));
  const GpsMessage& gps = std::get<GpsMessage>(log.messages.at(0));
  EXPECT_EQ(gps.fix, GnssFixQuality::kRtkFixed);
  ASSERT_TRUE(gps.position.has_value());
  EXPECT_EQ(gps.position->latitude_deg, 45.06279634884623);
  EXPECT_EQ(gps.position->sigma_horizontal_m, 0.01);
  const WheelsMessage& wheels = std::get<WheelsMessage>(log.messages.at(7));  // line 9 of the file
  EXPECT_EQ(wheels.time_s, 0.02);
  ASSERT_TRUE(wheels.torque_nm.has_value());
  EXPECT_EQ(wheels.torque_nm->at(1), 0.024894948223366825);  // left_rear
  const SteeringMessage& steering = std::get<SteeringMessage>(log.messages.at(6));
  EXPECT_EQ(steering.angle_rad, (std::vector<std::optional<double>>{0.0, 0.0015, 0.0015}));
  EXPECT_EQ(std::get<ImuMessage>(log.messages.back()).gyro_z_radps, 0.0005943272007083355);
  EXPECT_EQ(TimeOf(log.messages.back()), 1.42);
}

TEST(SensorLogReader, ReadsVineyardUltrasonicEchoesAndPingsWithoutEcho) {
  const ReadLog log = ReadFixtureRoundTrip("vineyard-002-1us-echoes.ndjson");
  EXPECT_EQ(log.header.ultrasonic, std::vector<std::string>{"us_front_left"});
  EXPECT_EQ(log.count_by_type, (std::map<std::string, int, std::less<>>{
                                   {"gps", 11}, {"imu", 214}, {"steering", 107}, {"ultrasonic", 22}, {"wheels", 107}}));
  const std::vector<UltrasonicMessage> pings = All<UltrasonicMessage>(log);
  const auto echoes = std::count_if(pings.begin(), pings.end(), [](const auto& p) { return p.range_m.has_value(); });
  EXPECT_EQ(echoes, 11);
  EXPECT_FALSE(pings.front().range_m.has_value());  // no echo: no measurement, not 0
  EXPECT_FALSE(pings.back().range_m.has_value());
  const auto first_echo = std::find_if(pings.begin(), pings.end(), [](const auto& p) { return p.range_m; });
  EXPECT_EQ(first_echo->time_s, 119.0);
  EXPECT_EQ(*first_echo->range_m, 3.995353637234504);
  EXPECT_EQ(first_echo->sensor, "us_front_left");
  EXPECT_EQ(first_echo->sensor_index, 0u);
  for (const WheelsMessage& w : All<WheelsMessage>(log)) EXPECT_FALSE(w.torque_nm.has_value());
  const SteeringMessage steering = All<SteeringMessage>(log).front();  // four-wheel steer: all four sent
  EXPECT_EQ(steering.angle_rad, (std::vector<std::optional<double>>{0.5355, 0.2955, -0.537, -0.2955}));
}

TEST(SensorLogReader, GnssDropoutHasAFixOfNoneAndNoPosition) {
  const ReadLog log = ReadFixtureRoundTrip("vineyard-002-1us-gnss-dropout.ndjson");
  const std::vector<GpsMessage> fixes = All<GpsMessage>(log);
  ASSERT_EQ(fixes.size(), 5u);
  EXPECT_EQ(fixes[1].fix, GnssFixQuality::kSbas);
  EXPECT_EQ(fixes[1].position->sigma_vertical_m, 1.345241083325118);
  for (std::size_t i = 2; i < fixes.size(); ++i) {
    EXPECT_EQ(fixes[i].fix, GnssFixQuality::kNone);
    EXPECT_FALSE(fixes[i].position.has_value());
  }
  EXPECT_EQ(fixes[2].time_s, 57.6);
}

// --- accepted variations -------------------------------------------------------------------------------

TEST(SensorLogReader, IgnoresUnknownKeysForForwardCompatibility) {
  std::string header = kHeader;
  header.insert(1, R"("future":{"x":[1,2]},)");
  const ReadLog log = ReadText(header + "\n" +
                               R"({"type":"imu","t":0.5,"sensor":"imu","accel_x_mps2":1,"accel_y_mps2":2,)"
                               R"("gyro_z_radps":3,"accel_z_mps2":9.81})" "\n");
  const ImuMessage& imu = std::get<ImuMessage>(log.messages.at(0));
  EXPECT_EQ(imu.accel_x_mps2, 1.0);
  EXPECT_EQ(imu.gyro_z_radps, 3.0);
}

TEST(SensorLogReader, AcceptsAMinorRevisionOfProtocolOne) {
  std::string header = kHeader;
  header.replace(header.find("rowloc/1"), 8, "rowloc/1.2");
  EXPECT_EQ(ReadText(header + "\n").header.protocol, "rowloc/1.2");
}

TEST(SensorLogReader, SkipsEmptyLinesAndAcceptsCrLf) {
  const ReadLog log = ReadText(kHeader + "\r\n\n" + kWheels + "\r\n\n");
  ASSERT_EQ(log.messages.size(), 1u);
  EXPECT_EQ(std::get<WheelsMessage>(log.messages[0]).speed_radps, (std::vector<double>{1.5, 1.25}));
}

TEST(SensorLogReader, SteeringCarriesOnlyTheSteerableWheels) {
  const ReadLog log = ReadText(Log({R"({"type":"steering","t":0,"angle_rad":{"right":-0.25}})"}));
  EXPECT_EQ(std::get<SteeringMessage>(log.messages[0]).angle_rad,
            (std::vector<std::optional<double>>{std::nullopt, -0.25}));
}

TEST(SensorLogReader, ReadsVioAndEqualTimeStamps) {
  const ReadLog log = ReadText(Log({kWheels, R"({"type":"vio","t":1.0,"sensor":"camera","velocity_x_mps":0.99,)"
                                             R"("velocity_y_mps":0.01,"sigma_mps":0.02})"}));
  const VioMessage& vio = std::get<VioMessage>(log.messages.at(1));
  EXPECT_EQ(vio.velocity_x_mps, 0.99);
  EXPECT_EQ(vio.sigma_mps, 0.02);
  EXPECT_EQ(TypeOf(log.messages[1]), "vio");
}

TEST(SensorLogReader, ParsesSingleLinesForTheService) {
  const LogHeader header = ParseLogHeader(kHeader, "session 7");
  const SensorMessage m =
      ParseSensorMessage(R"({"type":"ultrasonic","t":3,"sensor":"us_left","range_m":1.234})", header, "session 7", 40);
  EXPECT_EQ(std::get<UltrasonicMessage>(m).range_m, 1.234);
  try {
    (void)ParseSensorMessage(R"({"type":"imu","t":3})", header, "session 7", 41);
    FAIL() << "no error";
  } catch (const SensorLogError& e) {
    EXPECT_EQ(e.source(), "session 7");
    EXPECT_EQ(e.line(), 41u);
    EXPECT_EQ(e.subject(), "sensor");
    EXPECT_EQ(std::string(e.what()), "session 7:41: sensor: missing (required in an imu message)");
  }
}

TEST(SensorLogReader, GoesOnWithTheNextLineAfterABadOne) {
  std::istringstream in(Log({kWheels, R"({"type":"wheels"})", kWheels}));
  SensorLogReader reader(in, "test.ndjson");
  EXPECT_TRUE(reader.Next().has_value());
  EXPECT_THROW((void)reader.Next(), SensorLogError);
  EXPECT_TRUE(reader.Next().has_value());
  EXPECT_FALSE(reader.Next().has_value());
  EXPECT_EQ(reader.line_number(), 4u);
}

// --- errors: each names the source, the line, the key and the reason -----------------------------------

TEST(SensorLogReaderErrors, BadJsonNamesTheLine) {
  const std::string message = ErrorOf(Log({kWheels, R"({"type":"imu","t":)"}));
  EXPECT_THAT(message, StartsWith("test.ndjson:3: line: invalid JSON: "));
  EXPECT_THAT(message, HasSubstr("column"));
  EXPECT_THAT(ErrorOf(Log({R"({"type":"imu","t":NaN})"})), StartsWith("test.ndjson:2: line: invalid JSON: "));
  EXPECT_EQ(ErrorOf(Log({"[1,2]"})), "test.ndjson:2: line: must be a JSON object, got array");
}

TEST(SensorLogReaderErrors, MissingHeader) {
  EXPECT_EQ(ErrorOf(kWheels + "\n"),
            "test.ndjson:1: type: expected \"log_header\", got \"wheels\" (a sensor log starts with its header)");
  EXPECT_EQ(ErrorOf(Log({kHeader})),
            "test.ndjson:2: type: a second log_header (only the first line of a log is a header)");
}

TEST(SensorLogReaderErrors, EmptyStream) {
  EXPECT_EQ(ErrorOf(""), "test.ndjson:1: log_header: missing (the log is empty)");
  EXPECT_EQ(ErrorOf("\n\n"), "test.ndjson:1: log_header: missing (the log is empty)");
}

TEST(SensorLogReaderErrors, AnotherProtocolMajorVersion) {
  for (const std::string other : {"rowloc/2", "rowloc/10", "rowloc/1.", "rowloc-truth/1"}) {
    std::string header = kHeader;
    header.replace(header.find("rowloc/1"), 8, other);
    EXPECT_EQ(ErrorOf(header + "\n"),
              "test.ndjson:1: protocol: \"" + other + "\" is not supported (this reader reads rowloc/1)");
  }
}

TEST(SensorLogReaderErrors, MissingKey) {
  EXPECT_EQ(ErrorOf(Log({R"({"type":"imu","t":1,"sensor":"imu","accel_x_mps2":0,"accel_y_mps2":0})"})),
            "test.ndjson:2: gyro_z_radps: missing (required in an imu message)");
  EXPECT_EQ(ErrorOf(Log({R"({"type":"ultrasonic","t":1,"sensor":"us_left"})"})),
            "test.ndjson:2: range_m: missing (required in an ultrasonic message)");
  EXPECT_EQ(ErrorOf(Log({R"({"t":1})"})), "test.ndjson:2: type: missing (required in every message)");
  std::string header = kHeader;
  header.erase(header.find(R"("longitude_deg":7.0,)"), 20);
  EXPECT_EQ(ErrorOf(header + "\n"), "test.ndjson:1: origin.longitude_deg: missing (required in the log_header)");
}

TEST(SensorLogReaderErrors, WrongType) {
  EXPECT_EQ(ErrorOf(Log({R"({"type":"wheels","t":"1.0","speed_radps":{}})"})),
            "test.ndjson:2: t: must be a number, got string");
  EXPECT_EQ(ErrorOf(Log({R"({"type":"wheels","t":1,"speed_radps":{"left":true,"right":1}})"})),
            "test.ndjson:2: speed_radps.left: must be a number, got boolean");
  EXPECT_EQ(ErrorOf(Log({R"({"type":"steering","t":1,"angle_rad":[0.1]})"})),
            "test.ndjson:2: angle_rad: must be an object, got array");
  EXPECT_EQ(ErrorOf(Log({R"({"type":"ultrasonic","t":1,"sensor":"us_left","range_m":"none"})"})),
            "test.ndjson:2: range_m: must be a number, got string");
}

TEST(SensorLogReaderErrors, NumberBeyondTheRangeOfADouble) {
  EXPECT_EQ(ErrorOf(Log({R"({"type":"wheels","t":1,"speed_radps":{"left":1e999,"right":1}})"})),
            "test.ndjson:2: speed_radps.left: not a finite number (number overflow parsing '1e999')");
  EXPECT_EQ(ErrorOf(Log({kWheels, R"({"type":"wheels","t":-1e999})"})),
            "test.ndjson:3: t: not a finite number (number overflow parsing '-1e999')");
  // In an unknown key too (the line cannot be read at all); the path skips closed objects.
  EXPECT_EQ(ErrorOf(Log({R"({"type":"wheels","extra":{"w":[{"a":1},2e400]},"t":1})"})),
            "test.ndjson:2: extra.w: not a finite number (number overflow parsing '2e400')");
}

TEST(SensorLogReaderErrors, ValueOutOfItsRange) {
  EXPECT_EQ(ErrorOf(Log({R"({"type":"ultrasonic","t":1,"sensor":"us_left","range_m":0})"})),
            "test.ndjson:2: range_m: must be positive, got 0");
  EXPECT_EQ(ErrorOf(Log({R"({"type":"gps","t":1,"sensor":"gnss","fix":"sbas","latitude_deg":95,)"
                         R"("longitude_deg":7,"altitude_m":1,"sigma_horizontal_m":1,"sigma_vertical_m":1})"})),
            "test.ndjson:2: latitude_deg: 95 is not in [-90, 90]");
  EXPECT_EQ(ErrorOf(Log({R"({"type":"gps","t":1,"sensor":"gnss","fix":"dgps"})"})),
            "test.ndjson:2: fix: unknown fix quality \"dgps\" (none, sbas, rtk_float or rtk_fixed)");
}

TEST(SensorLogReaderErrors, ValuesNoSensorCanProduceNameTheirKey) {
  // Issue 26: a torque of 1e308, an altitude of 1e308 or sigmas of 1e300 aborted a replay without a
  // line or key. They are finite JSON numbers; the reader refuses them with their key.
  EXPECT_EQ(ErrorOf(Log({R"({"type":"wheels","t":1,"speed_radps":{"left":1,"right":1},)"
                         R"("torque_nm":{"left":1e308,"right":1}})"})),
            "test.ndjson:2: torque_nm.left: 1e+308 is not in [-1e+06, 1e+06]");
  EXPECT_EQ(ErrorOf(Log({R"({"type":"gps","t":1,"sensor":"gnss","fix":"sbas","latitude_deg":45,)"
                         R"("longitude_deg":7,"altitude_m":1e308,"sigma_horizontal_m":1,"sigma_vertical_m":1})"})),
            "test.ndjson:2: altitude_m: 1e+308 is not in [-1e+05, 1e+05]");
  EXPECT_EQ(ErrorOf(Log({R"({"type":"gps","t":1,"sensor":"gnss","fix":"sbas","latitude_deg":45,)"
                         R"("longitude_deg":7,"altitude_m":1,"sigma_horizontal_m":1e300,"sigma_vertical_m":1})"})),
            "test.ndjson:2: sigma_horizontal_m: 1e+300 is not in (0, 1e+06]");
  EXPECT_EQ(ErrorOf(Log({R"({"type":"imu","t":1,"sensor":"imu","accel_x_mps2":0,"accel_y_mps2":-1e200,)"
                         R"("gyro_z_radps":0})"})),
            "test.ndjson:2: accel_y_mps2: -1e+200 is not in [-1000, 1000]");
  EXPECT_EQ(ErrorOf(Log({R"({"type":"vio","t":1,"sensor":"cam","velocity_x_mps":1,"velocity_y_mps":0,)"
                         R"("sigma_mps":1e9})"})),
            "test.ndjson:2: sigma_mps: 1e+09 is not in (0, 1000]");
  EXPECT_EQ(ErrorOf(Log({R"({"type":"wheels","t":1,"speed_radps":{"left":1,"right":"fast"}})"})),
            "test.ndjson:2: speed_radps.right: must be a number, got string");
}

TEST(SensorLogReaderErrors, UnknownWheelOrSensor) {
  EXPECT_EQ(ErrorOf(Log({R"({"type":"wheels","t":1,"speed_radps":{"left":1,"right":1,"middle":1}})"})),
            "test.ndjson:2: speed_radps.middle: unknown wheel (the log header lists left, right)");
  EXPECT_EQ(ErrorOf(Log({R"({"type":"steering","t":1,"angle_rad":{"Left":0.1}})"})),
            "test.ndjson:2: angle_rad.Left: unknown wheel (the log header lists left, right)");
  EXPECT_EQ(ErrorOf(Log({R"({"type":"ultrasonic","t":1,"sensor":"us_right","range_m":null})"})),
            "test.ndjson:2: sensor: unknown ultrasonic sensor \"us_right\" (the log header lists us_left)");
}

TEST(SensorLogReader, ReadsTheEncodersCumulativeAngles) {
  const ReadLog log = ReadText(Log({R"({"type":"wheels","t":1,"speed_radps":{"left":1,"right":2},)"
                                    R"("angle_rad":{"right":-3.5,"left":1250.25}})",
                                    R"({"type":"wheels","t":2,"speed_radps":{"left":1,"right":2}})"}));
  const std::vector<WheelsMessage> wheels = All<WheelsMessage>(log);
  ASSERT_EQ(wheels.size(), 2u);
  ASSERT_TRUE(wheels[0].angle_rad.has_value());
  EXPECT_EQ(*wheels[0].angle_rad, (std::vector<double>{1250.25, -3.5}));  // header order: left, right
  EXPECT_FALSE(wheels[1].angle_rad.has_value());                        // optional per message
}

TEST(SensorLogReaderErrors, MissingWheel) {
  EXPECT_EQ(ErrorOf(Log({R"({"type":"wheels","t":1,"speed_radps":{"left":1}})"})),
            "test.ndjson:2: speed_radps.right: missing (every wheel of the log header must appear in speed_radps)");
  EXPECT_EQ(ErrorOf(Log({R"({"type":"wheels","t":1,"speed_radps":{"left":1,"right":1},"torque_nm":{"right":2}})"})),
            "test.ndjson:2: torque_nm.left: missing (every wheel of the log header must appear in torque_nm)");
  EXPECT_EQ(ErrorOf(Log({R"({"type":"wheels","t":1,"speed_radps":{"left":1,"right":1},"angle_rad":{"left":2}})"})),
            "test.ndjson:2: angle_rad.right: missing (every wheel of the log header must appear in angle_rad)");
}

TEST(SensorLogReaderErrors, TimeGoingBackwards) {
  EXPECT_EQ(ErrorOf(Log({kWheels, "", R"({"type":"wheels","t":0.5,"speed_radps":{"left":1,"right":1}})"})),
            "test.ndjson:4: t: 0.5 s is before the previous message's 1 s (time never decreases inside a log)");
}

TEST(SensorLogReaderErrors, UnknownMessageType) {
  EXPECT_EQ(ErrorOf(Log({R"({"type":"lidar","t":1})"})),
            "test.ndjson:2: type: unknown message type \"lidar\" "
            "(rowloc/1 sensor messages: gps, imu, wheels, steering, ultrasonic, vio)");
}

TEST(SensorLogReaderErrors, BadHeaderNames) {
  std::string header = kHeader;
  header.replace(header.find(R"(["left","right"])"), 16, R"(["left","left"])");
  EXPECT_EQ(ErrorOf(header + "\n"), "test.ndjson:1: wheels[1]: duplicate name \"left\"");
}

TEST(SensorLogReaderErrors, UnterminatedOrOverlongLine) {
  EXPECT_EQ(ErrorOf(kHeader + "\n" + kWheels), "test.ndjson:2: line: not terminated by a newline (a truncated log?)");
  const std::string padding(kMaxLogLineBytes, ' ');
  EXPECT_EQ(ErrorOf(Log({kWheels + padding})),
            "test.ndjson:2: line: longer than 1 MiB (1048576 bytes, the protocol's limit)");
  // At the limit exactly (with or without "\r") the line is read.
  const std::string at_limit = kWheels + std::string(kMaxLogLineBytes - kWheels.size(), ' ');
  EXPECT_EQ(ReadText(Log({at_limit})).messages.size(), 1u);
  EXPECT_EQ(ReadText(Log({at_limit + "\r"})).messages.size(), 1u);
  // Lines that end at or around the reader's internal block size (16 KiB) are read whole.
  for (const std::size_t size : {std::size_t{16382}, std::size_t{16383}, std::size_t{16384}, std::size_t{32767}}) {
    const ReadLog log = ReadText(Log({kWheels + std::string(size - kWheels.size(), ' '), kWheels}));
    EXPECT_EQ(log.messages.size(), 2u) << size;
  }
}

using rowloc::test::CountingFillBuffer;

TEST(SensorLogReaderErrors, OverlongLineIsRefusedAtTheLimitNotAtItsEnd) {
  // Issue 26: a 6 GiB line (or /dev/zero as a log) was read whole before the limit was checked.
  // Here a 256 MiB header line without a newline: the reader stops after about 1 MiB of it.
  CountingFillBuffer zeros("", '\0', std::size_t{256} << 20);
  std::istream in(&zeros);
  try {
    SensorLogReader reader(in, "zeros");
    ADD_FAILURE() << "read a header from zeros";
  } catch (const SensorLogError& error) {
    EXPECT_EQ(std::string(error.what()), "zeros:1: line: longer than 1 MiB (1048576 bytes, the protocol's limit)");
  }
  EXPECT_LT(zeros.handed_out(), kMaxLogLineBytes + (std::size_t{1} << 17));
}

TEST(SensorLogReader, GoesOnAfterAnOverlongLineWithoutHoldingIt) {
  const std::string text = Log({kWheels, kWheels + std::string(3 * kMaxLogLineBytes, ' '), kWheels});
  std::istringstream in(text);
  SensorLogReader reader(in, "test.ndjson");
  EXPECT_TRUE(reader.Next().has_value());
  try {
    (void)reader.Next();
    ADD_FAILURE() << "read an overlong line";
  } catch (const SensorLogError& error) {
    EXPECT_EQ(error.line(), 3u);
  }
  EXPECT_TRUE(reader.Next().has_value());  // the line after the overlong one
  EXPECT_EQ(reader.line_number(), 4u);
  EXPECT_FALSE(reader.Next().has_value());
}

TEST(SensorLogReader, ALineJustOverTheLimitDoesNotTakeTheNextLineWithIt) {
  // A line whose "\n" arrives in the same block as its limit-crossing bytes was refused and then
  // the line after it was skipped as the overlong line's "rest" (lost, and every later line number
  // one short). Lengths from the limit + 1 to a block beyond the limit.
  for (const std::size_t over : {std::size_t{1}, std::size_t{2}, std::size_t{3}, std::size_t{100}, std::size_t{16383},
                                 std::size_t{16384}, std::size_t{16385}}) {
    const std::string overlong = kWheels + std::string(kMaxLogLineBytes + over - kWheels.size(), ' ');
    const std::string text = Log({overlong, kWheels, kWheels});
    std::istringstream in(text);
    SensorLogReader reader(in, "test.ndjson");
    try {
      (void)reader.Next();
      ADD_FAILURE() << "read an overlong line, " << over << " bytes over";
    } catch (const SensorLogError& error) {
      EXPECT_EQ(error.line(), 2u) << over;
    }
    std::size_t after = 0;
    while (reader.Next()) ++after;
    EXPECT_EQ(after, 2u) << over;  // both lines after the overlong one
    EXPECT_EQ(reader.line_number(), 4u) << over;
  }
}

TEST(SensorLogReaderErrors, HeaderNameListsHaveALimit) {
  // Issue 26: 100,000 wheel names took 13-25 s to reject (a quadratic duplicate check).
  std::string names;
  for (int i = 0; i < 100000; ++i) names += std::string(i ? "," : "") + "\"w" + std::to_string(i) + "\"";
  std::string header = kHeader;
  header.replace(header.find(R"(["left","right"])"), 16, "[" + names + "]");
  EXPECT_EQ(ErrorOf(header + "\n"), "test.ndjson:1: wheels: 100000 names, more than the limit of 64");
  std::string sensors;
  for (int i = 0; i < 257; ++i) sensors += std::string(i ? "," : "") + "\"u" + std::to_string(i) + "\"";
  header = kHeader;
  header.replace(header.find(R"(["us_left"])"), 11, "[" + sensors + "]");
  EXPECT_EQ(ErrorOf(header + "\n"), "test.ndjson:1: ultrasonic: 257 names, more than the limit of 256");
  // At the limit, with the duplicate last: found by the (linear) set check.
  std::string at_limit;
  for (int i = 0; i < 64; ++i) at_limit += std::string(i ? "," : "") + "\"w" + std::to_string(i == 63 ? 0 : i) + "\"";
  header = kHeader;
  header.replace(header.find(R"(["left","right"])"), 16, "[" + at_limit + "]");
  EXPECT_EQ(ErrorOf(header + "\n"), "test.ndjson:1: wheels[63]: duplicate name \"w0\"");
}

}  // namespace
}  // namespace rowloc::formats
