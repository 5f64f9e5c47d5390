// Speed of the localization service (issue 25 §7; docs/service.md), end to end over loopback TCP:
// JSON parsing, the filter (GNSS, IMU, wheels, steering and four ultrasonic rangers against the row
// map) and the journal included. The messages are those of the simulated vineyard-002-4us drive
// (the first kLogSeconds of it), every session starting at the true initial pose so that the filter
// runs from the first message.
//
//   BM_ReplaySession          the same messages through rowloc replay's path in one thread
//                             (line parsing, LocalizationSession, estimate writer): the baseline of
//                             the service's overhead.
//   BM_ServiceThroughput/S/T  S sessions over min(S, 4) connections, the server on T threads, every
//                             message sent as fast as the service takes it (TCP backpressure), then
//                             one get_state per connection (its reply comes after all its lines were
//                             applied); items/s = sensor messages per second.
//   BM_ServiceLatency100      100 vehicles, each on its own connection, paced in real time (100 Hz
//                             IMU, wheels and steering, GNSS and 4 rangers at 10 Hz each): every
//                             10 ms each vehicle sends its messages of those 10 ms and a get_state
//                             (vehicles out of phase: four groups a quarter tick apart); p50/p99/max
//                             of the time from its send to its state reply (counters, us).
// The client runs in this process on the same 2-core machine, so throughput is shared with it.
//   service_bench --benchmark_repetitions=3 --benchmark_report_aggregates_only=true
#include "rowloc/formats/estimate_stream_writer.hpp"
#include "rowloc/formats/sensor_log_reader.hpp"
#include "rowloc/formats/trajectory_streams.hpp"
#include "rowloc/localization/localization_session.hpp"
#include "rowloc/mapio/row_map_geojson.hpp"
#include "rowloc/service/client.hpp"
#include "rowloc/service/dispatcher.hpp"
#include "rowloc/service/server.hpp"
#include "rowloc/sim/row_world.hpp"
#include "rowloc/sim/scenario.hpp"
#include "rowloc/sim/simulation.hpp"

#include <benchmark/benchmark.h>
#include <spdlog/spdlog.h>

#include <algorithm>
#include <chrono>
#include <filesystem>
#include <sstream>
#include <thread>

