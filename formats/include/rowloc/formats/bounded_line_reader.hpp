// Reading "\n"-terminated lines from a stream with a bound on the memory one line may take. Every
// NDJSON input rowloc reads line by line goes through it (the sensor-log reader, the truth and
// estimate stream readers, `rowloc send`, the service's journal resume), so that no input can make a
// reader hold more than its limit: issue 26 found a 6 GiB line without a newline, and /dev/zero given
// as a log, read whole before the line's length was checked.
//
// Contract of Read():
//   - It holds at most max_line_bytes + 2 bytes of a line (the limit, a "\r" before the "\n", and
//     one byte more that proves the line too long), read in blocks of at most 16 KiB.
//   - A longer line is reported (kTooLong) as soon as those bytes have been read; the next Read()
//     skips the rest of it, up to and including its "\n", without storing it, and returns the line
//     after it. (An endless line, such as /dev/zero, is thus refused after max_line_bytes + 2 bytes;
//     skipping the rest of it reads until the stream ends.)
//   - The "\n" and a "\r" just before it are removed; the "\r" does not count against the limit.
//   - Lines are numbered from 1, empty lines included; a too-long line has its number too.
// The reader does not interpret the bytes (JSON, UTF-8): its callers do.
#pragma once

#include <cstddef>
#include <istream>
#include <string>

namespace rowloc::formats {

/// Longest line of the protocol's NDJSON streams, terminator excluded (docs/protocol.md: "at most
/// 1 MiB per line"): sensor logs, truth and estimate streams.
inline constexpr std::size_t kMaxProtocolLineBytes = std::size_t{1} << 20;

/// Reads the lines of a stream, each at most max_line_bytes long (contract above).
class BoundedLineReader {
 public:
  enum class Result {
    kLine,          ///< a "\n"-terminated line of at most max_line_bytes
    kUnterminated,  ///< the stream's last line, not terminated by "\n" (at most max_line_bytes)
    kTooLong,       ///< a line longer than max_line_bytes; `line` is left empty
    kEnd,           ///< the end of the stream: no more lines
    kReadError,     ///< the stream failed (badbit): no line; later calls fail again
  };

  /// `in` must outlive the reader; max_line_bytes > 0.
  BoundedLineReader(std::istream& in, std::size_t max_line_bytes);

  /// The next line into `line` (replacing its content); see Result.
  Result Read(std::string& line);

  /// 1-based number of the last line read (kLine, kUnterminated or kTooLong); 0 before any.
  std::size_t line_number() const { return line_number_; }
  std::size_t max_line_bytes() const { return max_line_bytes_; }

 private:
  std::istream& in_;
  std::size_t max_line_bytes_;
  std::size_t line_number_ = 0;
  bool skip_rest_of_line_ = false;  ///< the last line was too long: its rest is still in in_
};

}  // namespace rowloc::formats
