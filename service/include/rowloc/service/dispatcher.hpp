// The service's request handling, apart from any socket (docs/service.md §1-§9): a line in, reply
// and error lines out to the client's OutputSink. The TCP and Unix-socket server (server.hpp), the
// tests and the fuzz target all drive this one class, so what is tested without sockets is what
// runs behind them.
//
// Thread safety: HandleLine may be called from many threads at once for different clients (one
// client's lines in order, from one thread at a time). The session registry has its own mutex,
// held only to look a session up, add or remove it; each session has its own (service_session.hpp).
#pragma once

#include "rowloc/geometry/row_map.hpp"
#include "rowloc/service/output_sink.hpp"
#include "rowloc/service/service_session.hpp"
#include "rowloc/service/service_settings.hpp"
#include "rowloc/service/service_stats.hpp"

#include <nlohmann/json.hpp>

#include <atomic>
#include <cstddef>
#include <map>
#include <memory>
#include <mutex>
#include <string>
#include <string_view>
#include <vector>

namespace rowloc::service {

inline constexpr std::string_view kServiceProtocol = "rowloc-service/1";

/// What the dispatcher keeps per client (one per connection).
struct ClientContext {
  std::shared_ptr<OutputSink> sink;
  bool authenticated = false;
  /// Sessions whose journals this batch of lines wrote to (flushed by EndBatch).
  std::vector<std::shared_ptr<ServiceSession>> touched;
};

class Dispatcher {
 public:
  /// Checks the settings (ValidateServiceSettings) and reads the token file. Throws ServiceSettingsError.
  explicit Dispatcher(ServiceSettings settings);

  /// Resumes every session left open in the journal directory (docs/service.md §8); returns how
  /// many. A journal that cannot be resumed is reported in `problems` and left in place.
  std::size_t ResumeJournals(std::vector<std::string>& problems);

  /// Handles one line (without its newline) of a client; line_number is 1-based on its connection.
  void HandleLine(ClientContext& client, std::string_view line, std::size_t line_number);
  /// A line longer than max_line_bytes (its bytes were skipped).
  void HandleOversizedLine(ClientContext& client, std::size_t line_number);
  /// After a batch of lines: writes the journals the batch touched, before its replies go out.
  void EndBatch(ClientContext& client);
  /// The client is gone: its subscriptions end.
  void ClientGone(ClientContext& client);

  /// About once a second: fsync journals (fsync interval), close idle sessions.
  void Tick();
  /// Stops serving requests (they get `shutting_down`) and closes every session (its held
  /// messages applied, its journal synced and moved to closed/). Only a crash leaves sessions to
  /// resume.
  void Shutdown();

  const ServiceSettings& settings() const { return settings_; }
  ServiceStats& stats() { return stats_; }
  std::size_t session_count() const;
  /// The session of that name, or null.
  std::shared_ptr<ServiceSession> FindSession(const std::string& name) const;
  /// True when the server has no token or `given` is it (compared in constant time); the live
  /// view's HTTP requests use the same rule as hello.
  bool TokenMatches(std::string_view given) const;
  bool requires_token() const { return !token_.empty(); }
  /// The row map of that name from the maps directory, loaded once (ServiceError: kUnknownMap,
  /// kInvalidName, kInvalidConfig).
  std::shared_ptr<const geometry::RowMap> LoadMap(const std::string& name);

 private:
  using Json = nlohmann::json;
  using OrderedJson = nlohmann::ordered_json;

  void Dispatch(ClientContext& client, const Json& request, const Json& id, std::string_view type,
                std::string_view line);
  void HandleSensorMessage(ClientContext& client, const Json& request, const Json& id, std::string_view line);
  OrderedJson Hello(ClientContext& client, const Json& request);
  OrderedJson OpenSession(const Json& request);
  OrderedJson CloseSession(const Json& request);
  void Subscribe(ClientContext& client, const Json& request, const Json& id);
  OrderedJson ListMaps();
  OrderedJson ListVehicles();
  OrderedJson ListSessions() const;
  OrderedJson Stats() const;

  std::shared_ptr<ServiceSession> Session(const Json& request) const;
  /// Builds a session from its spec (open_session and resume); journal may be null.
  std::shared_ptr<ServiceSession> BuildSession(SessionSpec spec, std::unique_ptr<SessionJournal> journal);
  /// The next free generated session name (s1, s2, ...). Registry lock held.
  std::string NewSessionName();
  void Reply(ClientContext& client, OrderedJson reply, const Json& id);
  void ReplyError(ClientContext& client, ErrorCode code, const std::string& message, const Json& id,
                  std::size_t line_number);

  ServiceSettings settings_;
  std::string token_;
  ServiceStats stats_;
  std::atomic<bool> shutting_down_{false};
  std::chrono::steady_clock::time_point started_ = std::chrono::steady_clock::now();

  mutable std::mutex registry_mutex_;
  std::map<std::string, std::shared_ptr<ServiceSession>> sessions_;
  std::size_t generated_names_ = 0;

  std::mutex maps_mutex_;
  std::map<std::string, std::shared_ptr<const geometry::RowMap>> maps_;  ///< by name, loaded once
};

}  // namespace rowloc::service
