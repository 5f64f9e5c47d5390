// A one-line progress display on stderr for long commands (`rowloc map build`): the stage's name,
// a bar when the total is known ("tiles  [##########..........]  12/40"), else a running count
// ("read   1234567 points"). It redraws in place with '\r' and ends its line when the stage
// changes or the display is destroyed. Redraws are limited to every 1/100 of the total or every
// 2^16 units, so the cost does not depend on how often it is called.
#pragma once

#include <fmt/format.h>

#include <algorithm>
#include <cstddef>
#include <cstdio>
#include <string>
#include <string_view>

namespace rowloc::apps {

class ProgressBar {
 public:
  explicit ProgressBar(std::FILE* out) : out_(out) {}
  ~ProgressBar() { EndLine(); }
  ProgressBar(const ProgressBar&) = delete;
  ProgressBar& operator=(const ProgressBar&) = delete;

  /// done of total units of a stage; total 0: unknown (a count is shown).
  void Update(std::string_view stage, std::size_t done, std::size_t total) {
    if (stage != stage_) {
      EndLine();
      stage_ = std::string(stage);
      last_ = 0;
    } else {
      const std::size_t step = total > 0 ? std::max<std::size_t>(1, total / 100) : std::size_t{1} << 16;
      if (done < total && done - last_ < step) return;
    }
    last_ = done;
    if (total > 0) {
      constexpr int kWidth = 30;
      const int filled = static_cast<int>(static_cast<double>(kWidth) * static_cast<double>(std::min(done, total)) /
                                          static_cast<double>(total));
      fmt::print(out_, "\r  {:<8} [{}{}] {}/{}", stage_, std::string(static_cast<std::size_t>(filled), '#'),
                 std::string(static_cast<std::size_t>(kWidth - filled), '.'), done, total);
    } else {
      fmt::print(out_, "\r  {:<8} {} points", stage_, done);
    }
    std::fflush(out_);
    open_ = true;
  }

 private:
  void EndLine() {
    if (!open_) return;
    fmt::print(out_, "\n");
    std::fflush(out_);
    open_ = false;
  }

  std::FILE* out_;
  std::string stage_;
  std::size_t last_ = 0;
  bool open_ = false;
};

}  // namespace rowloc::apps
