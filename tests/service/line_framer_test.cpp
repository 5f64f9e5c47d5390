#include "rowloc/service/line_framer.hpp"

#include <gtest/gtest.h>

#include <random>
#include <stdexcept>

namespace rowloc::service {
namespace {

using Kind = FramedLine::Kind;

TEST(LineFramer, SplitsLinesAndStripsTerminators) {
  LineFramer framer(100);
  const auto lines = framer.Feed("{\"a\":1}\n{\"b\":2}\r\n");
  ASSERT_EQ(lines.size(), 2u);
  EXPECT_EQ(lines[0].kind, Kind::kLine);
  EXPECT_EQ(lines[0].text, "{\"a\":1}");
  EXPECT_EQ(lines[0].line_number, 1u);
  EXPECT_EQ(lines[1].text, "{\"b\":2}");
  EXPECT_EQ(lines[1].line_number, 2u);
  EXPECT_EQ(framer.pending_bytes(), 0u);
}

TEST(LineFramer, ReassemblesLinesSplitAcrossArbitraryChunks) {
  const std::string stream = "first line\nsecond\r\n\nthird one here\n";
  std::mt19937 rng(3);
  for (int trial = 0; trial < 200; ++trial) {
    LineFramer framer(64);
    std::vector<FramedLine> lines;
    std::size_t pos = 0;
    while (pos < stream.size()) {
      const std::size_t len = std::uniform_int_distribution<std::size_t>(1, 7)(rng);
      for (auto& l : framer.Feed(std::string_view(stream).substr(pos, len))) lines.push_back(l);
      pos += len;
    }
    ASSERT_EQ(lines.size(), 3u);
    EXPECT_EQ(lines[0].text, "first line");
    EXPECT_EQ(lines[1].text, "second");
    EXPECT_EQ(lines[2].text, "third one here");
    EXPECT_EQ(lines[2].line_number, 4u);  // the blank line 3 is skipped but counted
  }
}

TEST(LineFramer, OversizedLineIsReportedOnceAndDiscarded) {
  LineFramer framer(8);
  auto out = framer.Feed("0123456789abcdef");
  ASSERT_EQ(out.size(), 1u);
  EXPECT_EQ(out[0].kind, Kind::kOversized);
  EXPECT_EQ(out[0].line_number, 1u);
  EXPECT_EQ(out[0].text, "0123456789abcdef");
  EXPECT_TRUE(framer.Feed("more and more bytes").empty());  // still discarding, buffer stays empty
  EXPECT_EQ(framer.pending_bytes(), 0u);
  out = framer.Feed("tail\nok\n");
  ASSERT_EQ(out.size(), 1u);
  EXPECT_EQ(out[0].kind, Kind::kLine);
  EXPECT_EQ(out[0].text, "ok");
  EXPECT_EQ(out[0].line_number, 2u);
}

TEST(LineFramer, LineOfExactlyTheLimitIsAcceptedWithEitherTerminator) {
  LineFramer framer(4);
  auto out = framer.Feed("abcd\nefgh\r\nijklm\n");
  ASSERT_EQ(out.size(), 3u);
  EXPECT_EQ(out[0].text, "abcd");
  EXPECT_EQ(out[1].text, "efgh");
  EXPECT_EQ(out[2].kind, Kind::kOversized);
}

TEST(LineFramer, FinishReturnsAnUnterminatedTail) {
  LineFramer framer(100);
  EXPECT_TRUE(framer.Feed("{\"partial\":").empty());
  const auto tail = framer.Finish();
  ASSERT_TRUE(tail.has_value());
  EXPECT_EQ(tail->kind, Kind::kUnterminated);
  EXPECT_EQ(tail->text, "{\"partial\":");
  EXPECT_FALSE(framer.Finish().has_value());
}

TEST(LineFramer, RejectsZeroLimit) { EXPECT_THROW(LineFramer(0), std::invalid_argument); }

}  // namespace
}  // namespace rowloc::service
