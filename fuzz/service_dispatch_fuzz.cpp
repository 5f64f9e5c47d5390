// libFuzzer target over the service's message parsing and dispatch (issue 25 §6; docs/building.md,
// "Fuzzing"). One Dispatcher, built once over the source tree's vehicles, maps and filters, with a
// journal directory in a temporary directory. Each input is the byte stream of one new client:
// framed into lines by the server's LineFramer, every line handled, one EndBatch, then ClientGone.
//
// Two sessions are open before every input so that sensor messages reach a real filter:
//   "f": agrimaro-swerve with the header of tests/data/logs/agrimaro-tiles-head.ndjson and an
//        initial pose at t = 0 (the seeds' f lines are that log's lines with "session":"f");
//   "m": vineyard-ugv-4ws on the map sample-vineyard, initialised in the corridor between row-1 and
//        row-2 at t = 118.4 (the seeds' m lines come from vineyard-002-1us-echoes.ndjson).
// They are opened once at start and reopened only when an input used them (accepted a message) or
// closed them, so every input starts from the same state and a crashing input reproduces on its own.
//
// Findings (abort()): a reply line that is not a JSON object with a string "type"; an error reply
// with code "internal"; after the input (held messages drained), a state of f or m that is not
// {initialised: false} or has a non-finite number or a covariance that is not exactly symmetric
// and positive definite (Eigen LLT). Sessions the input opened are closed after it.
#include "rowloc/service/dispatcher.hpp"
#include "rowloc/service/line_framer.hpp"
#include "rowloc/service/output_sink.hpp"
#include "rowloc/service/service_settings.hpp"

#include <Eigen/Cholesky>
#include <Eigen/Core>
#include <nlohmann/json.hpp>
#include <spdlog/spdlog.h>

#include <cmath>
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <memory>
#include <string>
#include <string_view>
#include <utility>
#include <vector>

namespace {

using rowloc::service::ClientContext;
using rowloc::service::Dispatcher;
using Json = nlohmann::json;

[[noreturn]] void Finding(const std::string& what, std::string_view line) {
  constexpr std::size_t kShown = 2000;
  std::fprintf(stderr, "service_dispatch_fuzz: FINDING: %s\n  line: %.*s%s\n", what.c_str(),
               static_cast<int>(std::min(line.size(), kShown)), line.data(), line.size() > kShown ? "..." : "");
  std::abort();
}

/// Checks every line the dispatcher sends; keeps them only when asked (the fixture's own requests).
class CheckingSink : public rowloc::service::OutputSink {
 public:
  CheckingSink(std::uint64_t id, bool keep) : id_(id), keep_(keep) {}
  void Push(std::string line, bool /*pushed*/) override {
    Json j = Json::parse(line, nullptr, /*allow_exceptions=*/false);
    if (j.is_discarded() || !j.is_object()) Finding("a line the service sent is not a JSON object", line);
    const auto type = j.find("type");
    if (type == j.end() || !type->is_string()) Finding("a line the service sent has no string \"type\"", line);
    if (*type == "error") {
      const auto code = j.find("code");
      if (code == j.end() || !code->is_string()) Finding("an error line without a string \"code\"", line);
      if (*code == "internal") Finding("an error with code \"internal\" (an exception nobody expected)", line);
    }
    if (keep_) lines_.push_back(std::move(j));
  }
  std::uint64_t client_id() const override { return id_; }
  std::vector<Json> Take() { return std::exchange(lines_, {}); }

