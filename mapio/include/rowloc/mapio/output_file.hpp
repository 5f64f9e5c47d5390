// Safe output files: every file rowloc writes goes through this component, so that no command can
// destroy its input or a file it was not meant to replace.
//
// Contract (issue 26, "files destroyed — never"):
//   1. An output path that names the same file as an input (also through symbolic or hard links:
//      std::filesystem::equivalent compares device and inode) is refused before anything is
//      opened; so are two outputs naming the same file (CheckOutputPaths).
//   2. An existing target that is not a regular file (a device such as /dev/full, a directory, a
//      FIFO, a socket) is refused: it is never replaced by a rename (CheckOutputTarget).
//   3. The bytes go to a new temporary file in the target's directory (same file system, created
//      with O_EXCL), which is flushed, fsync(2)ed and renamed over the target only on success
//      (rename(2) is atomic: a reader sees the old file or the new one, never a part). A failure,
//      or an OutputFile destroyed without Commit(), removes the temporary and leaves the target as
//      it was. A target that is a symbolic link is resolved: the file it points to is replaced.
//   4. Every error names the path and the operating system's reason (strerror of errno).
//
// The path "-" is not a file: commands that write to standard output handle it before calling here
// (IsStandardOutput).
#pragma once

#include <filesystem>
#include <fstream>
#include <stdexcept>
#include <string>
#include <string_view>
#include <system_error>
#include <utility>
#include <vector>

namespace rowloc::mapio {

/// An output could not be (or must not be) written. what() names the path and the reason; code()
/// is the OS error (errno), or std::errc::operation_not_permitted for a refused target.
class OutputFileError : public std::system_error {
 public:
  OutputFileError(std::error_code code, std::string message)
      : std::system_error(code, message), message_(std::move(message)) {}
  const char* what() const noexcept override { return message_.c_str(); }

 private:
  std::string message_;
};

/// True for "-", the conventional name of standard output.
bool IsStandardOutput(const std::filesystem::path& path);

/// Throws OutputFileError if the target exists and is not a regular file (after following links).
void CheckOutputTarget(const std::filesystem::path& output);

/// Throws OutputFileError if any output names the same file as any input or as another output
/// (equivalent(): same device and inode; for outputs that do not exist yet, the same absolute
/// path after resolving links), or if an output fails CheckOutputTarget. Empty paths and "-" are
/// skipped. `what` labels the paths in the message (e.g. "--smoothed").
struct LabelledPath {
  std::string label;  ///< how the user gave the path, e.g. "--output" or "log"
  std::filesystem::path path;
};
void CheckOutputPaths(const std::vector<LabelledPath>& inputs, const std::vector<LabelledPath>& outputs);

/// A file written to a temporary next to its target and renamed over the target by Commit().
class OutputFile {
 public:
  /// Checks the target (CheckOutputTarget) and its directory, and creates the temporary. Throws
  /// OutputFileError (a missing directory: std::errc::no_such_file_or_directory).
  explicit OutputFile(const std::filesystem::path& target);
  ~OutputFile();  // removes the temporary unless committed
  OutputFile(const OutputFile&) = delete;
  OutputFile& operator=(const OutputFile&) = delete;

  /// The stream on the temporary file (binary mode).
  std::ofstream& stream() { return stream_; }
  /// The temporary's path, for libraries that write a file by name (PCL, OctoMap); they must
  /// not write through stream() as well.
  const std::filesystem::path& temporary_path() const { return temporary_; }
  /// The file that Commit() replaces (the target, links resolved).
  const std::filesystem::path& target() const { return target_; }

  /// Flushes, fsyncs and closes the temporary and renames it over the target. Throws
  /// OutputFileError (the target is then untouched and the temporary removed).
  void Commit();

 private:
  std::filesystem::path target_;
  std::filesystem::path temporary_;
  std::ofstream stream_;
  bool committed_ = false;
};

/// Writes `bytes` to `path` through an OutputFile (checked, atomic).
void WriteFileAtomically(const std::filesystem::path& path, std::string_view bytes);

}  // namespace rowloc::mapio
