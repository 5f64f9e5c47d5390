// One session of the service (docs/service.md §3-§6): a LocalizationSession (the filter, its
// vehicle and row map), the session's reorder window (localization/reorder_buffer.hpp), its
// journal (session_journal.hpp) and its subscribers. Every member function locks the session's
// own mutex, so sessions never wait for one another and any connection may use any session.
#pragma once

#include "rowloc/formats/sensor_messages.hpp"
#include "rowloc/localization/localization_session.hpp"
#include "rowloc/localization/reorder_buffer.hpp"
#include "rowloc/mapio/local_frame.hpp"
#include "rowloc/service/output_sink.hpp"
#include "rowloc/service/session_journal.hpp"

#include <nlohmann/json.hpp>

#include <chrono>
#include <functional>
#include <cstddef>
#include <memory>
#include <mutex>
#include <optional>
#include <sstream>
#include <string>
#include <string_view>
#include <vector>

namespace rowloc::service {

/// What a session was opened with; also its journal's metadata (SESSION.session.json).
struct SessionSpec {
  std::string name;
  std::string vehicle;           ///< vehicle file name, or "" when inline
  nlohmann::json vehicle_config; ///< the vehicle configuration as read (object)
  std::string filter;            ///< filter file name, or "" (inline or defaults)
  nlohmann::json filter_config;  ///< the complete filter configuration (session_filter.hpp); null in
                                 ///< journals written before issue 29: the defaults
  std::string map;               ///< map name, or "" (no map)
  formats::LogHeader header;     ///< wheel and ranger order, origin
  double period_s = 0.1;
  double reorder_window_s = 0.2;
  std::optional<std::array<double, 6>> initial_pose;  ///< t, x, y, phi, sigma_xy, sigma_phi

  nlohmann::json ToJson() const;
  static SessionSpec FromJson(const nlohmann::json& j);  ///< throws std::invalid_argument
};

/// kState: state lines; kEstimates: the estimate stream; kLive: state lines plus the `gnss` and
/// `echo` observation lines of live_observations.hpp (the live view's stream).
enum class StreamKind { kState, kEstimates, kLive };

class ServiceSession {
 public:
  /// max_time_jump_s: how far ahead of the newest message a message may be (ServiceSettings).
  ServiceSession(SessionSpec spec, localization::LocalizationSession session,
                 std::unique_ptr<SessionJournal> journal, double max_time_jump_s);

  const std::string& name() const { return spec_.name; }
  /// What the session was opened with (never changes).
  const SessionSpec& spec() const { return spec_; }
  const formats::LogHeader& header() const { return spec_.header; }
  /// Journals the accepted messages from now on (a new session's journal, created after it was built).
  void AttachJournal(std::unique_ptr<SessionJournal> journal);
  /// The journal's path, if the session has one.
  std::optional<std::string> journal_path() const;
  /// Messages held in the reorder window.
  std::size_t pending() const;

  /// Accepts a parsed sensor message: journals `raw_line` (when journal is set), holds it in the
  /// reorder window and processes what the window releases, pushing to the subscribers. Returns the
  /// refusals of the filter for the messages released now ("t=...: reason"). Throws ServiceError:
  /// kTooOld (before the window), kInvalidField (more than max_time_jump_s after the newest
  /// message), kLimitExceeded (journal full).
  std::vector<std::string> Submit(std::string_view raw_line, formats::SensorMessage message, bool journal = true);
  /// Processes every held message (end of a stream, close).
  void Drain();
  /// Writes journal buffers out (end of a batch); with sync, also fsync (timer, shutdown).
  void FlushJournal(bool sync);
  /// Drains, then closes the journal (moved to closed/); returns its path, if any.
  std::optional<std::string> Close();

  /// The `state` object of docs/service.md §4 (without type and id).
  nlohmann::ordered_json State() const;
  /// A line for list_sessions.
  nlohmann::ordered_json Summary() const;

  /// Adds or replaces the subscription of `sink` (rate_hz 0: every change). Pushes the reply line
  /// that `reply` makes of the number of subscribers first, then (`estimates`) the estimate_header,
  /// so that nothing of the stream reaches the client before its reply.
  void Subscribe(const std::shared_ptr<OutputSink>& sink, StreamKind stream, double rate_hz,
                 const std::function<std::string(std::size_t subscribers)>& reply);
  /// Removes the subscription of a client; true when there was one.
  bool Unsubscribe(std::uint64_t client_id);

  std::size_t accepted() const;
  /// Messages the filter refused (after the reorder window).
  std::size_t rejected() const;
  /// Seconds since the last message or request used the session.
  double idle_s() const;
  void Touch();

 private:
  struct Subscriber {
    std::weak_ptr<OutputSink> sink;
    std::uint64_t client_id;
    StreamKind stream;
    double period_s;  ///< log time between state lines (0: every change)
    double last_push_t_s;
  };
  void ProcessReleased(formats::SensorMessage message, std::vector<std::string>& refusals);
  void Publish(const formats::SensorMessage& message, const localization::SessionStep& step);
  /// The estimate and update lines of a step, each ending with ,"session":NAME}.
  std::vector<std::string> EstimateLines(const localization::SessionStep& step);
  nlohmann::ordered_json StateLocked() const;

  mutable std::mutex mutex_;
  SessionSpec spec_;
  localization::LocalizationSession session_;
  localization::ReorderBuffer reorder_;
  std::unique_ptr<SessionJournal> journal_;
  double max_time_jump_s_;
  mapio::LocalFrame frame_;  ///< the session's local frame, for the state's latitude and longitude
  std::vector<Subscriber> subscribers_;
  std::size_t accepted_ = 0;
  std::size_t estimate_subscribers_ = 0;
  std::ostringstream estimate_text_;
  std::optional<formats::EstimateLogWriter> estimate_writer_;
  std::string estimate_header_;
  std::optional<std::string> last_refusal_;
  std::chrono::steady_clock::time_point last_used_ = std::chrono::steady_clock::now();
};

}  // namespace rowloc::service