 private:
  std::uint64_t id_;
  bool keep_;
  std::vector<Json> lines_;
};

std::filesystem::path SourceDir() { return ROWLOC_SOURCE_DIR; }

std::string FirstLine(const std::filesystem::path& path) {
  std::ifstream in(path);
  std::string line;
  if (!std::getline(in, line)) {
    std::fprintf(stderr, "service_dispatch_fuzz: cannot read %s\n", path.c_str());
    std::exit(2);
  }
  return line;
}

/// open_session requests of the two standing sessions.
Json OpenF() {
  return {{"type", "open_session"},
          {"session", "f"},
          {"vehicle", "agrimaro-swerve"},
          {"header", Json::parse(FirstLine(SourceDir() / "tests/data/logs/agrimaro-tiles-head.ndjson"))},
          {"initial_pose",
           {{"t", 0.0}, {"x_m", 0.0}, {"y_m", 0.0}, {"phi_rad", 0.0}, {"sigma_xy_m", 0.5}, {"sigma_phi_rad", 0.2}}}};
}
Json OpenM() {
  // Half-way between row-1 and row-2 of sample-vineyard, 20 m along the rows (heading 0.354 rad).
  return {{"type", "open_session"},
          {"session", "m"},
          {"vehicle", "vineyard-ugv-4ws"},
          {"map", "sample-vineyard"},
          {"initial_pose",
           {{"t", 118.4}, {"x_m", 18.4}, {"y_m", 8.0}, {"phi_rad", 0.354}, {"sigma_xy_m", 0.5},
            {"sigma_phi_rad", 0.1}}}};
}

class Fixture {
 public:
  Fixture() {
    spdlog::set_level(spdlog::level::err);  // not a line per opened session
    // tmpfs when there is one: a journal's metadata is written with fsync, which on a disk costs
    // milliseconds per reopened session.
    for (const std::filesystem::path& base :
         {std::filesystem::path("/dev/shm"), std::filesystem::temp_directory_path()}) {
      std::string pattern = (base / "rowloc-fuzz-XXXXXX").string();
      if (mkdtemp(pattern.data())) {
        journal_dir_ = pattern;
        break;
      }
    }
    if (journal_dir_.empty()) {
      std::perror("service_dispatch_fuzz: mkdtemp");
      std::exit(2);
    }
    rowloc::service::ServiceSettings settings;
    settings.vehicles_dir = SourceDir() / "config/vehicles";
    settings.maps_dir = SourceDir() / "maps";
    settings.filters_dir = SourceDir() / "config/filters";
    settings.journal_dir = journal_dir_;
    settings.fsync = rowloc::service::FsyncPolicy::kNone;
    settings.max_sessions = 16;  // an input that opens sessions in a loop stays small
    dispatcher_ = std::make_unique<Dispatcher>(settings);
    own_sink_ = std::make_shared<CheckingSink>(0, /*keep=*/true);
    own_.sink = own_sink_;
    standing_ = {{"f", OpenF(), nullptr}, {"m", OpenM(), nullptr}};
    for (Standing& s : standing_) Open(s);
  }

  // The process ends with exit(): close the sessions (journals to closed/) and remove the directory.
  void Cleanup() {
    dispatcher_->Shutdown();
    std::error_code ec;
    std::filesystem::remove_all(journal_dir_, ec);
  }

  void Run(std::string_view bytes) {
    auto sink = std::make_shared<CheckingSink>(++clients_, /*keep=*/false);
    ClientContext client;
    client.sink = sink;
    rowloc::service::LineFramer framer(dispatcher_->settings().max_line_bytes);
    const auto handle = [&](const rowloc::service::FramedLine& line) {
      if (line.kind == rowloc::service::FramedLine::Kind::kOversized) {
        dispatcher_->HandleOversizedLine(client, line.line_number);
      } else {
        dispatcher_->HandleLine(client, line.text, line.line_number);
      }
    };
    for (const auto& line : framer.Feed(bytes)) handle(line);
    if (const auto last = framer.Finish()) handle(*last);  // the server drops it; here it is one more line
    dispatcher_->EndBatch(client);
    dispatcher_->ClientGone(client);

    CloseOthers();
    for (Standing& s : standing_) {
      const auto session = dispatcher_->FindSession(s.name);
      const bool same = session && session == s.session;
      if (same) {
        session->Drain();  // what the reorder window holds reaches the filter and the check
        CheckState(s.name);
      }
      if (!same || session->accepted() > 0) {
        if (session) Request({{"type", "close_session"}, {"session", s.name}}, "session_closed");
        Open(s);
      }
    }
    // Closed sessions' journals move to closed/; nothing there is read again.
    std::error_code ec;
    std::filesystem::remove_all(journal_dir_ / "closed", ec);
  }

