// Reader of the NDJSON sensor log of docs/protocol.md §1 (written by `rowloc simulate` and by the
// service's session journals; read by `rowloc replay` and, one line at a time, by the service).
//
// Rules enforced (docs/protocol.md, conventions and §1; §4 "Reading a log" lists them):
// - one JSON object per line, at most kMaxLogLineBytes bytes, "\n"-terminated ("\r\n" accepted);
//   empty lines are skipped (as service/line_framer.hpp does) but counted in line numbers;
// - the first line is a `log_header` of protocol major version 1 ("rowloc/1", or "rowloc/1.N");
//   another major version, or a stream without a header, is refused;
// - every key a message defines is required unless the protocol calls it optional (`torque_nm`;
//   the position keys of a `gps` message whose `fix` is "none", which are then not read), with the
//   right JSON type; numbers must be finite (JSON has no NaN or infinity, so a non-finite number is
//   one beyond the range of a double, such as 1e999: refused, naming its key);
// - wheel names in `wheels` and `steering`, and the `sensor` of `ultrasonic`, must be listed in the
//   header (an unknown name is an error); `speed_radps` (and `torque_nm` when present) carries every
//   wheel of the header;
// - inside one log `t` never decreases (checked by SensorLogReader, not by ParseSensorMessage,
//   which sees one line), except in a log whose header has a `reorder_window_s` > 0 (a service
//   journal, in arrival order: its reader orders it with localization/reorder_buffer.hpp);
// - unknown keys are ignored (forward compatibility); an unknown message `type` is an error in this
//   version (a later protocol version may relax that, e.g. to skip types it declares optional), and
//   so is a second `log_header`.
// Beyond the letter of the protocol, values that no sensor can produce are refused: latitude outside
// [-90, 90] deg, longitude outside [-180, 180] deg, sigmas <= 0, an ultrasonic range <= 0 (no echo is
// null, never a zero range), a steering angle outside [-pi, pi] (angles are wrapped), empty or
// duplicate names in the header.
//
// Every error is a SensorLogError whose message is "<source>:<line>: <key or subject>: <reason>",
// e.g. "sensors.ndjson:12: speed_radps.rear_left: missing (every wheel of the log header must appear
// in speed_radps)". Nested keys are joined with '.'; whole-line problems use the subject "line".
#pragma once

#include "rowloc/formats/bounded_line_reader.hpp"
#include "rowloc/formats/sensor_messages.hpp"

#include <nlohmann/json_fwd.hpp>

#include <cstddef>
#include <istream>
#include <limits>
#include <optional>
#include <stdexcept>
#include <string>
#include <string_view>

namespace rowloc::formats {

/// Longest accepted line, terminator excluded (docs/protocol.md: "at most 1 MiB per line").
inline constexpr std::size_t kMaxLogLineBytes = kMaxProtocolLineBytes;
/// Most wheel (or track) names in a log header (docs/protocol.md §1; a vehicle file has at most 16).
inline constexpr std::size_t kMaxLogWheels = 64;
/// Most ultrasonic sensor names in a log header (docs/protocol.md §1; a vehicle file has at most 64).
inline constexpr std::size_t kMaxLogUltrasonicSensors = 256;

/// A defect of a sensor log or message, located by source and 1-based line number.
class SensorLogError : public std::runtime_error {
 public:
  SensorLogError(std::string source, std::size_t line, std::string subject, std::string reason);

  const std::string& source() const { return source_; }
  std::size_t line() const { return line_; }
  /// The key (path such as "origin.latitude_deg"), "type", "line" or a message type.
  const std::string& subject() const { return subject_; }
  const std::string& reason() const { return reason_; }

 private:
  std::string source_;
  std::size_t line_;
  std::string subject_;
  std::string reason_;
};

/// Parses a `log_header` line. `source` names the input in errors (a file name, a session).
/// Throws SensorLogError.
LogHeader ParseLogHeader(std::string_view line, const std::string& source, std::size_t line_number = 1);

/// Parses one sensor message line against `header` (wheel and sensor names). Does not check the
/// time order, which needs the previous message. Throws SensorLogError.
SensorMessage ParseSensorMessage(std::string_view line, const LogHeader& header, const std::string& source,
                                 std::size_t line_number);
/// The same for a line already parsed into JSON (the service parses each request line once).
SensorMessage ParseSensorMessageObject(const nlohmann::json& object, const LogHeader& header,
                                       const std::string& source, std::size_t line_number);

/// Reads a whole log from a stream: the header on construction, then one message per Next().
/// After a SensorLogError from Next() the bad line is consumed: calling Next() again goes on with
/// the following line, and the time order is checked against the last message returned.
class SensorLogReader {
 public:
  /// Reads the header (the first non-empty line). Throws SensorLogError for an empty stream, a first
  /// line that is not a valid `log_header`, or a read failure. `in` must outlive the reader.
  SensorLogReader(std::istream& in, std::string source);

  const LogHeader& header() const { return header_; }

  /// The next message, or nullopt at the end of the log. Throws SensorLogError.
  std::optional<SensorMessage> Next();

  /// 1-based number of the last line read (0 before any).
  std::size_t line_number() const { return lines_.line_number(); }
  /// Messages returned by Next() so far.
  std::size_t messages_read() const { return messages_read_; }
  /// False after a read error of the stream (Next() would fail again): a SensorLogError is then
  /// the end of the log, not one bad line to skip.
  bool readable() const { return !in_.bad(); }

 private:
  /// Reads the next non-empty line into `line` (terminator removed); false at the end of the stream.
  /// A line longer than kMaxLogLineBytes is refused after its first kMaxLogLineBytes + 2 bytes; the
  /// next call skips its rest without storing it (BoundedLineReader).
  bool ReadLine(std::string& line);
  LogHeader ReadHeader();

  std::istream& in_;
  std::string source_;
  BoundedLineReader lines_;
  LogHeader header_;  // after the members ReadHeader() uses: initialized by it
  double last_time_s_ = -std::numeric_limits<double>::infinity();
  std::size_t messages_read_ = 0;
};

}  // namespace rowloc::formats
