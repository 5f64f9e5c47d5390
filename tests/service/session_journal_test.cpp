// The per-session journal: what it writes, its size limit, its cut of a torn last line, and close.
#include "rowloc/service/session_journal.hpp"

#include "rowloc/service/service_error.hpp"

#include "test_support.hpp"

#include <gtest/gtest.h>

#include <fstream>
#include <sstream>

namespace rowloc::service {
namespace {

std::string Read(const std::filesystem::path& path) {
  std::ifstream in(path, std::ios::binary);
  std::ostringstream text;
  text << in.rdbuf();
  return text.str();
}

TEST(SessionJournal, WritesHeaderMetadataAndLinesOnFlush) {
  rowloc::test::ScratchDir dir;
  auto journal = SessionJournal::Create(dir.path(), "s1", R"({"session":"s1"})", "HEADER", 1 << 20,
                                        FsyncPolicy::kAlways);
  EXPECT_EQ(Read(dir / "s1.session.json"), "{\"session\":\"s1\"}\n");
  journal->Append("one");
  journal->Append("two");
  EXPECT_EQ(Read(dir / "s1.ndjson"), "HEADER\n");  // buffered until the batch ends
  EXPECT_TRUE(journal->dirty());
  journal->Flush();
  EXPECT_EQ(Read(dir / "s1.ndjson"), "HEADER\none\ntwo\n");
  EXPECT_FALSE(journal->dirty());
  EXPECT_EQ(SessionJournal::OpenSessions(dir.path()), std::vector<std::string>{"s1"});
  EXPECT_THROW(SessionJournal::Create(dir.path(), "s1", "{}", "H", 1 << 20, FsyncPolicy::kNone), std::runtime_error);
}

TEST(SessionJournal, RefusesAppendsPastItsLimit) {
  rowloc::test::ScratchDir dir;
  auto journal = SessionJournal::Create(dir.path(), "s", "{}", "HEADER", 20, FsyncPolicy::kNone);
  journal->Append("12345678");
  try {
    journal->Append("12345678");
    FAIL() << "accepted past the limit";
  } catch (const ServiceError& e) {
    EXPECT_EQ(e.code(), ErrorCode::kLimitExceeded);
  }
  journal->Flush();
  EXPECT_EQ(Read(dir / "s.ndjson"), "HEADER\n12345678\n");  // nothing half-written
}

TEST(SessionJournal, ReopenCutsATornLastLineAndAppends) {
  rowloc::test::ScratchDir dir;
  SessionJournal::Create(dir.path(), "s", "{}", "HEADER", 1 << 20, FsyncPolicy::kInterval)->Append("kept");
  std::ofstream(dir / "s.ndjson", std::ios::app) << "torn-li";
  std::size_t cut = 0;
  auto journal = SessionJournal::Reopen(dir.path(), "s", 1 << 20, FsyncPolicy::kInterval, cut);
  EXPECT_EQ(cut, 7u);
  journal->Append("next");
  journal->Sync();
  EXPECT_EQ(Read(dir / "s.ndjson"), "HEADER\nkept\nnext\n");
}

TEST(SessionJournal, CloseMovesBothFilesAside) {
  rowloc::test::ScratchDir dir;
  for (int round = 1; round <= 2; ++round) {
    auto journal = SessionJournal::Create(dir.path(), "s", "{}", "HEADER", 1 << 20, FsyncPolicy::kInterval);
    journal->Append("line");
    const auto closed = journal->Close();
    EXPECT_EQ(closed, dir / "closed" / ("s-" + std::to_string(round) + ".ndjson"));
    EXPECT_EQ(Read(closed), "HEADER\nline\n");
    EXPECT_TRUE(std::filesystem::exists(dir / "closed" / ("s-" + std::to_string(round) + ".session.json")));
    EXPECT_TRUE(SessionJournal::OpenSessions(dir.path()).empty());
  }
}

}  // namespace
}  // namespace rowloc::service
