// The settings of `rowloc serve` (docs/service.md §10): listen addresses, directories, limits and
// the journal's fsync policy, from a JSON settings file and/or command-line options. Every value has
// a domain; a file with an unknown key, a wrong type or a value outside its domain is refused with
// the key named (ServiceSettingsError), so that a typo never silently leaves a default in force.
#pragma once

#include <cstddef>
#include <filesystem>
#include <optional>
#include <stdexcept>
#include <string>

namespace rowloc::service {

enum class FsyncPolicy { kNone, kInterval, kAlways };
enum class SlowClientPolicy { kDropOldest, kDisconnect };

std::optional<FsyncPolicy> FsyncPolicyFromName(std::string_view name);
std::optional<SlowClientPolicy> SlowClientPolicyFromName(std::string_view name);

/// The largest max_line_bytes a server accepts (64 MiB): no line the service writes to a journal is
/// longer, whatever its settings were.
inline constexpr std::size_t kMaxLineBytesLimit = std::size_t{64} << 20;

class ServiceSettingsError : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

struct ServiceSettings {
  std::string listen = "127.0.0.1";   ///< TCP address
  int port = 7878;                    ///< 0: any free port
  /// The live view's HTTP/WebSocket port (live_view.hpp), on the same address: -1 (default): off,
  /// 0: any free port.
  int http_port = -1;
  /// Most WebSocket frames per second a live-view client is sent (wall clock), in (0, 1000].
  double live_view_rate_hz = 20.0;
  std::string unix_socket;            ///< empty: none
  std::string token_file;             ///< empty: no token (then only loopback addresses are allowed)
  std::filesystem::path vehicles_dir = "config/vehicles";
  std::filesystem::path maps_dir = "maps";
  std::filesystem::path filters_dir = "config/filters";
  std::filesystem::path journal_dir;  ///< empty: no journal, no resume
  FsyncPolicy fsync = FsyncPolicy::kInterval;
  int threads = 2;
  std::size_t max_line_bytes = std::size_t{1} << 20;
  std::size_t max_connections = 256;
  std::size_t max_sessions = 1024;
  std::size_t max_queue_lines = 4096;
  SlowClientPolicy slow_client = SlowClientPolicy::kDropOldest;
  std::size_t max_inline_config_bytes = 65536;
  double reorder_window_s = 0.2;
  double max_reorder_window_s = 5.0;
  /// A message this much newer than the newest of its session is refused (a clock jump): once
  /// accepted it would make every later message too old.
  double max_time_jump_s = 600.0;
  double connection_idle_timeout_s = 600.0;  ///< 0: never
  double session_idle_timeout_s = 0.0;       ///< 0: never
  std::size_t max_journal_bytes = std::size_t{1} << 30;
};

/// Reads a settings file over `base` (keys of docs/service.md §10). Throws ServiceSettingsError.
ServiceSettings LoadServiceSettings(const std::filesystem::path& path, ServiceSettings base = {});

/// Checks every value's domain and the security rule (a non-loopback listen address needs a token
/// file). Throws ServiceSettingsError naming the key.
void ValidateServiceSettings(const ServiceSettings& settings);

/// True for 127.0.0.0/8, ::1 and "localhost".
bool IsLoopbackAddress(const std::string& address);

/// The token of a token file (its first line, trailing white space removed; must not be empty and
/// the file at most 4 KiB). Throws ServiceSettingsError.
std::string ReadToken(const std::filesystem::path& path);

}  // namespace rowloc::service