namespace {

namespace fs = std::filesystem;
using nlohmann::json;
using rowloc::service::Client;

constexpr double kLogSeconds = 10.0;

struct BenchData {
  std::string header_line;
  std::vector<std::string> lines;  ///< messages with t < kLogSeconds
  std::vector<double> times;
  json initial_pose;
  fs::path work;
};

const BenchData& Data() {
  static const BenchData data = [] {
    spdlog::set_level(spdlog::level::warn);  // the service logs every session it opens and closes
    BenchData d;
    const fs::path source(ROWLOC_SOURCE_DIR);
    const rowloc::sim::Scenario scenario =
        rowloc::sim::LoadScenario(source / "config/scenarios/vineyard-002-4us.json");
    std::ostringstream sensors, truth;
    rowloc::sim::RunSimulation(scenario, {&sensors, &truth, nullptr, nullptr});
    std::istringstream in(sensors.str());
    std::getline(in, d.header_line);
    for (std::string line; std::getline(in, line);) {
      const double t = json::parse(line)["t"].get<double>();
      if (t >= kLogSeconds) break;
      d.lines.push_back(line);
      d.times.push_back(t);
    }
    std::istringstream truth_in(truth.str());
    const rowloc::formats::TruthStream stream = rowloc::formats::ParseTruthStream(truth_in, "truth");
    const auto& first = stream.samples.front();
    d.initial_pose = {{"t", first.t_s}, {"x_m", first.position_m.x()}, {"y_m", first.position_m.y()},
                      {"phi_rad", first.phi_rad}, {"sigma_xy_m", 0.05}, {"sigma_phi_rad", 0.02}};
    d.work = fs::temp_directory_path() / ("rowloc-service-bench-" + std::to_string(::getpid()));
    fs::create_directories(d.work / "maps");
    const rowloc::sim::RowWorld world(*scenario.world);
    rowloc::mapio::WriteRowMapGeoJson(world.TrueRowMap(scenario.row_map_height_m, world.StepForTolerance(1e-3)),
                                      d.work / "maps/bench.geojson");
    return d;
  }();
  return data;
}

void BM_ReplaySession(benchmark::State& state) {
  const BenchData& d = Data();
  const rowloc::formats::LogHeader header = rowloc::formats::ParseLogHeader(d.header_line, "bench");
  const rowloc::mapio::VehicleConfig vehicle =
      rowloc::mapio::LoadVehicleConfig(fs::path(ROWLOC_SOURCE_DIR) / "config/vehicles/vineyard-ugv-4ws.json");
  const rowloc::geometry::RowMap map = rowloc::mapio::ReadRowMapGeoJson(d.work / "maps/bench.geojson");
  for (auto _ : state) {
    rowloc::localization::LocalizationSession session(vehicle, {}, header);
    session.AttachRowMap(map);
    const json& p = d.initial_pose;
    session.SetPose(p["t"].get<double>(),
                    Eigen::Vector3d(p["x_m"].get<double>(), p["y_m"].get<double>(), p["phi_rad"].get<double>()),
                    Eigen::Vector3d(0.0025, 0.0025, 0.0004).asDiagonal().toDenseMatrix());
    std::ostringstream out;
    rowloc::formats::EstimateLogWriter writer(out, "bench", vehicle.name, header.origin);
    std::size_t line_number = 1;
    for (const std::string& line : d.lines) {
      const auto step = session.Process(rowloc::formats::ParseSensorMessage(line, header, "bench", ++line_number));
      for (const auto& update : step.updates) writer.WriteUpdate(update);
      if (step.estimate) writer.Write(*step.estimate);
    }
    benchmark::DoNotOptimize(out.str().size());
  }
  state.SetItemsProcessed(static_cast<std::int64_t>(state.iterations() * d.lines.size()));
}
BENCHMARK(BM_ReplaySession)->Unit(benchmark::kMillisecond);

/// A server on a free loopback port in this process, with the bench's map and a journal.
class InProcessServer {
 public:
  explicit InProcessServer(int threads) {
    const BenchData& d = Data();
    rowloc::service::ServiceSettings s;
    const fs::path source(ROWLOC_SOURCE_DIR);
    s.port = 0;
    s.threads = threads;
    s.vehicles_dir = source / "config/vehicles";
    s.filters_dir = source / "config/filters";
    s.maps_dir = d.work / "maps";
    s.journal_dir = d.work / ("journal-" + std::to_string(++instances_));
    s.max_queue_lines = 1 << 16;
    dispatcher_ = std::make_unique<rowloc::service::Dispatcher>(s);
    server_ = std::make_unique<rowloc::service::Server>(*dispatcher_);
    server_->Listen();
    thread_ = std::thread([this] { server_->Run(false); });
    const std::string endpoint = server_->tcp_endpoint();
    port_ = static_cast<unsigned short>(std::stoi(endpoint.substr(endpoint.rfind(':') + 1)));
  }
  ~InProcessServer() {
    server_->Stop();
    thread_.join();
    fs::remove_all(dispatcher_->settings().journal_dir);
  }
  unsigned short port() const { return port_; }
  rowloc::service::Dispatcher& dispatcher() { return *dispatcher_; }

