// The per-session journal of the service (docs/service.md §8): SESSION.ndjson, a sensor log
// (docs/protocol.md §1) whose header carries the session's wheel order, origin and reorder window,
// followed by every accepted sensor message as it arrived; and SESSION.session.json, what the
// session was opened with (vehicle and filter configurations inline, map name, options), written
// once through a temporary file and a rename. Together they rebuild the session bit for bit.
//
// Appends go to a buffer that Flush writes with one write(2): the dispatcher flushes every journal
// a batch of lines touched before it acknowledges the batch, so a killed process loses nothing
// acknowledged. fsync(2) follows the policy: kAlways at every Flush, kInterval when the server's
// timer calls Sync (about once a second), kNone never (the kernel writes back). A journal refuses
// an append that would take it past max_bytes (kLimitExceeded) instead of dropping data. Close
// moves both files to the subdirectory closed/ (as SESSION-N.*), where resume does not look.
#pragma once

#include "rowloc/service/service_settings.hpp"

#include <cstddef>
#include <filesystem>
#include <memory>
#include <string>
#include <string_view>
#include <vector>

namespace rowloc::service {

class SessionJournal {
 public:
  /// Creates SESSION.session.json (metadata_json) and SESSION.ndjson (header_line). Throws
  /// std::runtime_error when the files exist or cannot be written.
  static std::unique_ptr<SessionJournal> Create(const std::filesystem::path& directory, const std::string& session,
                                                const std::string& metadata_json, const std::string& header_line,
                                                std::size_t max_bytes, FsyncPolicy fsync);
  /// Opens an existing journal for appending (resume). A last line without its newline (a write
  /// cut by a power loss) is cut off and reported in `truncated_bytes`.
  static std::unique_ptr<SessionJournal> Reopen(const std::filesystem::path& directory, const std::string& session,
                                                std::size_t max_bytes, FsyncPolicy fsync,
                                                std::size_t& truncated_bytes);
  ~SessionJournal();
  SessionJournal(const SessionJournal&) = delete;
  SessionJournal& operator=(const SessionJournal&) = delete;

  /// Buffers one line (a newline is added). Throws ServiceError(kLimitExceeded) past max_bytes.
  void Append(std::string_view line);
  /// Writes the buffer (and fsyncs with kAlways). Throws std::runtime_error on a write error.
  void Flush();
  /// Flush, then fsync (kInterval's timer, shutdown); no-op fsync with kNone.
  void Sync();
  /// Sync, then move both files to closed/SESSION-N.*; returns the journal's new path.
  std::filesystem::path Close();

  const std::filesystem::path& path() const { return path_; }
  std::size_t bytes() const { return bytes_; }
  bool dirty() const { return !buffer_.empty() || unsynced_; }

  /// The names of the sessions with a journal in `directory` (SESSION.session.json present).
  static std::vector<std::string> OpenSessions(const std::filesystem::path& directory);
  static std::filesystem::path JournalPath(const std::filesystem::path& directory, const std::string& session);
  static std::filesystem::path MetadataPath(const std::filesystem::path& directory, const std::string& session);

 private:
  SessionJournal(std::filesystem::path directory, std::string session, int fd, std::size_t bytes,
                 std::size_t max_bytes, FsyncPolicy fsync);

  std::filesystem::path directory_;
  std::string session_;
  std::filesystem::path path_;
  int fd_ = -1;
  std::size_t bytes_ = 0;
  std::size_t max_bytes_;
  FsyncPolicy fsync_;
  std::string buffer_;
  bool unsynced_ = false;
};

}  // namespace rowloc::service
