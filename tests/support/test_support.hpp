// Helpers shared by rowloc's tests: where the source tree is, and scratch directories
// that clean themselves up.
#pragma once

#include <filesystem>
#include <random>
#include <string>

namespace rowloc::test {

/// Root of the source tree (for files under maps/ and tests/data/).
inline std::filesystem::path SourceDir() { return std::filesystem::path(ROWLOC_SOURCE_DIR); }

/// A fresh directory under the system temp dir, removed with everything in it on destruction.
class ScratchDir {
 public:
  ScratchDir() {
    std::random_device rd;
    path_ = std::filesystem::temp_directory_path() /
            ("rowloc-test-" + std::to_string(rd()) + "-" + std::to_string(rd()));
    std::filesystem::create_directories(path_);
  }
  ~ScratchDir() {
    std::error_code ec;
    std::filesystem::remove_all(path_, ec);
  }
  ScratchDir(const ScratchDir&) = delete;
  ScratchDir& operator=(const ScratchDir&) = delete;
  const std::filesystem::path& path() const { return path_; }
  std::filesystem::path operator/(const std::string& name) const { return path_ / name; }

 private:
  std::filesystem::path path_;
};

}  // namespace rowloc::test
