// The C++ client (rowloc::service::Client) and `rowloc send` as users meet them: against a real
// `rowloc serve` process on an ephemeral loopback port (--port 0; the port is read from the first
// stdout line), with the shipped vehicles, maps and filters (docs/service.md). Each test starts its
// own servers and always stops them (SIGTERM, SIGKILL after 10 s); a graceful stop must exit 0.
// The sensor log is simulated once per test process (`rowloc simulate vineyard-002-4us`, about 1 s)
// and cut to its first kLogMessages messages: the filter initialises from GNSS at line 4069
// (t = 16.6 s); tests that need an initialised filter earlier give the truth's first pose instead.
// ROWLOC_BIN is the rowloc executable (tests/CMakeLists.txt).
#include "rowloc/service/client.hpp"
#include "test_support.hpp"

#include <gmock/gmock.h>
#include <gtest/gtest.h>
#include <nlohmann/json.hpp>

#include <fcntl.h>
#include <poll.h>
#include <signal.h>
#include <spawn.h>
#include <sys/wait.h>
#include <unistd.h>

#include <array>
#include <chrono>
#include <cmath>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <functional>
#include <mutex>
#include <optional>
#include <sstream>
#include <stdexcept>
#include <string>
#include <thread>
#include <vector>

extern char** environ;

namespace rowloc::service {
namespace {

using namespace std::chrono_literals;
using Json = nlohmann::json;
using rowloc::test::ScratchDir;
using rowloc::test::SourceDir;
namespace fs = std::filesystem;

constexpr char kVehicle[] = "vineyard-ugv-4ws";
constexpr char kMap[] = "sample-vineyard";
constexpr std::size_t kLogMessages = 8000;  // t = 0 .. 32.7 s
constexpr std::size_t kInitialisedAfter = 4500;  // the GNSS initialisation is at message 4068

std::string ReadFile(const fs::path& path) {
  std::ifstream in(path, std::ios::binary);
  std::ostringstream text;
  text << in.rdbuf();
  return text.str();
}

std::vector<std::string> ReadLines(const fs::path& path) {
  std::ifstream in(path, std::ios::binary);
  std::vector<std::string> lines;
  for (std::string line; std::getline(in, line);) lines.push_back(line);
  return lines;
}

// ----- child processes ------------------------------------------------------------------------------

/// A child process (posix_spawn): stdin from /dev/null, stdout to a pipe the parent reads or to a
/// file, stderr to a file. The destructor kills it (SIGKILL) if it still runs.
class Child {
 public:
  Child(const std::vector<std::string>& argv, const fs::path& stderr_path, bool stdout_to_pipe,
        const fs::path& stdout_path = "/dev/null") {
    int fds[2] = {-1, -1};
    if (stdout_to_pipe && ::pipe2(fds, O_CLOEXEC) != 0) throw std::runtime_error("pipe2 failed");
    posix_spawn_file_actions_t actions;
    posix_spawn_file_actions_init(&actions);
    posix_spawn_file_actions_addopen(&actions, 0, "/dev/null", O_RDONLY, 0);
    if (stdout_to_pipe) {
      posix_spawn_file_actions_adddup2(&actions, fds[1], 1);
    } else {
      posix_spawn_file_actions_addopen(&actions, 1, stdout_path.c_str(), O_WRONLY | O_CREAT | O_TRUNC, 0644);
    }
    posix_spawn_file_actions_addopen(&actions, 2, stderr_path.c_str(), O_WRONLY | O_CREAT | O_TRUNC, 0644);
    std::vector<char*> args;
    for (const std::string& a : argv) args.push_back(const_cast<char*>(a.c_str()));
    args.push_back(nullptr);
    const int error = ::posix_spawn(&pid_, args[0], &actions, nullptr, args.data(), environ);
    posix_spawn_file_actions_destroy(&actions);
    if (stdout_to_pipe) ::close(fds[1]);
    if (error != 0) {
      if (stdout_to_pipe) ::close(fds[0]);
      throw std::runtime_error("cannot start " + argv[0] + ": " + std::strerror(error));
    }
    stdout_fd_ = fds[0];
  }
  ~Child() {
    if (running()) {
      ::kill(pid_, SIGKILL);
      Wait(10s);
    }
    if (stdout_fd_ >= 0) ::close(stdout_fd_);
  }
  Child(const Child&) = delete;
  Child& operator=(const Child&) = delete;

  bool running() const { return !status_; }
  int stdout_fd() const { return stdout_fd_; }

  /// The wait status once the process has ended, waiting at most `timeout`.
  std::optional<int> Wait(std::chrono::milliseconds timeout) {
    const auto deadline = std::chrono::steady_clock::now() + timeout;
    while (!status_) {
      int status = 0;
      const pid_t r = ::waitpid(pid_, &status, WNOHANG);
      if (r == pid_) {
        status_ = status;
      } else if (std::chrono::steady_clock::now() >= deadline) {
        break;
      } else {
        std::this_thread::sleep_for(5ms);
      }
    }
    return status_;
  }

  /// Sends `signal`, then SIGKILL when it has not ended after `grace`; the wait status.
  int Stop(int signal, std::chrono::milliseconds grace) {
    if (running()) ::kill(pid_, signal);
    if (!Wait(grace)) {
      ::kill(pid_, SIGKILL);
      Wait(30s);
    }
    return status_.value_or(-1);
  }

