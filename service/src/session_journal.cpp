// Per-session journals (see session_journal.hpp).
#include "rowloc/service/session_journal.hpp"

#include "rowloc/service/service_error.hpp"

#include <fcntl.h>
#include <sys/stat.h>
#include <unistd.h>

#include <algorithm>
#include <cerrno>
#include <cstring>
#include <fstream>
#include <stdexcept>

namespace rowloc::service {
namespace {

[[noreturn]] void Fail(const std::filesystem::path& path, const std::string& what) {
  throw std::runtime_error(path.string() + ": " + what + ": " + std::strerror(errno));
}

void WriteAll(int fd, const char* data, std::size_t size, const std::filesystem::path& path) {
  while (size > 0) {
    const ssize_t n = ::write(fd, data, size);
    if (n < 0) {
      if (errno == EINTR) continue;
      Fail(path, "journal write failed");
    }
    data += n;
    size -= static_cast<std::size_t>(n);
  }
}

void WriteFileAtomically(const std::filesystem::path& path, const std::string& text) {
  const std::filesystem::path temporary = path.string() + ".tmp";
  const int fd = ::open(temporary.c_str(), O_WRONLY | O_CREAT | O_TRUNC | O_CLOEXEC, 0644);
  if (fd < 0) Fail(temporary, "cannot create");
  try {
    WriteAll(fd, text.data(), text.size(), temporary);
    if (::fsync(fd) != 0) Fail(temporary, "fsync failed");
  } catch (...) {
    ::close(fd);
    throw;
  }
  ::close(fd);
  std::filesystem::rename(temporary, path);
}

}  // namespace

std::filesystem::path SessionJournal::JournalPath(const std::filesystem::path& directory, const std::string& session) {
  return directory / (session + ".ndjson");
}
std::filesystem::path SessionJournal::MetadataPath(const std::filesystem::path& directory,
                                                   const std::string& session) {
  return directory / (session + ".session.json");
}

SessionJournal::SessionJournal(std::filesystem::path directory, std::string session, int fd, std::size_t bytes,
                               std::size_t max_bytes, FsyncPolicy fsync)
    : directory_(std::move(directory)),
      session_(std::move(session)),
      path_(JournalPath(directory_, session_)),
      fd_(fd),
      bytes_(bytes),
      max_bytes_(max_bytes),
      fsync_(fsync) {}

SessionJournal::~SessionJournal() {
  if (fd_ < 0) return;
  try {
    Flush();
  } catch (const std::exception&) {
    // a destructor cannot report; Close and Sync are where errors are seen
  }
  ::close(fd_);
}

std::unique_ptr<SessionJournal> SessionJournal::Create(const std::filesystem::path& directory,
                                                       const std::string& session, const std::string& metadata_json,
                                                       const std::string& header_line, std::size_t max_bytes,
                                                       FsyncPolicy fsync) {
  std::filesystem::create_directories(directory);
  const std::filesystem::path path = JournalPath(directory, session);
  const int fd = ::open(path.c_str(), O_WRONLY | O_CREAT | O_EXCL | O_APPEND | O_CLOEXEC, 0644);
  if (fd < 0) Fail(path, "cannot create the journal");
  std::unique_ptr<SessionJournal> journal(new SessionJournal(directory, session, fd, 0, max_bytes, fsync));
  journal->Append(header_line);
  journal->Sync();
  WriteFileAtomically(MetadataPath(directory, session), metadata_json + "\n");
  return journal;
}

std::unique_ptr<SessionJournal> SessionJournal::Reopen(const std::filesystem::path& directory,
                                                       const std::string& session, std::size_t max_bytes,
                                                       FsyncPolicy fsync, std::size_t& truncated_bytes) {
  const std::filesystem::path path = JournalPath(directory, session);
  // O_NONBLOCK: a FIFO or a device put in the journal's place must not block the open; it is
  // refused below, on the opened file, before a byte is read.
  const int fd = ::open(path.c_str(), O_RDWR | O_APPEND | O_CLOEXEC | O_NONBLOCK);
  if (fd < 0) Fail(path, "cannot open the journal");
  const auto close_and_fail = [fd, &path](const std::string& what) {
    const int error = errno;
    ::close(fd);
    errno = error;
    Fail(path, what);
  };
  struct stat info {};
  if (::fstat(fd, &info) != 0) close_and_fail("cannot examine the journal");
  if (!S_ISREG(info.st_mode)) {
    ::close(fd);
    throw std::runtime_error(path.string() + ": the journal is not a regular file (a FIFO, a device or a directory)");
  }
  const int flags = ::fcntl(fd, F_GETFL);
  if (flags >= 0) ::fcntl(fd, F_SETFL, flags & ~O_NONBLOCK);
  const off_t size = ::lseek(fd, 0, SEEK_END);
  // Cut a last line that lacks its newline (the rest of a write interrupted by a power loss),
  // scanning back from the end in blocks.
  off_t keep = size;
  char block[1 << 16];
  while (keep > 0) {
    const off_t start = std::max<off_t>(0, keep - static_cast<off_t>(sizeof block));
    const auto want = static_cast<std::size_t>(keep - start);
    if (::pread(fd, block, want, start) != static_cast<ssize_t>(want)) close_and_fail("cannot read the journal");
    if (const void* newline = ::memrchr(block, '\n', want)) {
      keep = start + (static_cast<const char*>(newline) - block) + 1;
      break;
    }
    keep = start;
  }
  truncated_bytes = static_cast<std::size_t>(size - keep);
  if (truncated_bytes > 0 && ::ftruncate(fd, keep) != 0) {
    ::close(fd);
    Fail(path, "cannot cut the journal's unterminated last line");
  }
  return std::unique_ptr<SessionJournal>(
      new SessionJournal(directory, session, fd, static_cast<std::size_t>(keep), max_bytes, fsync));
}

void SessionJournal::Append(std::string_view line) {
  if (bytes_ + buffer_.size() + line.size() + 1 > max_bytes_) {
    throw ServiceError(ErrorCode::kLimitExceeded, "session journal " + path_.string() + " reached its limit of " +
                                                      std::to_string(max_bytes_) + " bytes (max_journal_bytes)");
  }
  buffer_.append(line);
  buffer_.push_back('\n');
}

void SessionJournal::Flush() {
  if (buffer_.empty()) return;
  WriteAll(fd_, buffer_.data(), buffer_.size(), path_);
  bytes_ += buffer_.size();
  buffer_.clear();
  unsynced_ = true;
  if (fsync_ == FsyncPolicy::kAlways) Sync();
}

void SessionJournal::Sync() {
  Flush();
  if (!unsynced_) return;
  if (fsync_ != FsyncPolicy::kNone && ::fdatasync(fd_) != 0) Fail(path_, "fsync of the journal failed");
  unsynced_ = false;
}

std::filesystem::path SessionJournal::Close() {
  Sync();
  ::close(fd_);
  fd_ = -1;
  const std::filesystem::path closed = directory_ / "closed";
  std::filesystem::create_directories(closed);
  std::filesystem::path target;
  for (int n = 1;; ++n) {
    target = closed / (session_ + "-" + std::to_string(n) + ".ndjson");
    if (!std::filesystem::exists(target)) break;
  }
  const std::filesystem::path metadata_target = target.parent_path() / (target.stem().string() + ".session.json");
  std::filesystem::rename(MetadataPath(directory_, session_), metadata_target);
  std::filesystem::rename(path_, target);
  path_ = target;
  return target;
}

std::vector<std::string> SessionJournal::OpenSessions(const std::filesystem::path& directory) {
  std::vector<std::string> sessions;
  std::error_code ec;
  const std::string suffix = ".session.json";
  for (const auto& entry : std::filesystem::directory_iterator(directory, ec)) {
    const std::string file = entry.path().filename().string();
    if (entry.is_regular_file() && file.size() > suffix.size() && file.ends_with(suffix)) {
      sessions.push_back(file.substr(0, file.size() - suffix.size()));
    }
  }
  std::sort(sessions.begin(), sessions.end());
  return sessions;
}

}  // namespace rowloc::service
