#include "rowloc/service/line_framer.hpp"

#include <stdexcept>

namespace rowloc::service {

namespace {
constexpr std::size_t kOversizedPreviewBytes = 64;
}

LineFramer::LineFramer(std::size_t max_line_bytes) : max_line_bytes_(max_line_bytes) {
  if (max_line_bytes == 0) throw std::invalid_argument("LineFramer: max_line_bytes must be > 0");
}

void LineFramer::CompleteLine(std::vector<FramedLine>& out) {
  ++line_number_;
  if (discarding_) {
    discarding_ = false;
    pending_.clear();
    return;
  }
  if (!pending_.empty() && pending_.back() == '\r') pending_.pop_back();
  if (!pending_.empty()) out.push_back({FramedLine::Kind::kLine, std::move(pending_), line_number_});
  pending_.clear();
}

std::vector<FramedLine> LineFramer::Feed(std::string_view bytes) {
  std::vector<FramedLine> out;
  while (!bytes.empty()) {
    const std::size_t newline = bytes.find('\n');
    const std::string_view chunk = bytes.substr(0, newline);
    if (!discarding_) {
      pending_.append(chunk);
      // +1 leaves room for a '\r' that belongs to a "\r\n" terminator.
      const bool may_end_in_cr = pending_.size() == max_line_bytes_ + 1 && pending_.back() == '\r';
      if (pending_.size() > max_line_bytes_ && !may_end_in_cr) {
        out.push_back({FramedLine::Kind::kOversized, pending_.substr(0, kOversizedPreviewBytes),
                       line_number_ + 1});
        pending_.clear();
        discarding_ = true;
      }
    }
    if (newline == std::string_view::npos) break;
    CompleteLine(out);
    bytes.remove_prefix(newline + 1);
  }
  return out;
}

std::optional<FramedLine> LineFramer::Finish() {
  if (discarding_ || pending_.empty()) {
    discarding_ = false;
    pending_.clear();
    return std::nullopt;
  }
  FramedLine line{FramedLine::Kind::kUnterminated, std::move(pending_), line_number_ + 1};
  pending_.clear();
  return line;
}

}  // namespace rowloc::service
