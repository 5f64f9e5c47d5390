// Bounded reading of input files: every whole file rowloc reads as input (row maps, vehicle,
// filter, scenario and other configuration files) goes through ReadInputFile, so that no input
// can make a reader wait forever or allocate without bound (issue 26: "/dev/zero as a vehicle or
// filter file ... configs have a size limit too").
//
// Contract:
//   1. Only a regular file is read. A directory is refused ("is a directory"), and so are
//      devices (/dev/zero), FIFOs and sockets, before a byte is read: they have no end, or one
//      that another process decides.
//   2. At most max_bytes are read. A file larger than that (by its size, or by what it yields:
//      files of /proc report size 0) is refused, naming the limit; at most max_bytes + 1 bytes
//      are ever held in memory.
//   3. A file that cannot be opened or read is refused with the operating system's reason
//      (strerror(errno)), e.g. "cannot open vehicle file: No such file or directory".
// Limits (docs/map-format.md, "Limits"; docs/simulation-scenarios.md): configuration files
// kMaxConfigFileBytes (16 MiB: the shipped ones are under 10 KiB), row maps kMaxRowMapFileBytes
// (256 MiB: about 5 million positions of 50 bytes; the vertex limits of the map come first).
#pragma once

#include <cstdint>
#include <filesystem>
#include <stdexcept>
#include <string>

namespace rowloc::mapio {

inline constexpr std::uintmax_t kMaxConfigFileBytes = std::uintmax_t{16} << 20;   ///< 16 MiB
inline constexpr std::uintmax_t kMaxRowMapFileBytes = std::uintmax_t{256} << 20;  ///< 256 MiB

/// An input file that cannot or must not be read. what() is "<path>: <reason>"; reason() alone
/// is e.g. "is a directory, not a regular file" or "cannot open vehicle file: Permission denied".
class InputFileError : public std::runtime_error {
 public:
  InputFileError(const std::string& path, std::string reason)
      : std::runtime_error(path + ": " + reason), reason_(std::move(reason)) {}
  const std::string& reason() const { return reason_; }

 private:
  std::string reason_;
};

/// The whole content of the regular file at path, of at most max_bytes bytes (contract above).
/// `what` names the kind of file in the messages ("vehicle file"). Throws InputFileError.
std::string ReadInputFile(const std::filesystem::path& path, std::uintmax_t max_bytes,
                          const std::string& what = "file");

/// "16 MiB", "256 MiB", "1.5 KiB", "100 bytes": a byte count for messages.
std::string ByteCountText(std::uintmax_t bytes);

}  // namespace rowloc::mapio