 private:
  static inline int instances_ = 0;
  std::unique_ptr<rowloc::service::Dispatcher> dispatcher_;
  std::unique_ptr<rowloc::service::Server> server_;
  std::thread thread_;
  unsigned short port_ = 0;
};

/// Opens the sessions of one connection; returns their names.
std::vector<std::string> OpenSessions(Client& client, int first, int count, const std::string& prefix) {
  const BenchData& d = Data();
  std::vector<std::string> names;
  for (int i = first; i < first + count; ++i) {
    names.push_back(prefix + std::to_string(i));
    client.OpenSession({{"session", names.back()}, {"vehicle", "vineyard-ugv-4ws"}, {"map", "bench"},
                        {"header", json::parse(d.header_line)}, {"initial_pose", d.initial_pose}});
  }
  return names;
}

/// The lines of messages [begin, end) for every session, interleaved in time, as one chunk of
/// newline-separated lines (without the last newline: SendLine adds it).
std::string Chunk(const std::vector<std::string>& sessions, std::size_t begin, std::size_t end) {
  const BenchData& d = Data();
  std::string chunk;
  for (std::size_t i = begin; i < end; ++i) {
    for (const std::string& session : sessions) {
      chunk += rowloc::service::WithSessionKey(d.lines[i], session);
      chunk += '\n';
    }
  }
  if (!chunk.empty()) chunk.pop_back();
  return chunk;
}

void BM_ServiceThroughput(benchmark::State& state) {
  const BenchData& d = Data();
  const int sessions = static_cast<int>(state.range(0));
  const int connections = std::min(sessions, 4);
  InProcessServer server(static_cast<int>(state.range(1)));
  std::vector<Client> clients;
  for (int c = 0; c < connections; ++c) clients.push_back(Client::ConnectTcp("127.0.0.1", server.port()));
  int round = 0;
  for (auto _ : state) {
    std::vector<std::vector<std::string>> names(connections);
    std::vector<std::vector<std::string>> chunks(connections);
    for (int c = 0; c < connections; ++c) {
      const int first = c * sessions / connections, last = (c + 1) * sessions / connections;
      names[c] = OpenSessions(clients[c], first, last - first, std::string("r").append(std::to_string(round)) + "-");
      for (std::size_t i = 0; i < d.lines.size(); i += 200) {
        chunks[c].push_back(Chunk(names[c], i, std::min(i + 200, d.lines.size())));
      }
    }
    const auto start = std::chrono::steady_clock::now();
    std::vector<std::thread> senders;
    for (int c = 0; c < connections; ++c) {
      senders.emplace_back([&, c] {
        for (const std::string& chunk : chunks[c]) clients[c].SendLine(chunk);
        clients[c].GetState(names[c].back());
      });
    }
    for (std::thread& t : senders) t.join();
    state.SetIterationTime(std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count());
    for (int c = 0; c < connections; ++c) {
      for (const std::string& name : names[c]) clients[c].CloseSession(name);
      if (const auto error = clients[c].TakeError()) state.SkipWithError(error->dump().c_str());
    }
    ++round;
  }
  state.SetItemsProcessed(static_cast<std::int64_t>(state.iterations() * d.lines.size() * sessions));
  state.counters["sessions"] = sessions;
  state.counters["server_threads"] = static_cast<double>(state.range(1));
}
BENCHMARK(BM_ServiceThroughput)
    ->Args({1, 1})->Args({1, 2})->Args({100, 1})->Args({100, 2})
    ->UseManualTime()->Unit(benchmark::kMillisecond)->Iterations(2);

void BM_ServiceLatency100(benchmark::State& state) {
  const BenchData& d = Data();
  constexpr int kSessions = 100, kThreads = 4;
  constexpr double kTickS = 0.01;
  InProcessServer server(2);
  std::vector<Client> clients;  // one connection per vehicle, as robots connect
  std::vector<std::string> names;
  for (int i = 0; i < kSessions; ++i) {
    clients.push_back(Client::ConnectTcp("127.0.0.1", server.port()));
    names.push_back(OpenSessions(clients.back(), i, 1, "l").front());
  }
  const std::size_t ticks = static_cast<std::size_t>(d.times.back() / kTickS);
  std::vector<std::vector<double>> latencies_us(kThreads);
  for (auto _ : state) {
    const auto start = std::chrono::steady_clock::now();
    std::vector<std::thread> senders;
    for (int thread = 0; thread < kThreads; ++thread) {
      senders.emplace_back([&, thread] {
        // The vehicles of this thread: each sends its last 10 ms of messages and asks for its
        // state; vehicles are not in phase (thread k starts k quarter ticks later).
        std::vector<std::size_t> next(kSessions, 0);
        const auto phase = std::chrono::duration<double>(thread * kTickS / kThreads);
        for (std::size_t tick = 0; tick < ticks; ++tick) {
          std::this_thread::sleep_until(start + phase + std::chrono::duration<double>(tick * kTickS));
          for (int v = thread; v < kSessions; v += kThreads) {
            std::size_t end = next[v];
            while (end < d.lines.size() && d.times[end] < (tick + 1) * kTickS) ++end;
            const std::string chunk = Chunk({names[v]}, next[v], end);
            next[v] = end;
            const auto sent = std::chrono::steady_clock::now();
            if (!chunk.empty()) clients[v].SendLine(chunk);
            clients[v].GetState(names[v]);
            latencies_us[thread].push_back(
                std::chrono::duration<double, std::micro>(std::chrono::steady_clock::now() - sent).count());
          }
        }
      });
    }
    for (std::thread& t : senders) t.join();
  }
  std::vector<double> all;
  for (const auto& l : latencies_us) all.insert(all.end(), l.begin(), l.end());
  std::sort(all.begin(), all.end());
  const auto quantile = [&](double q) {
    return all[std::min(all.size() - 1, static_cast<std::size_t>(q * static_cast<double>(all.size())))];
  };
  state.counters["p50_us"] = quantile(0.5);
  state.counters["p90_us"] = quantile(0.9);
  state.counters["p99_us"] = quantile(0.99);
  state.counters["max_us"] = all.back();
  state.counters["samples"] = static_cast<double>(all.size());
  state.counters["msgs_per_s"] = static_cast<double>(d.lines.size() * kSessions) / (static_cast<double>(ticks) * kTickS);
  const json stats = clients[0].Stats();
  state.counters["server_line_p99_us"] = stats["latency_us"]["p99"].get<double>();
}
BENCHMARK(BM_ServiceLatency100)->Iterations(1)->Unit(benchmark::kMillisecond)->UseRealTime();

}  // namespace