 private:
  pid_t pid_ = -1;
  int stdout_fd_ = -1;
  std::optional<int> status_;
};

/// "exit N" or "signal N" of a wait status.
std::string Describe(int status) {
  if (WIFEXITED(status)) return "exit " + std::to_string(WEXITSTATUS(status));
  if (WIFSIGNALED(status)) return "signal " + std::to_string(WTERMSIG(status));
  return "status " + std::to_string(status);
}

/// Runs rowloc with these arguments to its end (at most `timeout`); the wait status. Its stdout (where
/// its log lines go) is written next to stderr_path, as NAME.stdout.
int RunRowloc(const std::vector<std::string>& args, const fs::path& stderr_path,
              std::chrono::milliseconds timeout = 120s) {
  std::vector<std::string> argv{ROWLOC_BIN};
  argv.insert(argv.end(), args.begin(), args.end());
  Child child(argv, stderr_path, false, fs::path(stderr_path).replace_extension(".stdout"));
  if (!child.Wait(timeout)) throw std::runtime_error("rowloc " + args.at(0) + " did not end in time");
  return child.Stop(SIGKILL, 0ms);
}

// ----- the server -------------------------------------------------------------------------------------

struct ServerOptions {
  fs::path journal_dir;                   ///< empty: WORKDIR/journal
  fs::path maps_dir = SourceDir() / "maps";
  fs::path vehicles_dir = SourceDir() / "config" / "vehicles";
  fs::path filters_dir = SourceDir() / "config" / "filters";
  std::vector<std::string> extra;         ///< more options
};

/// A `rowloc serve --port 0` process on 127.0.0.1, by default with the source tree's vehicles and filters.
class Server {
 public:
  Server(const fs::path& workdir, ServerOptions options = {}) {
    fs::create_directories(workdir);
    journal_dir_ = options.journal_dir.empty() ? workdir / "journal" : options.journal_dir;
    fs::create_directories(journal_dir_);
    static int count = 0;
    stderr_path_ = workdir / ("serve-" + std::to_string(++count) + ".stderr");
    std::vector<std::string> argv{ROWLOC_BIN,
                                  "serve",
                                  "--port",
                                  "0",
                                  "--vehicles",
                                  options.vehicles_dir.string(),
                                  "--maps",
                                  options.maps_dir.string(),
                                  "--filters",
                                  options.filters_dir.string(),
                                  "--journal-dir",
                                  journal_dir_.string()};
    argv.insert(argv.end(), options.extra.begin(), options.extra.end());
    process_.emplace(argv, stderr_path_, true);
    ReadListeningLine();
  }
  ~Server() {
    if (process_->running()) process_->Stop(SIGKILL, 0ms);
  }

  const Json& listening() const { return listening_; }
  unsigned short port() const { return port_; }
  std::string address() const { return "127.0.0.1:" + std::to_string(port_); }
  const fs::path& journal_dir() const { return journal_dir_; }

  /// A connected client that has said hello.
  Client Connect() const {
    Client client = Client::ConnectTcp("127.0.0.1", port_);
    client.Hello();
    return client;
  }

  /// SIGTERM, then SIGKILL after 10 s; the wait status (a graceful stop is exit 0).
  int Stop() { return process_->Stop(SIGTERM, 10s); }
  /// kill -9.
  void Kill() { process_->Stop(SIGKILL, 0ms); }

  std::string StderrTail() const {
    const std::string text = ReadFile(stderr_path_);
    return text.size() > 3000 ? text.substr(text.size() - 3000) : text;
  }

 private:
  void ReadListeningLine() {
    const auto deadline = std::chrono::steady_clock::now() + 30s;
    std::string text;
    while (text.find('\n') == std::string::npos) {
      const auto left = std::chrono::duration_cast<std::chrono::milliseconds>(deadline - std::chrono::steady_clock::now());
      if (left <= 0ms) throw std::runtime_error("rowloc serve printed no listening line in 30 s\n" + StderrTail());
      pollfd p{process_->stdout_fd(), POLLIN, 0};
      if (::poll(&p, 1, static_cast<int>(left.count())) <= 0) continue;
      std::array<char, 4096> buffer{};
      const ssize_t n = ::read(process_->stdout_fd(), buffer.data(), buffer.size());
      if (n <= 0) {
        const std::optional<int> status = process_->Wait(5s);
        throw std::runtime_error("rowloc serve ended before listening (" + (status ? Describe(*status) : "?") +
                                 ")\n" + StderrTail());
      }
      text.append(buffer.data(), static_cast<std::size_t>(n));
    }
    listening_ = Json::parse(text.substr(0, text.find('\n')));
    if (listening_.value("type", "") != "listening") throw std::runtime_error("not a listening line: " + text);
    const std::string tcp = listening_.at("tcp").get<std::string>();
    if (tcp.rfind("127.0.0.1:", 0) != 0) throw std::runtime_error("listening on " + tcp);
    port_ = static_cast<unsigned short>(std::stoi(tcp.substr(tcp.rfind(':') + 1)));
  }

  fs::path journal_dir_, stderr_path_;
  std::optional<Child> process_;
  Json listening_;
  unsigned short port_ = 0;
};

#define EXPECT_GRACEFUL_STOP(server)                                                       \
  do {                                                                                     \
    const int status_ = (server).Stop();                                                   \
    EXPECT_TRUE(WIFEXITED(status_) && WEXITSTATUS(status_) == 0)                           \
        << "rowloc serve after SIGTERM: " << Describe(status_) << "\n" << (server).StderrTail(); \
  } while (false)

// ----- the sensor log -----------------------------------------------------------------------------------

struct SimulatedLog {
  std::string header_line;
  Json header;
  std::vector<std::string> lines;  ///< the first kLogMessages messages
  Json initial_pose;               ///< the truth at t = 0, sigma 0.3 m and 0.05 rad
  fs::path row_map;                ///< the run's true row map
  fs::path dir;

