// A dispatcher driven as a client would drive it, without sockets: lines in, reply lines out.
#pragma once

#include "rowloc/service/dispatcher.hpp"
#include "test_support.hpp"

#include <nlohmann/json.hpp>

#include <fstream>
#include <mutex>
#include <string>
#include <vector>

namespace rowloc::service::test {

/// Collects the lines a client would receive.
class ListSink : public OutputSink {
 public:
  explicit ListSink(std::uint64_t id = 1) : id_(id) {}
  void Push(std::string line, bool pushed) override {
    std::lock_guard lock(mutex_);
    lines_.push_back(std::move(line));
    if (pushed) ++pushed_;
  }
  std::uint64_t client_id() const override { return id_; }
  std::vector<std::string> Take() {
    std::lock_guard lock(mutex_);
    std::vector<std::string> lines;
    lines.swap(lines_);
    return lines;
  }
  std::size_t pushed() const { return pushed_; }

 private:
  std::uint64_t id_;
  std::mutex mutex_;
  std::vector<std::string> lines_;
  std::size_t pushed_ = 0;
};

/// Settings over the source tree's vehicles, maps and filters.
inline ServiceSettings SourceTreeSettings() {
  ServiceSettings s;
  const auto source = rowloc::test::SourceDir();
  s.vehicles_dir = source / "config/vehicles";
  s.maps_dir = source / "maps";
  s.filters_dir = source / "config/filters";
  return s;
}

/// One client of a dispatcher.
class TestClient {
 public:
  explicit TestClient(Dispatcher& dispatcher, std::uint64_t id = 1)
      : dispatcher_(dispatcher), sink_(std::make_shared<ListSink>(id)) {
    context_.sink = sink_;
  }
  ~TestClient() { dispatcher_.ClientGone(context_); }

  /// Sends one line (a batch of one) and returns every line received since the last call.
  std::vector<std::string> SendRaw(const std::string& line) {
    dispatcher_.HandleLine(context_, line, ++line_number_);
    dispatcher_.EndBatch(context_);
    return sink_->Take();
  }
  /// Sends a request and returns the last line received, parsed.
  nlohmann::json Send(const nlohmann::json& request) {
    const std::vector<std::string> lines = SendRaw(request.dump());
    return lines.empty() ? nlohmann::json() : nlohmann::json::parse(lines.back());
  }
  /// The lines received since the last call.
  std::vector<std::string> Take() { return sink_->Take(); }
  ClientContext& context() { return context_; }

 private:
  Dispatcher& dispatcher_;
  std::shared_ptr<ListSink> sink_;
  ClientContext context_;
  std::size_t line_number_ = 0;
};

/// The lines of a sensor log file (the header first).
inline std::vector<std::string> LogLines(const std::string& file) {
  std::ifstream in(rowloc::test::SourceDir() / "tests/data/logs" / file);
  std::vector<std::string> lines;
  for (std::string line; std::getline(in, line);) {
    if (!line.empty()) lines.push_back(line);
  }
  return lines;
}

/// The log line with "session" added.
inline std::string InSession(const std::string& line, const std::string& session) {
  nlohmann::ordered_json j = nlohmann::ordered_json::parse(line);
  j["session"] = session;
  return j.dump();
}

/// open_session for the AgriMaRo swerve robot with the tiles log's header and a known initial pose.
inline nlohmann::json OpenTilesSession(const std::string& name, double reorder_window_s = 0.2) {
  const nlohmann::json header = nlohmann::json::parse(LogLines("agrimaro-tiles-head.ndjson").front());
  return {{"type", "open_session"}, {"id", 1}, {"session", name}, {"vehicle", "agrimaro-swerve"},
          {"header", header}, {"reorder_window_s", reorder_window_s},
          {"initial_pose", {{"t", 0.0}, {"x_m", 0.0}, {"y_m", 0.0}, {"phi_rad", 0.0}, {"sigma_xy_m", 0.5},
                            {"sigma_phi_rad", 0.2}}}};
}

}  // namespace rowloc::service::test
