// libFuzzer target over the sensor-log reader (docs/protocol.md §1; docs/building.md, "Fuzzing"):
// the input's first line is a log header, the rest are message lines.
//   - ParseLogHeader on the first line;
//   - ParseSensorMessage on every other line, against that header when it parsed, else against the
//     header of tests/data/logs/agrimaro-tiles-head.ndjson (so message lines are fuzzed either way);
//   - SensorLogReader over the whole input (the time order, blank lines, "\r\n").
// Every function may throw SensorLogError only (sensor_log_reader.hpp): any other exception
// escapes and libFuzzer reports it as a crash, as it does sanitizer errors.
#include "rowloc/formats/sensor_log_reader.hpp"

#include <cstdint>
#include <optional>
#include <sstream>
#include <string>
#include <string_view>

namespace {

using rowloc::formats::LogHeader;
using rowloc::formats::SensorLogError;

const LogHeader& FallbackHeader() {
  static const LogHeader header = rowloc::formats::ParseLogHeader(
      R"({"type":"log_header","protocol":"rowloc/1","source":"rowloc simulate","scenario":"agrimaro-tiles",)"
      R"("vehicle":"agrimaro-swerve","origin":{"latitude_deg":45.0628,"longitude_deg":7.6621,"altitude_m":240.0},)"
      R"("wheels":["left_front","left_rear","right"],"ultrasonic":[]})",
      "fallback");
  return header;
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  const std::string_view input(reinterpret_cast<const char*>(data), size);
  std::string_view rest = input;
  const std::size_t end = rest.find('\n');
  const std::string_view first = rest.substr(0, end);
  rest.remove_prefix(end == std::string_view::npos ? rest.size() : end + 1);

  std::optional<LogHeader> header;
  try {
    header = rowloc::formats::ParseLogHeader(first, "fuzz");
  } catch (const SensorLogError&) {
  }
  const LogHeader& against = header ? *header : FallbackHeader();
  std::size_t line_number = 1;
  while (!rest.empty()) {
    const std::size_t next = rest.find('\n');
    const std::string_view line = rest.substr(0, next);
    rest.remove_prefix(next == std::string_view::npos ? rest.size() : next + 1);
    ++line_number;
    try {
      rowloc::formats::ParseSensorMessage(line, against, "fuzz", line_number);
    } catch (const SensorLogError&) {
    }
  }

  std::istringstream stream{std::string(input)};
  try {
    rowloc::formats::SensorLogReader reader(stream, "fuzz");
    for (;;) {
      try {
        if (!reader.Next()) break;
      } catch (const SensorLogError&) {
        // the bad line is consumed; the reader goes on with the next one
      }
    }
  } catch (const SensorLogError&) {
    // no valid header
  }
  return 0;
}