  /// The header and the first `n` messages as a log file.
  fs::path Write(std::size_t n) const {
    const fs::path path = dir / ("log-" + std::to_string(n) + ".ndjson");
    if (!fs::exists(path)) {
      std::ofstream out(path, std::ios::binary);
      out << header_line << '\n';
      for (std::size_t i = 0; i < n; ++i) out << lines.at(i) << '\n';
    }
    return path;
  }
};

SimulatedLog Simulate(const fs::path& dir) {
  SimulatedLog log;
  log.dir = dir;
  const fs::path run = dir / "sim";
  const int status = RunRowloc({"simulate", (SourceDir() / "config" / "scenarios" / "vineyard-002-4us.json").string(),
                                "-o", run.string(), "--no-baselines"},
                               dir / "simulate.stderr");
  if (!WIFEXITED(status) || WEXITSTATUS(status) != 0) {
    throw std::runtime_error("rowloc simulate failed (" + Describe(status) + "): " + ReadFile(dir / "simulate.stdout") +
                             ReadFile(dir / "simulate.stderr"));
  }
  {
    std::ifstream in(run / "sensors.ndjson", std::ios::binary);
    std::getline(in, log.header_line);
    for (std::string line; log.lines.size() < kLogMessages && std::getline(in, line);) log.lines.push_back(line);
  }
  log.header = Json::parse(log.header_line);
  {
    std::ifstream in(run / "truth.ndjson", std::ios::binary);
    std::string line;
    std::getline(in, line);  // truth_header
    std::getline(in, line);
    const Json truth = Json::parse(line);
    log.initial_pose = {{"t", truth.at("t")},          {"x_m", truth.at("x_m")},
                        {"y_m", truth.at("y_m")},      {"phi_rad", truth.at("phi_rad")},
                        {"sigma_xy_m", 0.3},           {"sigma_phi_rad", 0.05}};
  }
  fs::remove(run / "sensors.ndjson");
  fs::remove(run / "truth.ndjson");
  log.row_map = run / "row-map.geojson";
  return log;
}

/// The simulated log, made once per test process.
const SimulatedLog& Log() {
  static ScratchDir dir;
  static const SimulatedLog log = Simulate(dir.path());
  return log;
}

/// open_session parameters for the log's vehicle and the sample map, with the log's header.
Json OpenParameters(const std::string& session, bool with_initial_pose = false) {
  Json open{{"session", session}, {"vehicle", kVehicle}, {"map", kMap}, {"header", Log().header}};
  if (with_initial_pose) open["initial_pose"] = Log().initial_pose;
  return open;
}

void Stream(Client& client, const std::string& session, std::size_t from, std::size_t to) {
  for (std::size_t i = from; i < to; ++i) client.SendMessage(session, Log().lines.at(i));
}

/// A state reply without what differs between equal sessions (its id and the session's name).
std::string Comparable(Json state) {
  state.erase("id");
  state.erase("session");
  return state.dump();
}

/// The code of the ClientError `call` throws; "(none)" when it returns.
std::string CodeOf(const std::function<void()>& call) {
  try {
    call();
  } catch (const ClientError& e) {
    return e.code();
  }
  return "(none)";
}

/// True when `call` throws a std::runtime_error that is not a ClientError (a lost connection).
bool LosesTheConnection(const std::function<void()>& call) {
  try {
    call();
  } catch (const ClientError&) {
    return false;
  } catch (const std::runtime_error&) {
    return true;
  }
  return false;
}

/// A finite number.
bool Finite(const Json& v) { return v.is_number() && std::isfinite(v.get<double>()); }

/// Cholesky of a row-major 3x3 matrix: true when symmetric positive definite.
bool SymmetricPositiveDefinite(const Json& m) {
  if (!m.is_array() || m.size() != 9) return false;
  double a[3][3];
  for (int i = 0; i < 3; ++i)
    for (int j = 0; j < 3; ++j) {
      if (!Finite(m[3 * i + j])) return false;
      a[i][j] = m[3 * i + j].get<double>();
    }
  for (int i = 0; i < 3; ++i)
    for (int j = 0; j < i; ++j)
      if (std::abs(a[i][j] - a[j][i]) > 1e-12 * (std::abs(a[i][i]) + std::abs(a[j][j]))) return false;
  double l[3][3] = {};
  for (int i = 0; i < 3; ++i)
    for (int j = 0; j <= i; ++j) {
      double s = a[i][j];
      for (int k = 0; k < j; ++k) s -= l[i][k] * l[j][k];
      if (i == j) {
        if (!(s > 0.0)) return false;
        l[i][i] = std::sqrt(s);
      } else {
        l[i][j] = s / l[j][j];
      }
    }
  return true;
}

// ----- the tests -----------------------------------------------------------------------------------------

TEST(ClientServer, HelloOpenSessionStreamAndAFiniteStateWithSpdCovariance) {
  ScratchDir work;
  Server server(work.path());
  Client client = Client::ConnectTcp("127.0.0.1", server.port());
  const Json hello = client.Hello();
  EXPECT_EQ(hello.value("type", ""), "hello");
  EXPECT_EQ(hello.value("protocol", ""), "rowloc-service/1");
  EXPECT_EQ(hello.value("sensor_protocol", ""), "rowloc/1");
  EXPECT_EQ(hello.value("auth", ""), "none");

  ASSERT_EQ(client.OpenSession(OpenParameters("ugv1")), "ugv1");
  const Json before = client.GetState("ugv1");
  EXPECT_EQ(before.value("initialised", true), false);
  EXPECT_FALSE(before.contains("x_m"));
  Stream(client, "ugv1", 0, kInitialisedAfter);

  const Json state = client.GetState("ugv1");
  EXPECT_EQ(state.value("type", ""), "state");
  EXPECT_EQ(state.value("session", ""), "ugv1");
  ASSERT_EQ(state.value("initialised", false), true) << state.dump();
  for (const char* key : {"t", "x_m", "y_m", "phi_rad", "latitude_deg", "longitude_deg"}) {
    EXPECT_TRUE(Finite(state[key])) << key << " in " << state.dump();
  }
  // The state answers for the messages up to the reorder window (0.2 s) before the newest one.
  const double newest = Json::parse(Log().lines.at(kInitialisedAfter - 1)).at("t").get<double>();
  EXPECT_LE(state["t"].get<double>(), newest - 0.2 + 1e-9);
  EXPECT_GT(state["t"].get<double>(), newest - 0.3);
  EXPECT_TRUE(SymmetricPositiveDefinite(state["covariance_xy_phi"])) << state["covariance_xy_phi"].dump();
  for (const char* key : {"semi_major_m", "semi_minor_m", "angle_rad"}) {
    EXPECT_TRUE(Finite(state["ellipse_2sigma"][key])) << key;
  }
  EXPECT_GE(state["ellipse_2sigma"]["semi_major_m"].get<double>(), state["ellipse_2sigma"]["semi_minor_m"].get<double>());
  for (const char* key : {"x_mps", "y_mps", "yaw_rate_radps"}) EXPECT_TRUE(Finite(state["velocity"][key])) << key;
  ASSERT_TRUE(state["slip"].is_object());
  EXPECT_EQ(state["slip"].size(), 4u);
  EXPECT_GT(state["health"]["sensors"]["gnss"]["accepted"].get<int>(), 0) << state["health"].dump();
  EXPECT_TRUE(Finite(state["health"]["last_fix_age_s"]));
  EXPECT_EQ(state["health"]["rejected_messages"].get<int>(), 0);
  EXPECT_FALSE(client.TakeError()) << "an error to a sensor message";

  const Json stats = client.Stats();
  EXPECT_EQ(stats["sessions"].get<int>(), 1);
  EXPECT_EQ(stats["messages"].get<std::size_t>(), kInitialisedAfter);
  EXPECT_TRUE(stats["rejects"].empty()) << stats.dump();

  // A graceful stop tells the client, which then finds the connection closed (not a timeout).
  EXPECT_GRACEFUL_STOP(server);
  const std::optional<std::string> notice = client.ReadPushed(5s);
  ASSERT_TRUE(notice);
  EXPECT_EQ(Json::parse(*notice).value("type", ""), "shutdown");
  const auto start = std::chrono::steady_clock::now();
  EXPECT_TRUE(LosesTheConnection([&] { client.GetState("ugv1"); }));
  EXPECT_LT(std::chrono::steady_clock::now() - start, 5s);
  EXPECT_FALSE(client.ReadPushed(0ms));
}

TEST(ClientServer, FiftySessionsOverFourConnectionsEndAsTheLogStreamedAlone) {
  constexpr std::size_t kMessages = 1500;  // t = 0 .. 6.1 s, from the truth's first pose
  constexpr int kSessions = 50, kConnections = 4;
  ScratchDir work;
  Server server(work.path());
  std::string alone;
  {
    Client client = server.Connect();
    client.OpenSession(OpenParameters("alone", true));
    Stream(client, "alone", 0, kMessages);
    const Json state = client.GetState("alone");
    ASSERT_TRUE(state.value("initialised", false)) << state.dump();
    alone = Comparable(state);
    EXPECT_FALSE(client.TakeError());
  }

  std::vector<Json> states(kSessions);
  std::mutex failures_mutex;
  std::vector<std::string> failures;
  std::vector<std::thread> threads;
  for (int c = 0; c < kConnections; ++c) {
    threads.emplace_back([&, c] {
      try {
        Client client = server.Connect();
        std::vector<std::string> names;
        for (int s = c; s < kSessions; s += kConnections) {
          names.push_back(client.OpenSession(OpenParameters("fleet-" + std::to_string(s), true)));
        }
        for (std::size_t i = 0; i < kMessages; ++i) {
          for (const std::string& name : names) client.SendMessage(name, Log().lines[i]);
        }
        for (int s = c, k = 0; s < kSessions; s += kConnections, ++k) states[s] = client.GetState(names[k]);
        if (const std::optional<Json> error = client.TakeError()) throw std::runtime_error(error->dump());
      } catch (const std::exception& e) {
        std::lock_guard lock(failures_mutex);
        failures.push_back("connection " + std::to_string(c) + ": " + e.what());
      }
    });
  }
  for (std::thread& t : threads) t.join();
  EXPECT_TRUE(failures.empty()) << failures.front();
  for (int s = 0; s < kSessions; ++s) {
    EXPECT_EQ(states[s].value("session", ""), "fleet-" + std::to_string(s));
    EXPECT_EQ(Comparable(states[s]), alone) << "session fleet-" << s;
  }
  Client client = server.Connect();
  const Json stats = client.Stats();
  EXPECT_EQ(stats["sessions"].get<int>(), kSessions + 1);
  EXPECT_EQ(stats["messages"].get<std::size_t>(), (kSessions + 1) * kMessages);
  EXPECT_TRUE(stats["rejects"].empty()) << stats.dump();
  EXPECT_EQ(stats["dropped_states"].get<int>(), 0);
  EXPECT_GRACEFUL_STOP(server);
}

TEST(ClientServer, EveryErrorReachesTheClientWithItsCodeAndTheConnectionGoesOn) {
  ScratchDir work;
  {
    std::ofstream settings(work / "settings.json");
    settings << R"({"max_line_bytes": 65536})";
  }
  ServerOptions options;
  options.extra = {"--config", (work / "settings.json").string()};
  Server server(work.path(), options);
  Client client = server.Connect();

  // Replies to requests: ClientError with the code.
  EXPECT_EQ(CodeOf([&] { client.GetState("no-such-session"); }), "unknown_session");
  EXPECT_EQ(CodeOf([&] { client.CloseSession("no-such-session"); }), "unknown_session");
  EXPECT_EQ(CodeOf([&] { client.OpenSession(OpenParameters("../escape")); }), "invalid_name");
  EXPECT_EQ(CodeOf([&] { client.OpenSession({{"vehicle", "../vehicles/vineyard-ugv-4ws"}, {"map", kMap}}); }),
            "invalid_name");
  EXPECT_EQ(CodeOf([&] { client.OpenSession({{"vehicle", "no-such-vehicle"}, {"map", kMap}}); }), "unknown_vehicle");
  EXPECT_EQ(CodeOf([&] { client.OpenSession({{"vehicle", kVehicle}, {"map", "no-such-map"}}); }), "unknown_map");
  EXPECT_EQ(CodeOf([&] { client.OpenSession({{"vehicle", kVehicle}, {"map", kMap}, {"filter", "no-such"}}); }),
            "unknown_filter");
  EXPECT_EQ(CodeOf([&] { client.OpenSession({{"map", kMap}}); }), "missing_field");
  EXPECT_EQ(CodeOf([&] { client.Request({{"type", "teleport"}}); }), "unknown_type");
  EXPECT_EQ(CodeOf([&] { client.Request({{"type", "hello"}, {"protocol", "rowloc-service/2"}}); }),
            "unsupported_protocol");

  Json open = OpenParameters("errs");
  open["reorder_window_s"] = 0.0;  // every message at once: an older one is too old
  ASSERT_EQ(client.OpenSession(open), "errs");
  EXPECT_EQ(CodeOf([&] { client.OpenSession(open); }), "session_exists");
  EXPECT_EQ(CodeOf([&] { client.Subscribe("errs", "video"); }), "invalid_field");
  Stream(client, "errs", 0, 100);
  // A sensor message sent as a request (with an id) that is older than the applied ones.
  try {
    client.Request(Json::parse(WithSessionKey(Log().lines[50], "errs")));
    ADD_FAILURE() << "an old message was accepted";
  } catch (const ClientError& e) {
    EXPECT_EQ(e.code(), "too_old");
    EXPECT_TRUE(e.reply()["id"].is_number_integer());
    EXPECT_NE(std::string(e.what()).find("older than the session's reorder window"), std::string::npos) << e.what();
  }
  // A request line longer than max_line_bytes: the server cannot read its id, the error names its
  // line, and the client still gives it to the request that waits for it.
  try {
    client.Request({{"type", "get_state"}, {"session", "errs"}, {"padding", std::string(70000, 'x')}}, 10s);
    ADD_FAILURE() << "a line of 70 kB was accepted";
  } catch (const ClientError& e) {
    EXPECT_EQ(e.code(), "line_too_long");
    EXPECT_TRUE(e.reply()["id"].is_null());
  }

  // Lines sent without an id: their errors come through TakeError, in order, naming their lines.
  client.SendMessage("errs", Log().lines[60]);
  client.SendLine("this is not JSON");
  client.SendLine("[1, 2, 3]");
  client.SendMessage("no-such-session", Log().lines[100]);
  client.SendLine(R"({"type":"imu","session":"errs","t":"soon"})");
  Stream(client, "errs", 100, 200);  // the session goes on
  const Json state = client.GetState("errs");  // its reply comes after every error above
  std::vector<Json> errors;
  while (const std::optional<Json> e = client.TakeError()) errors.push_back(*e);
  ASSERT_EQ(errors.size(), 5u);
  const std::vector<std::string> codes{"too_old", "malformed_json", "not_an_object", "unknown_session",
                                       "invalid_field"};
  for (std::size_t i = 0; i < errors.size(); ++i) {
    EXPECT_EQ(errors[i].value("type", ""), "error");
    EXPECT_EQ(errors[i].value("code", ""), codes[i]) << errors[i].dump();
    EXPECT_TRUE(errors[i]["id"].is_null());
    EXPECT_FALSE(errors[i].value("message", "").empty());
    EXPECT_EQ(errors[i]["line"].get<std::size_t>(), errors[0]["line"].get<std::size_t>() + i);
  }
  EXPECT_FALSE(client.ReadPushed(0ms)) << "an error came as a pushed line";

  // The connection and the session went on.
  EXPECT_EQ(client.Hello().value("type", ""), "hello");
  EXPECT_EQ(state["t"].get<double>(), Json::parse(Log().lines[199]).at("t").get<double>());
  EXPECT_EQ(state["health"]["pending"].get<int>(), 0);
  const Json closed = client.CloseSession("errs");
  EXPECT_EQ(closed["messages"].get<int>(), 200);
  EXPECT_EQ(closed["rejected"].get<int>(), 0);
  const Json stats = client.Stats();
  EXPECT_EQ(stats["rejects"].value("too_old", 0), 2);
  EXPECT_EQ(stats["rejects"].value("unknown_session", 0), 3);
  EXPECT_EQ(stats["rejects"].value("line_too_long", 0), 1);
  EXPECT_GRACEFUL_STOP(server);
}

TEST(ClientServer, KillNineMidStreamThenRestartResumesTheSameStateAndTheSameEnd) {
  constexpr std::size_t kBefore = 5000;  // initialised from GNSS at message 4068
  ScratchDir work;
  std::string uninterrupted;
  {
    Server server(work / "reference");
    Client client = server.Connect();
    client.OpenSession(OpenParameters("whole"));
    Stream(client, "whole", 0, kLogMessages);
    uninterrupted = Comparable(client.GetState("whole"));
    EXPECT_GRACEFUL_STOP(server);
  }

  Json before;
  const fs::path journal = work / "journal";
  {
    ServerOptions options;
    options.journal_dir = journal;
    Server server(work / "first", options);
    Client client = server.Connect();
    Json open = OpenParameters("crash");
    open["type"] = "open_session";
    const Json opened = client.Request(open);
    EXPECT_EQ(opened.value("journal", ""), (journal / "crash.ndjson").string());
    Stream(client, "crash", 0, kBefore);
    before = client.GetState("crash");  // every line before it is in the journal when it is answered
    ASSERT_TRUE(before.value("initialised", false));
    server.Kill();
    EXPECT_TRUE(LosesTheConnection([&] { client.GetState("crash"); }));
  }
  ServerOptions options;
  options.journal_dir = journal;
  Server server(work / "second", options);
  EXPECT_EQ(server.listening().value("resumed_sessions", 0), 1);
  Client client = server.Connect();
  Json after = client.GetState("crash");
  before.erase("id");
  after.erase("id");
  EXPECT_EQ(after.dump(), before.dump());
  Stream(client, "crash", kBefore, kLogMessages);
  EXPECT_EQ(Comparable(client.GetState("crash")), uninterrupted);
  EXPECT_EQ(client.CloseSession("crash")["messages"].get<std::size_t>(), kLogMessages);
  EXPECT_FALSE(client.TakeError());
  EXPECT_GRACEFUL_STOP(server);
  EXPECT_FALSE(fs::exists(journal / "crash.ndjson"));
  EXPECT_TRUE(fs::exists(journal / "closed" / "crash-1.ndjson"));
}

TEST(ClientServer, KillNineWithLinesInFlightResumesExactlyWhatTheJournalHolds) {
  constexpr std::size_t kSynced = 4500, kSent = 6000;
  ScratchDir work;
  const fs::path journal = work / "journal";
  ServerOptions options;
  options.journal_dir = journal;
  {
    Server server(work / "first", options);
    Client client = server.Connect();
    client.OpenSession(OpenParameters("crash"));
    Stream(client, "crash", 0, kSynced);
    client.GetState("crash");                 // the first kSynced messages are in the journal
    Stream(client, "crash", kSynced, kSent);  // in flight: sent, not waited for
    // Kill while the server is taking them (messages reaches the journal after its batch).
    Client watcher = server.Connect();
    const auto deadline = std::chrono::steady_clock::now() + 10s;
    while (watcher.Stats()["messages"].get<std::size_t>() <= kSynced && std::chrono::steady_clock::now() < deadline) {
    }
    server.Kill();
  }
  Server server(work / "second", options);
  EXPECT_EQ(server.listening().value("resumed_sessions", 0), 1);
  // The journal holds the first n messages, as they were sent.
  const std::vector<std::string> journaled = ReadLines(journal / "crash.ndjson");
  ASSERT_GE(journaled.size(), 1 + kSynced);
  ASSERT_LE(journaled.size(), 1 + kSent);
  const std::size_t n = journaled.size() - 1;
  for (std::size_t i = 0; i < n; ++i) ASSERT_EQ(journaled[i + 1], WithSessionKey(Log().lines[i], "crash")) << i;
  // The resumed session is a session that got those n messages; the rest of the log ends it as the
  // whole log ends a session that never stopped.
  Client client = server.Connect();
  client.OpenSession(OpenParameters("prefix"));
  Stream(client, "prefix", 0, n);
  EXPECT_EQ(Comparable(client.GetState("crash")), Comparable(client.GetState("prefix"))) << n << " messages";
  client.OpenSession(OpenParameters("whole"));
  Stream(client, "whole", 0, kLogMessages);
  Stream(client, "crash", n, kLogMessages);
  EXPECT_EQ(Comparable(client.GetState("crash")), Comparable(client.GetState("whole")));
  EXPECT_FALSE(client.TakeError());
  EXPECT_GRACEFUL_STOP(server);
}

TEST(ClientServer, EstimatesSubscriptionIsTheReplayStreamWithTheSessionKey) {
  constexpr std::size_t kMessages = 5000;
  ScratchDir work;
  Server server(work.path());
  Client client = server.Connect();
  client.OpenSession(OpenParameters("est"));
  const Json subscribed = client.Subscribe("est", "estimates");
  EXPECT_EQ(subscribed.value("type", ""), "subscribed");
  EXPECT_EQ(subscribed.value("stream", ""), "estimates");
  Stream(client, "est", 0, kMessages);
  client.CloseSession("est");  // applies what the window holds; its reply comes after those lines
  std::vector<std::string> pushed;
  while (const std::optional<std::string> line = client.ReadPushed(0ms)) pushed.push_back(*line);
  ASSERT_GT(pushed.size(), 100u);

  std::vector<std::string> stream;
  std::size_t estimates = 0, updates = 0;
  for (const std::string& line : pushed) {
    ASSERT_TRUE(line.ends_with(R"(,"session":"est"})")) << line;
    stream.push_back(WithoutSessionKey(line, "est"));
    const Json j = Json::parse(stream.back());
    EXPECT_FALSE(j.contains("session")) << stream.back();
    const std::string type = j.value("type", "");
    if (stream.size() == 1) {
      EXPECT_EQ(type, "estimate_header");
    } else {
      EXPECT_TRUE(type == "estimate" || type == "update") << stream.back();
      (type == "estimate" ? estimates : updates) += 1;
    }
  }
  EXPECT_GT(estimates, 20u);  // every 0.1 s after the initialisation at 16.6 s
  EXPECT_GT(updates, 50u);

  // ... the bytes `rowloc replay` writes for the same log, vehicle and map.
  const fs::path replayed = work / "replay.ndjson";
  const int status = RunRowloc({"replay", Log().Write(kMessages).string(), "--vehicle",
                                (SourceDir() / "config" / "vehicles" / (std::string(kVehicle) + ".json")).string(),
                                "--map", (SourceDir() / "maps" / (std::string(kMap) + ".geojson")).string(), "-o",
                                replayed.string()},
                               work / "replay.stderr");
  ASSERT_EQ(Describe(status), "exit 0") << ReadFile(work / "replay.stdout") << ReadFile(work / "replay.stderr");
  const std::vector<std::string> expected = ReadLines(replayed);
  ASSERT_EQ(stream.size(), expected.size());
  for (std::size_t i = 0; i < stream.size(); ++i) ASSERT_EQ(stream[i], expected[i]) << "line " << i + 1;
  EXPECT_GRACEFUL_STOP(server);
}

TEST(ClientServer, ConnectsOverTcpOrAUnixSocketAndNamesWhatItCannotReach) {
  ScratchDir work;
  const fs::path socket = work / "rowloc.sock";
  ServerOptions options;
  options.extra = {"--unix-socket", socket.string()};
  Server server(work.path(), options);
  EXPECT_EQ(server.listening().value("unix", ""), socket.string());
  Client tcp = Client::Connect(server.address());
  Client local = Client::Connect("unix:" + socket.string());
  EXPECT_EQ(tcp.Hello().value("protocol", ""), "rowloc-service/1");
  EXPECT_EQ(local.Hello().value("protocol", ""), "rowloc-service/1");
  // A session is not tied to its connection.
  tcp.OpenSession(OpenParameters("shared", true));
  Stream(tcp, "shared", 0, 300);
  EXPECT_EQ(tcp.Request({{"type", "list_sessions"}})["sessions"].size(), 1u);
  const Json state = local.GetState("shared");
  EXPECT_TRUE(state.value("initialised", false));
  EXPECT_EQ(Comparable(state), Comparable(tcp.GetState("shared")));

  EXPECT_THROW(Client::Connect("127.0.0.1"), std::invalid_argument);
  EXPECT_THROW(Client::Connect("127.0.0.1:0"), std::invalid_argument);
  EXPECT_THROW(Client::Connect("127.0.0.1:http"), std::invalid_argument);
  EXPECT_GRACEFUL_STOP(server);
  try {
    Client::ConnectTcp("127.0.0.1", server.port());
    ADD_FAILURE() << "connected to a stopped server";
  } catch (const std::runtime_error& e) {
    EXPECT_NE(std::string(e.what()).find("cannot connect to 127.0.0.1:" + std::to_string(server.port())),
              std::string::npos)
        << e.what();
  }
  EXPECT_THROW(Client::Connect("unix:" + (work / "no-such.sock").string()), std::runtime_error);
}

TEST(ClientServer, SessionKeyHelpers) {
  EXPECT_EQ(WithSessionKey(R"({"type":"imu","t":0.5})", "a-1"), R"({"type":"imu","t":0.5,"session":"a-1"})");
  EXPECT_EQ(WithSessionKey("{\"type\":\"imu\"}\r\n", "a"), R"({"type":"imu","session":"a"})");
  EXPECT_THROW(WithSessionKey("[1]", "a"), std::invalid_argument);
  EXPECT_EQ(WithoutSessionKey(R"({"type":"estimate","t":1,"session":"a-1"})", "a-1"), R"({"type":"estimate","t":1})");
  EXPECT_EQ(WithoutSessionKey(R"({"type":"estimate","session":"b"})", "a"), R"({"type":"estimate","session":"b"})");
}

// ----- the session's filter (issue 29): given > the vehicle file's recommended_filter > defaults

/// DIR/vehicles and DIR/filters: copies of the shipped files, the log's vehicle recommending
/// canopy-gnss-flat.json (which extends canopy-gnss.json) instead of default.json, and a vehicle
/// "broken" whose recommended filter is missing.
ServerOptions RecommendingDirectories(const fs::path& dir) {
  ServerOptions options;
  options.vehicles_dir = dir / "vehicles";
  options.filters_dir = dir / "filters";
  fs::create_directories(dir);
  fs::copy(SourceDir() / "config" / "vehicles", options.vehicles_dir);
  fs::copy(SourceDir() / "config" / "filters", options.filters_dir);
  Json vehicle = Json::parse(ReadFile(options.vehicles_dir / (std::string(kVehicle) + ".json")));
  EXPECT_EQ(vehicle.value("recommended_filter", ""), "../filters/default.json");
  vehicle["recommended_filter"] = "../filters/canopy-gnss-flat.json";
  std::ofstream(options.vehicles_dir / (std::string(kVehicle) + ".json")) << vehicle.dump(2);
  vehicle["name"] = "broken";
  vehicle["recommended_filter"] = "../filters/absent.json";
  std::ofstream(options.vehicles_dir / "broken.json") << vehicle.dump(2);
  return options;
}

TEST(ClientServer, TheSessionsFilterIsTheGivenOneElseTheVehiclesRecommendedOneElseTheDefaults) {
  ScratchDir work;
  Server server(work / "server", RecommendingDirectories(work / "config"));
  Client client = server.Connect();
  const auto open = [&](const std::string& session, const Json& extra) {
    Json request = OpenParameters(session);
    request["type"] = "open_session";
    request.update(extra);
    return client.Request(request);
  };
  // By vehicle name: the vehicle file's recommended filter.
  Json opened = open("recommended", Json::object());
  EXPECT_EQ(opened.value("filter_source", ""), "vehicle") << opened.dump();
  EXPECT_EQ(opened.value("filter", ""), "canopy-gnss-flat") << opened.dump();
  // A filter named or inline: that one.
  opened = open("given", {{"filter", "canopy-gnss-flat"}});
  EXPECT_EQ(opened.value("filter_source", ""), "given");
  EXPECT_EQ(opened.value("filter", ""), "canopy-gnss-flat");
  opened = open("default", {{"filter", "default"}});
  EXPECT_EQ(opened.value("filter_source", ""), "given");
  // An inline vehicle has no file to resolve a recommended filter against: the defaults.
  Json inline_vehicle = Json::parse(ReadFile(SourceDir() / "config" / "vehicles" / (std::string(kVehicle) + ".json")));
  Json request = OpenParameters("inline");
  request.erase("vehicle");
  request["type"] = "open_session";
  request["vehicle_config"] = inline_vehicle;
  opened = client.Request(request);
  EXPECT_EQ(opened.value("filter_source", ""), "defaults");
  EXPECT_TRUE(opened.at("filter").is_null()) << opened.dump();

  // Each runs with its filter's values: the recommended one as the same file given, not as the defaults.
  for (const char* session : {"recommended", "given", "default", "inline"}) Stream(client, session, 0, kLogMessages);
  const std::string recommended = Comparable(client.GetState("recommended"));
  EXPECT_EQ(recommended, Comparable(client.GetState("given")));
  EXPECT_NE(recommended, Comparable(client.GetState("default")));
  EXPECT_EQ(Comparable(client.GetState("inline")), Comparable(client.GetState("default")));

  // A vehicle whose recommended filter cannot be read is refused, naming the vehicle and the key.
  try {
    open("broken-1", {{"vehicle", "broken"}});
    ADD_FAILURE() << "a vehicle with a missing recommended filter opened a session";
  } catch (const ClientError& e) {
    EXPECT_EQ(e.code(), "invalid_config");
    EXPECT_THAT(std::string(e.what()),
                ::testing::AllOf(::testing::HasSubstr("vehicle 'broken'"), ::testing::HasSubstr("recommended_filter"),
                                 ::testing::HasSubstr("absent.json: cannot open filter file")));
  }
  // ... unless a filter is given.
  EXPECT_EQ(open("broken-2", {{"vehicle", "broken"}, {"filter", "default"}}).value("filter_source", ""), "given");
  EXPECT_FALSE(client.TakeError());
  EXPECT_GRACEFUL_STOP(server);
}

TEST(ClientServer, AResumedSessionKeepsTheFilterValuesItWasOpenedWith) {
  constexpr std::size_t kBefore = 5000;
  ScratchDir work;
  ServerOptions options = RecommendingDirectories(work / "config");
  options.journal_dir = work / "journal";
  std::string uninterrupted;
  {
    Server server(work / "first", options);
    Client client = server.Connect();
    client.OpenSession(OpenParameters("whole"));
    Stream(client, "whole", 0, kLogMessages);
    uninterrupted = Comparable(client.GetState("whole"));
    client.CloseSession("whole");
    client.OpenSession(OpenParameters("crash"));
    Stream(client, "crash", 0, kBefore);
    client.GetState("crash");  // every line before it is in the journal
    server.Kill();
  }
  // The journal holds every value (also those canopy-gnss-flat.json inherits from canopy-gnss.json).
  const Json metadata = Json::parse(ReadFile(options.journal_dir / "crash.session.json"));
  EXPECT_EQ(metadata.at("filter"), "canopy-gnss-flat");
  const Json& filter = metadata.at("filter_config");
  EXPECT_FALSE(filter.contains("extends")) << filter.dump();
  EXPECT_TRUE(filter.at("gps").at("estimate_bias").get<bool>());
  EXPECT_TRUE(filter.contains("max_time_jump_s"));
  // The filter file changes while the server is down: the resumed session does not see it.
  std::ofstream(options.filters_dir / "canopy-gnss-flat.json") << R"({"name": "canopy-gnss-flat"})";
  Server server(work / "second", options);
  EXPECT_EQ(server.listening().value("resumed_sessions", 0), 1);
  Client client = server.Connect();
  Stream(client, "crash", kBefore, kLogMessages);
  EXPECT_EQ(Comparable(client.GetState("crash")), uninterrupted);
  // A new session reads the file as it is now.
  client.OpenSession(OpenParameters("new"));
  Stream(client, "new", 0, kLogMessages);
  EXPECT_NE(Comparable(client.GetState("new")), uninterrupted);
  EXPECT_FALSE(client.TakeError());
  EXPECT_GRACEFUL_STOP(server);
}

// `rowloc send` when things go wrong after the session is open (its CLI tests are in
// tests/apps/send_cli.cmake).

TEST(ClientServer, SendExitsOneWhenTheServiceGoesAwayMidStream) {
  ScratchDir work;
  Server server(work.path());
  Child send({ROWLOC_BIN, "send", Log().Write(kLogMessages).string(), "--to", server.address(), "--vehicle", kVehicle,
              "--map", kMap, "--rate", "realtime", "-o", (work / "out.ndjson").string()},
             work / "send.stderr", false, work / "send.stdout");
  // Wait until the stream runs (the session has messages), then kill -9 the server.
  Client client = server.Connect();
  const auto deadline = std::chrono::steady_clock::now() + 20s;
  while (client.Stats()["messages"].get<int>() < 50) {
    ASSERT_LT(std::chrono::steady_clock::now(), deadline) << ReadFile(work / "send.stderr");
    std::this_thread::sleep_for(20ms);
  }
  server.Kill();
  const std::optional<int> status = send.Wait(20s);
  ASSERT_TRUE(status) << "rowloc send still runs 20 s after the server died";
  const std::string stderr_text = ReadFile(work / "send.stdout") + ReadFile(work / "send.stderr");  // spdlog: stdout
  EXPECT_EQ(Describe(*status), "exit 1") << stderr_text;
  EXPECT_NE(stderr_text.find("send: the service went away after"), std::string::npos) << stderr_text;
}

TEST(ClientServer, SendRefusingItsInputLeavesNoSessionOpen) {
  ScratchDir work;
  Server server(work.path());
  // An output it cannot write: refused before a session is opened.
  int status = RunRowloc({"send", Log().Write(100).string(), "--to", server.address(), "--vehicle", kVehicle, "-o",
                          (work / "no-such-dir" / "out.ndjson").string()},
                         work / "send.stderr");
  std::string output = ReadFile(work / "send.stdout") + ReadFile(work / "send.stderr");
  EXPECT_EQ(Describe(status), "exit 2") << output;
  EXPECT_NE(output.find("no-such-dir' does not exist"), std::string::npos) << output;
  Client client = server.Connect();
  EXPECT_EQ(client.Stats()["sessions"].get<int>(), 0);
  EXPECT_TRUE(fs::is_empty(server.journal_dir())) << "a journal was created";

  // A log line that is not a JSON object: named, and the session it had opened is closed.
  const fs::path bad_log = work / "bad.ndjson";
  {
    std::ofstream out(bad_log);
    out << Log().header_line << '\n' << Log().lines[0] << '\n' << Log().lines[1] << "\n[1, 2]\n";
  }
  status = RunRowloc({"send", bad_log.string(), "--to", server.address(), "--vehicle", kVehicle, "-o",
                      (work / "out.ndjson").string()},
                     work / "send-bad.stderr");
  output = ReadFile(work / "send-bad.stdout") + ReadFile(work / "send-bad.stderr");
  EXPECT_EQ(Describe(status), "exit 2") << output;
  EXPECT_NE(output.find("bad.ndjson:4: not a JSON object line"), std::string::npos) << output;
  EXPECT_EQ(client.Stats()["sessions"].get<int>(), 0);
  EXPECT_GRACEFUL_STOP(server);
}

}  // namespace
}  // namespace rowloc::service
