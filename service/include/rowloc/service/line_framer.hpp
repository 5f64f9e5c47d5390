// Newline-delimited framing of a byte stream (the service protocol is one JSON message per
// line, docs/protocol.md). Bytes arrive in arbitrary chunks from a socket; the framer returns complete
// lines, strips "\r\n" and "\n", skips blank lines, and enforces a maximum line length so that
// a client that never sends a newline cannot grow a buffer without bound: an over-long line is
// reported once (with its line number) and its bytes are discarded up to the next newline.
#pragma once

#include <cstddef>
#include <optional>
#include <string>
#include <string_view>
#include <vector>

namespace rowloc::service {

/// One outcome of framing.
struct FramedLine {
  enum class Kind {
    kLine,          ///< a complete line, without its terminator
    kOversized,     ///< a line longer than the limit; `text` holds its first bytes (<= 64)
    kUnterminated,  ///< end of stream in the middle of a line (from Finish() only)
  };
  Kind kind;
  std::string text;
  std::size_t line_number;  ///< 1-based, counting every newline-terminated line, blank ones too
};

class LineFramer {
 public:
  /// max_line_bytes: longest accepted line, terminator excluded; must be > 0.
  explicit LineFramer(std::size_t max_line_bytes);

  /// Consumes a chunk and returns the lines it completed, in order.
  std::vector<FramedLine> Feed(std::string_view bytes);

  /// End of stream: a pending partial line is returned as kUnterminated (never silently lost).
  std::optional<FramedLine> Finish();

  std::size_t pending_bytes() const { return pending_.size(); }
  std::size_t max_line_bytes() const { return max_line_bytes_; }

 private:
  void CompleteLine(std::vector<FramedLine>& out);

  std::size_t max_line_bytes_;
  std::string pending_;
  bool discarding_ = false;  // inside an over-long line, skipping to its newline
  std::size_t line_number_ = 0;
};

}  // namespace rowloc::service
