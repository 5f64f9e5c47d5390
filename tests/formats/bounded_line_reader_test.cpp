// BoundedLineReader: lines, terminators and numbers as a plain line split gives them, for every
// length around the limit and the reader's 16 KiB blocks; a longer line refused after at most
// limit + 2 bytes held, its rest skipped, and the line after it read.
#include "rowloc/formats/bounded_line_reader.hpp"

#include "counting_fill_buffer.hpp"

#include <gtest/gtest.h>

#include <random>
#include <sstream>
#include <stdexcept>
#include <string>
#include <vector>

namespace rowloc::formats {
namespace {

using Result = BoundedLineReader::Result;
using rowloc::test::CountingFillBuffer;

struct Line {
  Result result;
  std::string text;
  std::size_t number;
  bool operator==(const Line&) const = default;
};

std::ostream& operator<<(std::ostream& out, const Line& line) {
  return out << "{result " << static_cast<int>(line.result) << ", " << line.text.size() << " bytes, line "
             << line.number << "}";
}

/// Everything the reader returns for `text`, up to kEnd (not included).
std::vector<Line> ReadAll(const std::string& text, std::size_t max_line_bytes) {
  std::istringstream in(text);
  BoundedLineReader reader(in, max_line_bytes);
  std::vector<Line> lines;
  std::string line;
  for (Result r; (r = reader.Read(line)) != Result::kEnd;) {
    lines.push_back({r, line, reader.line_number()});
    if (r == Result::kReadError || lines.size() > text.size() + 1) break;
  }
  return lines;
}

/// What the contract says, from a plain split of the whole text at "\n".
std::vector<Line> Expected(const std::string& text, std::size_t max_line_bytes) {
  std::vector<Line> lines;
  std::size_t start = 0;
  while (start < text.size()) {
    const std::size_t end = text.find('\n', start);
    const bool terminated = end != std::string::npos;
    std::string line = text.substr(start, terminated ? end - start : std::string::npos);
    if (!line.empty() && line.back() == '\r') line.pop_back();
    const std::size_t number = lines.size() + 1;
    if (line.size() > max_line_bytes) {
      lines.push_back({Result::kTooLong, "", number});
    } else {
      lines.push_back({terminated ? Result::kLine : Result::kUnterminated, line, number});
    }
    start = terminated ? end + 1 : text.size();
  }
  return lines;
}

TEST(BoundedLineReader, ReadsLinesAndNumbersThem) {
  const std::vector<Line> lines = ReadAll("one\n\ntwo\r\n\r\nthree", 100);
  const std::vector<Line> expected = {{Result::kLine, "one", 1},
                                      {Result::kLine, "", 2},
                                      {Result::kLine, "two", 3},
                                      {Result::kLine, "", 4},
                                      {Result::kUnterminated, "three", 5}};
  EXPECT_EQ(lines, expected);
  EXPECT_TRUE(ReadAll("", 100).empty());
  EXPECT_EQ(ReadAll("a\rb\n", 100), (std::vector<Line>{{Result::kLine, "a\rb", 1}}));  // only a final "\r" goes
  EXPECT_THROW(BoundedLineReader(std::cin, 0), std::invalid_argument);
}

TEST(BoundedLineReader, TheLimitExcludesTheTerminators) {
  const std::string at_limit(10, 'x');
  EXPECT_EQ(ReadAll(at_limit + "\n", 10), (std::vector<Line>{{Result::kLine, at_limit, 1}}));
  EXPECT_EQ(ReadAll(at_limit + "\r\n", 10), (std::vector<Line>{{Result::kLine, at_limit, 1}}));
  EXPECT_EQ(ReadAll(at_limit + "\r", 10), (std::vector<Line>{{Result::kUnterminated, at_limit, 1}}));
  EXPECT_EQ(ReadAll(at_limit + "x\n", 10), (std::vector<Line>{{Result::kTooLong, "", 1}}));
  EXPECT_EQ(ReadAll(at_limit + "x\r\n", 10), (std::vector<Line>{{Result::kTooLong, "", 1}}));
  EXPECT_EQ(ReadAll(at_limit + "x", 10), (std::vector<Line>{{Result::kTooLong, "", 1}}));
}

TEST(BoundedLineReader, AgreesWithAPlainSplitAroundTheLimitAndTheBlocks) {
  // Every line length from 0 to limit + 20, with and without "\r", followed by a short line, for
  // limits below, at and above the 16 KiB block: too-long lines never take the next line along.
  std::mt19937 rng(26);
  for (const std::size_t limit : {std::size_t{1}, std::size_t{2}, std::size_t{7}, std::size_t{16381},
                                  std::size_t{16382}, std::size_t{16383}, std::size_t{16384}, std::size_t{40000}}) {
    const std::size_t from = limit > 100 ? limit - 20 : 0;
    for (std::size_t length = from; length <= limit + 20; ++length) {
      for (const char* ending : {"\n", "\r\n"}) {
        std::string long_line(length, 'a');
        if (!long_line.empty()) long_line[rng() % long_line.size()] = 'b';
        const std::string text = "first\n" + long_line + ending + "next\n" + long_line;
        ASSERT_EQ(ReadAll(text, limit), Expected(text, limit)) << "limit " << limit << ", length " << length;
      }
    }
  }
  // Lines ending at and around the block size and its multiples, under a large limit.
  for (const std::size_t length : {std::size_t{16382}, std::size_t{16383}, std::size_t{16384}, std::size_t{16385},
                                   std::size_t{32766}, std::size_t{32767}, std::size_t{32768}, std::size_t{49151}}) {
    const std::string text = std::string(length, 'c') + "\n" + std::string(length, 'd') + "\r\nend\n";
    ASSERT_EQ(ReadAll(text, kMaxProtocolLineBytes), Expected(text, kMaxProtocolLineBytes)) << length;
  }
}

TEST(BoundedLineReader, HoldsAtMostTheLimitOfAnEndlessLine) {
  // Issue 26: /dev/zero given as a log was read whole (4 GB and more) before the limit was checked.
  CountingFillBuffer zeros("", '\0', std::size_t{256} << 20);  // 256 MiB without a newline
  std::istream in(&zeros);
  BoundedLineReader reader(in, kMaxProtocolLineBytes);
  std::string line;
  EXPECT_EQ(reader.Read(line), Result::kTooLong);
  EXPECT_TRUE(line.empty());
  EXPECT_LE(zeros.handed_out(), kMaxProtocolLineBytes + 2 + (std::size_t{1} << 16));  // + one block of the buffer
  EXPECT_EQ(reader.line_number(), 1u);
  // Its rest is skipped (read, not stored) by the next call, which finds the end.
  EXPECT_EQ(reader.Read(line), Result::kEnd);
  EXPECT_EQ(zeros.handed_out(), std::size_t{256} << 20);
}

TEST(BoundedLineReader, SkipsTheRestOfAnOverlongLineAndGoesOn) {
  const std::string text = "a\n" + std::string(3 * kMaxProtocolLineBytes, 'z') + "\nb\n";
  const std::vector<Line> expected = {{Result::kLine, "a", 1}, {Result::kTooLong, "", 2}, {Result::kLine, "b", 3}};
  EXPECT_EQ(ReadAll(text, kMaxProtocolLineBytes), expected);
}

/// A stream buffer whose reads fail after `good` bytes of "x\n" lines (as read(2) failing with EIO).
class FailingBuffer : public std::streambuf {
 public:
  explicit FailingBuffer(std::size_t lines) : lines_(lines) {}

 protected:
  int_type underflow() override {
    if (lines_ == 0) throw std::runtime_error("EIO");
    --lines_;
    setg(line_, line_, line_ + 2);
    return traits_type::to_int_type(line_[0]);
  }

 private:
  std::size_t lines_;
  char line_[2] = {'x', '\n'};
};

TEST(BoundedLineReader, ReportsAReadError) {
  FailingBuffer failing(2);
  std::istream in(&failing);
  BoundedLineReader reader(in, 100);
  std::string line;
  EXPECT_EQ(reader.Read(line), Result::kLine);
  EXPECT_EQ(reader.Read(line), Result::kLine);
  EXPECT_EQ(reader.Read(line), Result::kReadError);
  EXPECT_EQ(reader.line_number(), 2u);
  EXPECT_EQ(reader.Read(line), Result::kReadError);
}

}  // namespace
}  // namespace rowloc::formats
