// Bounded line reading (contract in bounded_line_reader.hpp): istream::getline into a block whose
// size never lets the line grow past max_line_bytes + 2 bytes; istream::ignore skips the rest of a
// longer line without storing it.
#include "rowloc/formats/bounded_line_reader.hpp"

#include <algorithm>
#include <limits>
#include <stdexcept>

namespace rowloc::formats {

BoundedLineReader::BoundedLineReader(std::istream& in, std::size_t max_line_bytes)
    : in_(in), max_line_bytes_(max_line_bytes) {
  if (max_line_bytes == 0) throw std::invalid_argument("BoundedLineReader: max_line_bytes must be > 0");
}

BoundedLineReader::Result BoundedLineReader::Read(std::string& line) {
  line.clear();
  if (in_.bad()) return Result::kReadError;
  if (skip_rest_of_line_) {  // the rest of an overlong line: skipped, never held in memory
    skip_rest_of_line_ = false;
    in_.ignore(std::numeric_limits<std::streamsize>::max(), '\n');
    if (in_.bad()) return Result::kReadError;
  }
  // The limit plus one byte for a "\r" before the "\n"; one more byte proves the line too long.
  const std::size_t max_held = max_line_bytes_ + 2;
  constexpr std::size_t kBlockBytes = std::size_t{1} << 14;
  char block[kBlockBytes];
  bool terminated = false;
  for (;;) {
    // getline stores at most `room` - 1 bytes: the line never exceeds max_held (room >= 2 here).
    const std::size_t room = std::min(kBlockBytes, max_held - line.size() + 1);
    in_.getline(block, static_cast<std::streamsize>(room));  // stops at '\n' (extracted), the end, or a full block
    const auto count = static_cast<std::size_t>(in_.gcount());
    if (in_.bad()) {
      line.clear();
      return Result::kReadError;
    }
    if (in_.eof()) {  // the stream ended inside the line (or before it)
      line.append(block, count);
      break;
    }
    if (!in_.fail()) {  // '\n' found and extracted (counted by gcount, not stored)
      line.append(block, count - 1);
      terminated = true;
      break;
    }
    in_.clear();  // a full block without '\n': go on, up to the limit
    line.append(block, count);
    if (line.size() >= max_held) {  // its "\n" (if any) is still ahead: the next Read() skips to it
      ++line_number_;
      line.clear();
      skip_rest_of_line_ = true;
      return Result::kTooLong;
    }
  }
  if (!terminated && line.empty()) return Result::kEnd;
  ++line_number_;
  if (!line.empty() && line.back() == '\r') line.pop_back();
  if (line.size() > max_line_bytes_) {  // its "\n" already read (or the stream ended): nothing to skip
    line.clear();
    return Result::kTooLong;
  }
  return terminated ? Result::kLine : Result::kUnterminated;
}

}  // namespace rowloc::formats
