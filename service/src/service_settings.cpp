// Settings of the service (see service_settings.hpp).
#include "rowloc/service/service_settings.hpp"

#include "rowloc/mapio/input_file.hpp"

#include <nlohmann/json.hpp>

#include <cmath>
#include <functional>
#include <map>

namespace rowloc::service {
namespace {

constexpr std::size_t kMaxSettingsFileBytes = 1 << 20;

/// A whole small file through mapio::ReadInputFile: regular files only (a FIFO or a device is
/// refused before a byte is read, checked on the opened file), at most max_bytes.
std::string ReadSmallFile(const std::filesystem::path& path, std::size_t max_bytes, const char* what) {
  try {
    return mapio::ReadInputFile(path, max_bytes, what);
  } catch (const mapio::InputFileError& e) {
    throw ServiceSettingsError(e.what());
  }
}

using Json = nlohmann::json;
using Setter = std::function<void(ServiceSettings&, const Json&, const std::string& key)>;

[[noreturn]] void Bad(const std::string& key, const std::string& reason) {
  throw ServiceSettingsError("settings: " + key + ": " + reason);
}

Setter String(std::string ServiceSettings::*member) {
  return [member](ServiceSettings& s, const Json& v, const std::string& key) {
    if (!v.is_string()) Bad(key, "must be a string");
    s.*member = v.get<std::string>();
  };
}
Setter Path(std::filesystem::path ServiceSettings::*member) {
  return [member](ServiceSettings& s, const Json& v, const std::string& key) {
    if (!v.is_string()) Bad(key, "must be a string (a directory)");
    s.*member = v.get<std::string>();
  };
}
Setter Count(std::size_t ServiceSettings::*member) {
  return [member](ServiceSettings& s, const Json& v, const std::string& key) {
    if (!v.is_number_unsigned()) Bad(key, "must be a whole number >= 0");
    s.*member = v.get<std::size_t>();
  };
}
Setter Seconds(double ServiceSettings::*member) {
  return [member](ServiceSettings& s, const Json& v, const std::string& key) {
    if (!v.is_number()) Bad(key, "must be a number (seconds)");
    s.*member = v.get<double>();
  };
}

const std::map<std::string, Setter>& Setters() {
  static const std::map<std::string, Setter> setters = {
      {"listen", String(&ServiceSettings::listen)},
      {"port",
       [](ServiceSettings& s, const Json& v, const std::string& key) {
         if (!v.is_number_integer()) Bad(key, "must be a whole number");
         s.port = static_cast<int>(std::clamp<std::int64_t>(v.get<std::int64_t>(), -1, 65536));
       }},
      {"http_port",
       [](ServiceSettings& s, const Json& v, const std::string& key) {
         if (v.is_null()) {
           s.http_port = -1;  // off
           return;
         }
         if (!v.is_number_integer()) Bad(key, "must be a whole number (-1 or null: no live view)");
         s.http_port = static_cast<int>(std::clamp<std::int64_t>(v.get<std::int64_t>(), -2, 65536));
       }},
      {"live_view_rate_hz",
       [](ServiceSettings& s, const Json& v, const std::string& key) {
         if (!v.is_number()) Bad(key, "must be a number (frames per second)");
         s.live_view_rate_hz = v.get<double>();
       }},
      {"unix_socket", String(&ServiceSettings::unix_socket)},
      {"token_file", String(&ServiceSettings::token_file)},
      {"vehicles_dir", Path(&ServiceSettings::vehicles_dir)},
      {"maps_dir", Path(&ServiceSettings::maps_dir)},
      {"filters_dir", Path(&ServiceSettings::filters_dir)},
      {"journal_dir", Path(&ServiceSettings::journal_dir)},
      {"fsync",
       [](ServiceSettings& s, const Json& v, const std::string& key) {
         const auto policy = v.is_string() ? FsyncPolicyFromName(v.get<std::string>()) : std::nullopt;
         if (!policy) Bad(key, "must be \"none\", \"interval\" or \"always\"");
         s.fsync = *policy;
       }},
      {"threads",
       [](ServiceSettings& s, const Json& v, const std::string& key) {
         if (!v.is_number_integer()) Bad(key, "must be a whole number");
         s.threads = static_cast<int>(std::clamp<std::int64_t>(v.get<std::int64_t>(), -1, 1025));
       }},
      {"max_line_bytes", Count(&ServiceSettings::max_line_bytes)},
      {"max_connections", Count(&ServiceSettings::max_connections)},
      {"max_sessions", Count(&ServiceSettings::max_sessions)},
      {"max_queue_lines", Count(&ServiceSettings::max_queue_lines)},
      {"slow_client",
       [](ServiceSettings& s, const Json& v, const std::string& key) {
         const auto policy = v.is_string() ? SlowClientPolicyFromName(v.get<std::string>()) : std::nullopt;
         if (!policy) Bad(key, "must be \"drop_oldest\" or \"disconnect\"");
         s.slow_client = *policy;
       }},
      {"max_inline_config_bytes", Count(&ServiceSettings::max_inline_config_bytes)},
      {"reorder_window_s", Seconds(&ServiceSettings::reorder_window_s)},
      {"max_reorder_window_s", Seconds(&ServiceSettings::max_reorder_window_s)},
      {"max_time_jump_s", Seconds(&ServiceSettings::max_time_jump_s)},
      {"connection_idle_timeout_s", Seconds(&ServiceSettings::connection_idle_timeout_s)},
      {"session_idle_timeout_s", Seconds(&ServiceSettings::session_idle_timeout_s)},
      {"max_journal_bytes", Count(&ServiceSettings::max_journal_bytes)},
  };
  return setters;
}

void CheckRange(bool ok, const std::string& key, const std::string& domain) {
  if (!ok) Bad(key, "must be " + domain);
}

}  // namespace

std::optional<FsyncPolicy> FsyncPolicyFromName(std::string_view name) {
  if (name == "none") return FsyncPolicy::kNone;
  if (name == "interval") return FsyncPolicy::kInterval;
  if (name == "always") return FsyncPolicy::kAlways;
  return std::nullopt;
}

std::optional<SlowClientPolicy> SlowClientPolicyFromName(std::string_view name) {
  if (name == "drop_oldest") return SlowClientPolicy::kDropOldest;
  if (name == "disconnect") return SlowClientPolicy::kDisconnect;
  return std::nullopt;
}

ServiceSettings LoadServiceSettings(const std::filesystem::path& path, ServiceSettings base) {
  const std::string text = ReadSmallFile(path, kMaxSettingsFileBytes, "settings file");
  const Json j = Json::parse(text, nullptr, false);
  if (j.is_discarded()) throw ServiceSettingsError(path.string() + ": not valid JSON");
  if (!j.is_object()) throw ServiceSettingsError(path.string() + ": must be a JSON object");
  for (const auto& [key, value] : j.items()) {
    const auto it = Setters().find(key);
    if (it == Setters().end()) throw ServiceSettingsError(path.string() + ": unknown key \"" + key + "\"");
    try {
      it->second(base, value, key);
    } catch (const ServiceSettingsError& e) {
      throw ServiceSettingsError(path.string() + ": " + e.what());
    }
  }
  return base;
}

bool IsLoopbackAddress(const std::string& address) {
  return address == "localhost" || address == "::1" || address.rfind("127.", 0) == 0;
}

void ValidateServiceSettings(const ServiceSettings& s) {
  CheckRange(s.port >= 0 && s.port <= 65535, "port", "in [0, 65535]");
  CheckRange(s.http_port >= -1 && s.http_port <= 65535, "http_port", "in [0, 65535], or -1: no live view");
  CheckRange(std::isfinite(s.live_view_rate_hz) && s.live_view_rate_hz > 0 && s.live_view_rate_hz <= 1000,
             "live_view_rate_hz", "in (0, 1000] Hz");
  CheckRange(s.threads >= 1 && s.threads <= 64, "threads", "in [1, 64]");
  CheckRange(s.max_line_bytes >= 256 && s.max_line_bytes <= kMaxLineBytesLimit, "max_line_bytes",
             "in [256, 64 MiB]");
  CheckRange(s.max_connections >= 1 && s.max_connections <= 100000, "max_connections", "in [1, 100000]");
  CheckRange(s.max_sessions >= 1 && s.max_sessions <= 100000, "max_sessions", "in [1, 100000]");
  CheckRange(s.max_queue_lines >= 16 && s.max_queue_lines <= 10000000, "max_queue_lines", "in [16, 1e7]");
  CheckRange(s.max_inline_config_bytes >= 1024 && s.max_inline_config_bytes <= (std::size_t{16} << 20),
             "max_inline_config_bytes", "in [1 KiB, 16 MiB]");
  CheckRange(std::isfinite(s.max_reorder_window_s) && s.max_reorder_window_s >= 0 && s.max_reorder_window_s <= 3600,
             "max_reorder_window_s", "in [0, 3600] s");
  CheckRange(std::isfinite(s.reorder_window_s) && s.reorder_window_s >= 0 &&
                 s.reorder_window_s <= s.max_reorder_window_s,
             "reorder_window_s", "in [0, max_reorder_window_s] s");
  CheckRange(std::isfinite(s.max_time_jump_s) && s.max_time_jump_s > 0 && s.max_time_jump_s <= 1e7,
             "max_time_jump_s", "in (0, 1e7] s");
  CheckRange(std::isfinite(s.connection_idle_timeout_s) && s.connection_idle_timeout_s >= 0 &&
                 s.connection_idle_timeout_s <= 1e7,
             "connection_idle_timeout_s", "in [0, 1e7] s (0: never)");
  CheckRange(std::isfinite(s.session_idle_timeout_s) && s.session_idle_timeout_s >= 0 &&
                 s.session_idle_timeout_s <= 1e7,
             "session_idle_timeout_s", "in [0, 1e7] s (0: never)");
  CheckRange(s.max_journal_bytes >= 4096, "max_journal_bytes", ">= 4096");
  CheckRange(!s.listen.empty(), "listen", "an address");
  if (!IsLoopbackAddress(s.listen) && s.token_file.empty()) {
    Bad("listen", "'" + s.listen + "' is not a loopback address: listening on it needs a token file (token_file, "
                  "--token-file), and every connection then authenticates in hello");
  }
}

std::string ReadToken(const std::filesystem::path& path) {
  std::string text = ReadSmallFile(path, 4096, "token file");
  text = text.substr(0, text.find('\n'));
  while (!text.empty() && std::isspace(static_cast<unsigned char>(text.back()))) text.pop_back();
  if (text.empty()) throw ServiceSettingsError(path.string() + ": the token file's first line is empty");
  return text;
}

}  // namespace rowloc::service
