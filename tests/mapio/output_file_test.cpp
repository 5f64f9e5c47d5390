// Safe output files: a target is replaced only by a complete file, only if it is a regular file,
// and never when it is one of the inputs (also through links); errors give the OS reason.
#include "rowloc/mapio/output_file.hpp"

#include "test_support.hpp"

#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include <sys/stat.h>

#include <fstream>
#include <functional>
#include <sstream>

namespace rowloc::mapio {
namespace {

namespace fs = std::filesystem;
using ::testing::HasSubstr;

std::string Slurp(const fs::path& path) {
  std::ifstream in(path, std::ios::binary);
  std::ostringstream out;
  out << in.rdbuf();
  return out.str();
}

std::size_t EntriesIn(const fs::path& dir) {
  return static_cast<std::size_t>(std::distance(fs::directory_iterator(dir), fs::directory_iterator()));
}

std::string ErrorOf(const std::function<void()>& body) {
  try {
    body();
  } catch (const OutputFileError& e) {
    return e.what();
  }
  return "no error";
}

TEST(OutputFile, CommitReplacesTheTargetAndLeavesNoTemporary) {
  const test::ScratchDir dir;
  std::ofstream(dir / "out.txt") << "old";
  {
    OutputFile file(dir / "out.txt");
    file.stream() << "new content";
    EXPECT_EQ(Slurp(dir / "out.txt"), "old");  // untouched until Commit
    file.Commit();
  }
  EXPECT_EQ(Slurp(dir / "out.txt"), "new content");
  EXPECT_EQ(EntriesIn(dir.path()), 1U);
}

TEST(OutputFile, WithoutCommitTheTargetStaysAsItWas) {
  const test::ScratchDir dir;
  std::ofstream(dir / "out.txt") << "old";
  {
    OutputFile file(dir / "out.txt");
    file.stream() << "half a file";
  }
  EXPECT_EQ(Slurp(dir / "out.txt"), "old");
  EXPECT_EQ(EntriesIn(dir.path()), 1U);
}

TEST(OutputFile, KeepsTheModeOfTheReplacedFile) {
  const test::ScratchDir dir;
  std::ofstream(dir / "out.txt") << "old";
  fs::permissions(dir / "out.txt", fs::perms::owner_read | fs::perms::owner_write | fs::perms::group_read);
  WriteFileAtomically(dir / "out.txt", "new");
  EXPECT_EQ(fs::status(dir / "out.txt").permissions(),
            fs::perms::owner_read | fs::perms::owner_write | fs::perms::group_read);
}

TEST(OutputFile, RefusesADirectoryAndAFifo) {
  const test::ScratchDir dir;
  fs::create_directory(dir / "sub");
  EXPECT_THAT(ErrorOf([&] { WriteFileAtomically(dir / "sub", "x"); }), HasSubstr("is a directory"));
  ASSERT_EQ(::mkfifo((dir / "fifo").c_str(), 0600), 0);
  EXPECT_THAT(ErrorOf([&] { WriteFileAtomically(dir / "fifo", "x"); }), HasSubstr("is a FIFO"));
  EXPECT_TRUE(fs::is_fifo(dir / "fifo"));
  EXPECT_TRUE(fs::is_directory(dir / "sub"));
  EXPECT_EQ(EntriesIn(dir.path()), 2U);  // no temporary left behind
}

TEST(OutputFile, RefusesACharacterDeviceWithoutTouchingIt) {
  // /dev/null is a character device on every Linux; the check comes before any file is created.
  ASSERT_TRUE(fs::is_character_file("/dev/null"));
  EXPECT_THAT(ErrorOf([] { CheckOutputTarget("/dev/null"); }), HasSubstr("is a character device"));
}

TEST(OutputFile, MissingDirectoryIsAnErrorWithTheReason) {
  const test::ScratchDir dir;
  const fs::path path = dir / "no" / "such" / "file.txt";
  try {
    WriteFileAtomically(path, "x");
    FAIL() << "wrote into a missing directory";
  } catch (const OutputFileError& e) {
    EXPECT_EQ(e.code(), std::errc::no_such_file_or_directory);
    EXPECT_THAT(std::string(e.what()), HasSubstr(path.string()));
    EXPECT_THAT(std::string(e.what()), HasSubstr("does not exist"));
  }
}

TEST(OutputFile, FollowsASymbolicLinkAndReplacesTheLinkedFile) {
  const test::ScratchDir dir;
  std::ofstream(dir / "real.txt") << "old";
  fs::create_symlink(dir / "real.txt", dir / "link.txt");
  WriteFileAtomically(dir / "link.txt", "new");
  EXPECT_TRUE(fs::is_symlink(dir / "link.txt"));
  EXPECT_EQ(Slurp(dir / "real.txt"), "new");
}

TEST(CheckOutputPaths, RefusesAnOutputThatIsAnInputByNameHardLinkOrSymbolicLink) {
  const test::ScratchDir dir;
  std::ofstream(dir / "log.ndjson") << "input";
  fs::create_hard_link(dir / "log.ndjson", dir / "hard.ndjson");
  fs::create_symlink(dir / "log.ndjson", dir / "soft.ndjson");
  const std::vector<LabelledPath> inputs{{"log", dir / "log.ndjson"}};
  for (const fs::path& out : {dir / "log.ndjson", dir / "hard.ndjson", dir / "soft.ndjson",
                              dir.path() / "." / "log.ndjson"}) {
    EXPECT_THAT(ErrorOf([&] { CheckOutputPaths(inputs, {{"--output", out}}); }),
                HasSubstr("is the same file as the input log"))
        << out;
  }
  EXPECT_EQ(Slurp(dir / "log.ndjson"), "input");
  EXPECT_NO_THROW(CheckOutputPaths(inputs, {{"--output", dir / "new.ndjson"}, {"--smoothed", "-"}}));
}

TEST(CheckOutputPaths, RefusesTwoOutputsNamingOneFileEvenIfItDoesNotExistYet) {
  const test::ScratchDir dir;
  EXPECT_THAT(ErrorOf([&] {
                CheckOutputPaths({}, {{"--output", dir / "a.ndjson"}, {"--smoothed", dir.path() / "." / "a.ndjson"}});
              }),
              HasSubstr("two outputs cannot share a file"));
}

}  // namespace
}  // namespace rowloc::mapio
