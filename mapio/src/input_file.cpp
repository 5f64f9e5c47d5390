// Bounded reading of input files (contract in input_file.hpp): open(2), fstat(2) to refuse what is
// not a regular file, then read(2) in blocks until the end or one byte past the limit.
#include "rowloc/mapio/input_file.hpp"

#include <fcntl.h>
#include <sys/stat.h>
#include <unistd.h>

#include <cerrno>
#include <cstdio>
#include <cstring>
#include <utility>

namespace rowloc::mapio {
namespace {

/// Closes a file descriptor on every path out of ReadInputFile.
class FileDescriptor {
 public:
  explicit FileDescriptor(int fd) : fd_(fd) {}
  FileDescriptor(const FileDescriptor&) = delete;
  FileDescriptor& operator=(const FileDescriptor&) = delete;
  ~FileDescriptor() {
    if (fd_ >= 0) ::close(fd_);
  }
  int get() const { return fd_; }

 private:
  int fd_;
};

/// What a file that is not a regular file is, for the message.
std::string NotRegularReason(mode_t mode) {
  if (S_ISDIR(mode)) return "is a directory, not a regular file";
  if (S_ISCHR(mode)) return "is a character device, not a regular file";
  if (S_ISBLK(mode)) return "is a block device, not a regular file";
  if (S_ISFIFO(mode)) return "is a FIFO (named pipe), not a regular file";
  if (S_ISSOCK(mode)) return "is a socket, not a regular file";
  return "is not a regular file";
}

std::string TooLarge(std::uintmax_t max_bytes, const std::string& what) {
  return "is larger than the limit of " + ByteCountText(max_bytes) + " (" + what + ")";
}

}  // namespace

std::string ByteCountText(std::uintmax_t bytes) {
  constexpr const char* kUnits[] = {"KiB", "MiB", "GiB"};
  if (bytes < 1024) return std::to_string(bytes) + " bytes";
  double value = static_cast<double>(bytes) / 1024.0;
  int unit = 0;
  while (value >= 1024.0 && unit < 2) {
    value /= 1024.0;
    ++unit;
  }
  char text[32];
  std::snprintf(text, sizeof text, "%g %s", value, kUnits[unit]);
  return text;
}

std::string ReadInputFile(const std::filesystem::path& path, std::uintmax_t max_bytes, const std::string& what) {
  const std::string name = path.string();
  // O_NONBLOCK: opening a FIFO without a writer must not block; it is refused below anyway.
  const FileDescriptor fd(::open(path.c_str(), O_RDONLY | O_CLOEXEC | O_NONBLOCK));
  if (fd.get() < 0) throw InputFileError(name, "cannot open " + what + ": " + std::strerror(errno));
  struct stat info {};
  if (::fstat(fd.get(), &info) != 0) throw InputFileError(name, "cannot examine " + what + ": " + std::strerror(errno));
  if (!S_ISREG(info.st_mode)) throw InputFileError(name, NotRegularReason(info.st_mode));
  if (info.st_size > 0 && static_cast<std::uintmax_t>(info.st_size) > max_bytes) {
    throw InputFileError(name, TooLarge(max_bytes, what));
  }
  const int flags = ::fcntl(fd.get(), F_GETFL);
  if (flags >= 0) ::fcntl(fd.get(), F_SETFL, flags & ~O_NONBLOCK);
  std::string bytes;
  bytes.reserve(static_cast<std::size_t>(info.st_size));
  char buffer[1 << 16];
  for (;;) {
    const ssize_t n = ::read(fd.get(), buffer, sizeof buffer);
    if (n == 0) break;
    if (n < 0) {
      if (errno == EINTR) continue;
      throw InputFileError(name, "cannot read " + what + ": " + std::strerror(errno));
    }
    if (bytes.size() + static_cast<std::size_t>(n) > max_bytes) throw InputFileError(name, TooLarge(max_bytes, what));
    bytes.append(buffer, static_cast<std::size_t>(n));
  }
  return bytes;
}

}  // namespace rowloc::mapio