 private:
  struct Standing {
    std::string name;
    Json open;
    std::shared_ptr<rowloc::service::ServiceSession> session;
  };

  /// Sends a request as the fixture's own client and returns its reply, which must be of `type`.
  Json Request(const Json& request, std::string_view type) {
    dispatcher_->HandleLine(own_, request.dump(), ++own_lines_);
    dispatcher_->EndBatch(own_);
    std::vector<Json> lines = own_sink_->Take();
    if (lines.size() != 1 || lines.front()["type"] != type) {
      Finding("the fixture's request got no " + std::string(type) + " reply (" +
                  (lines.empty() ? std::string("nothing") : lines.back().dump()) + ")",
              request.dump());
    }
    return lines.front();
  }

  void Open(Standing& s) {
    Request(s.open, "session_opened");
    s.session = dispatcher_->FindSession(s.name);
  }

  void CloseOthers() {
    const Json list = Request({{"type", "list_sessions"}}, "sessions");
    for (const Json& summary : list["sessions"]) {
      const std::string name = summary["session"].get<std::string>();
      if (name != "f" && name != "m") Request({{"type", "close_session"}, {"session", name}}, "session_closed");
    }
  }

  static void RequireNumber(const Json& state, const Json& value, const std::string& key) {
    if (!value.is_number() || !std::isfinite(value.get<double>())) {
      Finding(key + " is not a finite number in an initialised state", state.dump());
    }
  }

  static void AllFinite(const Json& state, const Json& value) {
    if (value.is_number_float() && !std::isfinite(value.get<double>())) Finding("a non-finite number", state.dump());
    if (value.is_structured()) {
      for (const Json& item : value) AllFinite(state, item);
    }
  }

  void CheckState(const std::string& name) {
    const Json state = Request({{"type", "get_state"}, {"session", name}}, "state");
    AllFinite(state, state);
    const auto initialised = state.find("initialised");
    if (initialised == state.end() || !initialised->is_boolean()) {
      Finding("state without a boolean initialised", state.dump());
    }
    if (!*initialised) return;
    for (const char* key : {"t", "x_m", "y_m", "phi_rad", "latitude_deg", "longitude_deg"}) {
      RequireNumber(state, state.value(key, Json()), key);
    }
    for (const char* key : {"semi_major_m", "semi_minor_m", "angle_rad"}) {
      RequireNumber(state, state["ellipse_2sigma"].value(key, Json()), std::string("ellipse_2sigma.") + key);
    }
    for (const char* key : {"x_mps", "y_mps", "yaw_rate_radps"}) {
      RequireNumber(state, state["velocity"].value(key, Json()), std::string("velocity.") + key);
    }
    const Json& covariance = state["covariance_xy_phi"];
    if (!covariance.is_array() || covariance.size() != 9) Finding("covariance_xy_phi is not 9 numbers", state.dump());
    Eigen::Matrix3d p;
    for (int i = 0; i < 9; ++i) {
      RequireNumber(state, covariance[i], "covariance_xy_phi");
      p(i / 3, i % 3) = covariance[i].get<double>();
    }
    if (p != p.transpose()) Finding("the covariance of " + name + " is not symmetric", state.dump());
    if (Eigen::LLT<Eigen::Matrix3d>(p).info() != Eigen::Success) {
      Finding("the covariance of " + name + " is not positive definite", state.dump());
    }
  }

  std::filesystem::path journal_dir_;
  std::unique_ptr<Dispatcher> dispatcher_;
  std::shared_ptr<CheckingSink> own_sink_;
  ClientContext own_;
  std::size_t own_lines_ = 0;
  std::uint64_t clients_ = 0;
  std::vector<Standing> standing_;
};

Fixture* fixture = nullptr;  // never destroyed: libFuzzer ends with exit(), Cleanup runs from atexit

}  // namespace

extern "C" int LLVMFuzzerInitialize(int* /*argc*/, char*** /*argv*/) {
  fixture = new Fixture();
  std::atexit([] { fixture->Cleanup(); });
  return 0;
}

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  fixture->Run(std::string_view(reinterpret_cast<const char*>(data), size));
  return 0;
}
