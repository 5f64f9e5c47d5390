// A stream buffer for tests of bounded reading: `prefix`, then `fill` bytes up to `size` bytes in
// all (then the end), handed out in blocks of 64 KiB and counted. An endless or huge line without
// newlines, such as /dev/zero, that shows how much of it a reader has taken.
#pragma once

#include <algorithm>
#include <cstddef>
#include <streambuf>
#include <string>
#include <utility>

namespace rowloc::test {

class CountingFillBuffer : public std::streambuf {
 public:
  CountingFillBuffer(std::string prefix, char fill, std::size_t size)
      : prefix_(std::move(prefix)), size_(size), block_(1 << 16, fill) {}
  /// Bytes handed to the stream so far (the reader has taken at most that many).
  std::size_t handed_out() const { return handed_out_; }

 protected:
  int_type underflow() override {
    if (handed_out_ >= size_) return traits_type::eof();
    std::string& block = handed_out_ < prefix_.size() ? prefix_ : block_;
    const std::size_t n = std::min(block.size(), size_ - handed_out_);
    setg(block.data(), block.data(), block.data() + n);
    handed_out_ += n;
    return traits_type::to_int_type(block[0]);
  }

 private:
  std::string prefix_;
  std::size_t size_;
  std::string block_;
  std::size_t handed_out_ = 0;
};

}  // namespace rowloc::test
