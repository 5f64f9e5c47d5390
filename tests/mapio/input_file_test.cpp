// Bounded reading of input files (mapio::ReadInputFile) and the configuration reader built on it
// (detail::ReadTextFile): only regular files, at most the limit, the OS reason when unreadable.
#include "rowloc/mapio/input_file.hpp"

#include "rowloc/mapio/detail/json_object_reader.hpp"

#include "test_support.hpp"

#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include <sys/stat.h>
#include <unistd.h>

#include <fstream>
#include <stdexcept>
#include <string>

namespace rowloc::mapio {
namespace {

using ::testing::HasSubstr;

/// The InputFileError message of reading path with the limit; fails the test if nothing is thrown.
std::string ErrorOf(const std::filesystem::path& path, std::uintmax_t max_bytes = kMaxConfigFileBytes) {
  try {
    ReadInputFile(path, max_bytes, "test file");
  } catch (const InputFileError& e) {
    EXPECT_EQ(std::string(e.what()), path.string() + ": " + e.reason());
    return e.what();
  }
  ADD_FAILURE() << "read " << path;
  return "";
}

TEST(InputFile, ReadsARegularFileWhole) {
  const test::ScratchDir dir;
  const std::string text = std::string("{\"a\": 1}\n") + std::string(200000, ' ') + "x";
  std::ofstream(dir / "f.json", std::ios::binary) << text;
  EXPECT_EQ(ReadInputFile(dir / "f.json", kMaxConfigFileBytes), text);
  EXPECT_EQ(ReadInputFile(dir / "f.json", text.size()), text);  // exactly at the limit
}

TEST(InputFile, MissingFileNamesTheSystemReason) {
  const test::ScratchDir dir;
  EXPECT_THAT(ErrorOf(dir / "absent.json"), HasSubstr("absent.json: cannot open test file: No such file or directory"));
}

TEST(InputFile, DirectoryIsNotReadAsEmptyText) {
  const test::ScratchDir dir;
  EXPECT_THAT(ErrorOf(dir.path()), HasSubstr("is a directory, not a regular file"));
}

TEST(InputFile, DeviceIsRefusedBeforeReading) {
  EXPECT_THAT(ErrorOf("/dev/zero"), HasSubstr("/dev/zero: is a character device, not a regular file"));
}

TEST(InputFile, FifoWithoutWriterIsRefusedWithoutBlocking) {
  const test::ScratchDir dir;
  const std::filesystem::path fifo = dir / "pipe";
  ASSERT_EQ(::mkfifo(fifo.c_str(), 0600), 0);
  EXPECT_THAT(ErrorOf(fifo), HasSubstr("is a FIFO (named pipe), not a regular file"));
}

TEST(InputFile, FileLargerThanTheLimitIsRefused) {
  const test::ScratchDir dir;
  const std::filesystem::path big = dir / "big.json";
  std::ofstream(big).close();
  std::filesystem::resize_file(big, kMaxConfigFileBytes + 1);  // sparse: no disk space used
  EXPECT_THAT(ErrorOf(big), HasSubstr("is larger than the limit of 16 MiB (test file)"));
  std::ofstream(dir / "small.json") << "12345";
  EXPECT_THAT(ErrorOf(dir / "small.json", 4), HasSubstr("is larger than the limit of 4 bytes"));
}

TEST(InputFile, FileWithoutSizeIsBoundedByWhatItYields) {
  // /proc files report st_size 0 and yield their content on reading: the limit counts the bytes.
  std::string error;
  try {
    ReadInputFile("/proc/self/maps", 16);
  } catch (const InputFileError& e) {
    error = e.what();
  }
  EXPECT_THAT(error, HasSubstr("is larger than the limit of 16 bytes"));
}

TEST(InputFile, ConfigReaderReportsTheKindOfFile) {
  const test::ScratchDir dir;
  const auto error_of = [](const std::filesystem::path& path) {
    try {
      detail::ReadTextFile<std::runtime_error>(path, "vehicle file");
    } catch (const std::runtime_error& e) {
      return std::string(e.what());
    }
    return std::string("no error");
  };
  EXPECT_EQ(error_of(dir.path()), dir.path().string() + ": is a directory, not a regular file");
  EXPECT_EQ(error_of("/dev/zero"), "/dev/zero: is a character device, not a regular file");
  EXPECT_THAT(error_of(dir / "none.json"), HasSubstr("none.json: cannot open vehicle file: No such file or directory"));
}

TEST(InputFile, ByteCountsAreShort) {
  EXPECT_EQ(ByteCountText(100), "100 bytes");
  EXPECT_EQ(ByteCountText(1536), "1.5 KiB");
  EXPECT_EQ(ByteCountText(kMaxConfigFileBytes), "16 MiB");
  EXPECT_EQ(ByteCountText(kMaxRowMapFileBytes), "256 MiB");
}

}  // namespace
}  // namespace rowloc::mapio
