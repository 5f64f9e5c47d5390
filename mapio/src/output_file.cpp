// Safe output files (see output_file.hpp): checked targets, a temporary next to the target,
// fsync(2) and an atomic rename(2).
#include "rowloc/mapio/output_file.hpp"

#include <fcntl.h>
#include <sys/stat.h>
#include <unistd.h>

#include <cerrno>
#include <cstring>
#include <random>
#include <system_error>

namespace rowloc::mapio {
namespace {

namespace fs = std::filesystem;

const std::error_code kRefused = std::make_error_code(std::errc::operation_not_permitted);

std::string Quoted(const fs::path& path) {
  std::string quoted(1, '\'');  // appended, not "'" + ...: g++ 12 -Wrestrict false positive
  quoted.append(path.string()).push_back('\'');
  return quoted;
}

[[noreturn]] void ThrowOsError(const fs::path& path, const std::string& action, int error) {
  throw OutputFileError(std::error_code(error, std::generic_category()),
                        "cannot write " + Quoted(path) + ": " + action + ": " + std::strerror(error));
}

std::string KindOf(fs::file_type type) {
  switch (type) {
    case fs::file_type::directory: return "a directory";
    case fs::file_type::character: return "a character device";
    case fs::file_type::block: return "a block device";
    case fs::file_type::fifo: return "a FIFO (named pipe)";
    case fs::file_type::socket: return "a socket";
    default: return "not a regular file";
  }
}

/// The file a write to `path` replaces: links resolved, so that the linked-to file is replaced.
fs::path ResolvedTarget(const fs::path& path) {
  std::error_code ec;
  const fs::path resolved = fs::weakly_canonical(path, ec);
  return ec ? path : resolved;
}

fs::path DirectoryOf(const fs::path& path) { return path.has_parent_path() ? path.parent_path() : fs::path("."); }

/// True if a and b name the same file: the same inode if both exist, else the same resolved path.
bool SameFile(const fs::path& a, const fs::path& b) {
  std::error_code ec;
  if (fs::exists(a, ec) && fs::exists(b, ec)) {
    const bool same = fs::equivalent(a, b, ec);
    return !ec && same;
  }
  return ResolvedTarget(fs::absolute(a, ec)) == ResolvedTarget(fs::absolute(b, ec));
}

bool Skipped(const fs::path& path) { return path.empty() || IsStandardOutput(path); }

/// Makes the rename durable (best effort: the file is already complete and in place).
void SyncDirectory(const fs::path& directory) {
  const int fd = ::open(directory.c_str(), O_RDONLY | O_DIRECTORY | O_CLOEXEC);
  if (fd < 0) return;
  ::fsync(fd);
  ::close(fd);
}

/// Flushes the temporary's data to the disk (the ofstream gives no file descriptor).
void SyncFile(const fs::path& target, const fs::path& temporary) {
  const int fd = ::open(temporary.c_str(), O_RDONLY | O_CLOEXEC);
  if (fd < 0) ThrowOsError(target, "cannot reopen the temporary " + Quoted(temporary), errno);
  const int status = ::fsync(fd);
  const int error = errno;
  ::close(fd);
  if (status != 0) ThrowOsError(target, "cannot flush the temporary " + Quoted(temporary), error);
}

}  // namespace

bool IsStandardOutput(const fs::path& path) { return path == "-"; }

void CheckOutputTarget(const fs::path& output) {
  std::error_code ec;
  const fs::file_status status = fs::status(output, ec);  // follows links
  if (status.type() != fs::file_type::not_found && status.type() != fs::file_type::none &&
      status.type() != fs::file_type::regular) {
    throw OutputFileError(kRefused, "cannot write " + Quoted(output) + ": it exists and is " + KindOf(status.type()) +
                          "; only a regular file is ever replaced");
  }
}

/// Throws OutputFileError if the directory of output does not exist.
static void RequireDirectoryOf(const fs::path& output) {
  std::error_code ec;
  const fs::path directory = DirectoryOf(ResolvedTarget(output));
  if (!fs::is_directory(directory, ec)) {
    throw OutputFileError(std::make_error_code(std::errc::no_such_file_or_directory),
                          "cannot write " + Quoted(output) + ": the directory " + Quoted(directory) +
                          (fs::exists(directory, ec) ? " is not a directory" : " does not exist"));
  }
}

void CheckOutputPaths(const std::vector<LabelledPath>& inputs, const std::vector<LabelledPath>& outputs) {
  for (std::size_t i = 0; i < outputs.size(); ++i) {
    const LabelledPath& out = outputs[i];
    if (Skipped(out.path)) continue;
    for (const LabelledPath& in : inputs) {
      if (Skipped(in.path) || !SameFile(in.path, out.path)) continue;
      throw OutputFileError(kRefused, out.label + " " + Quoted(out.path) + " is the same file as the input " + in.label + " " +
                            Quoted(in.path) + ": refusing to overwrite an input");
    }
    for (std::size_t j = 0; j < i; ++j) {
      if (Skipped(outputs[j].path) || !SameFile(outputs[j].path, out.path)) continue;
      throw OutputFileError(kRefused, out.label + " " + Quoted(out.path) + " is the same file as " + outputs[j].label + " " +
                            Quoted(outputs[j].path) + ": two outputs cannot share a file");
    }
    CheckOutputTarget(out.path);
  }
}

OutputFile::OutputFile(const fs::path& target) : target_(ResolvedTarget(target)) {
  CheckOutputTarget(target);
  RequireDirectoryOf(target);
  std::random_device random;
  for (int attempt = 0; attempt < 16 && temporary_.empty(); ++attempt) {
    fs::path candidate = target_;
    candidate += ".tmp-" + std::to_string(::getpid()) + "-" + std::to_string(random());
    const int fd = ::open(candidate.c_str(), O_WRONLY | O_CREAT | O_EXCL | O_CLOEXEC, 0666);
    if (fd >= 0) {
      struct stat existing {};
      if (::stat(target_.c_str(), &existing) == 0) ::fchmod(fd, existing.st_mode & 07777);  // keep its mode
      ::close(fd);
      temporary_ = candidate;
    } else if (errno != EEXIST) {
      ThrowOsError(target, "cannot create a temporary file in " + Quoted(DirectoryOf(target_)), errno);
    }
  }
  if (temporary_.empty()) ThrowOsError(target, "cannot create a temporary file", EEXIST);
  stream_.open(temporary_, std::ios::binary | std::ios::trunc);
  if (!stream_) {
    const int error = errno;
    ::unlink(temporary_.c_str());
    ThrowOsError(target, "cannot open the temporary " + Quoted(temporary_), error);
  }
}

OutputFile::~OutputFile() {
  if (committed_) return;
  stream_.close();
  ::unlink(temporary_.c_str());
}

void OutputFile::Commit() {
  if (committed_) throw std::logic_error("OutputFile::Commit called twice for " + target_.string());
  errno = 0;
  stream_.flush();
  stream_.close();
  if (stream_.fail()) ThrowOsError(target_, "write failed", errno != 0 ? errno : EIO);
  SyncFile(target_, temporary_);
  CheckOutputTarget(target_);  // still not a device or directory (it may have changed meanwhile)
  if (::rename(temporary_.c_str(), target_.c_str()) != 0) ThrowOsError(target_, "cannot rename the temporary over it", errno);
  committed_ = true;
  SyncDirectory(DirectoryOf(target_));
}

void WriteFileAtomically(const fs::path& path, std::string_view bytes) {
  OutputFile file(path);
  file.stream().write(bytes.data(), static_cast<std::streamsize>(bytes.size()));
  file.Commit();
}

}  // namespace rowloc::mapio
