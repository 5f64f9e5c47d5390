// Simulator throughput (issue 3: "a 10-minute four-sensor vineyard run simulates at >= 100x real
// time on one core"). Runs config/scenarios/vineyard-002-4us.json (600.2 s of driving, four
// ultrasonic rangers, GNSS, IMU, wheel and steering encoders, truth at 50 Hz and both baselines)
// into memory streams. Counter real_time_factor = simulated seconds / wall seconds.
#include "rowloc/sim/simulation.hpp"

#include <benchmark/benchmark.h>

#include <filesystem>
#include <sstream>
#include <string>

namespace {

const rowloc::sim::Scenario& Vineyard(const std::string& name) {
  static const rowloc::sim::Scenario smooth =
      rowloc::sim::LoadScenario(std::filesystem::path(ROWLOC_SOURCE_DIR) / "config/scenarios/vineyard-002-4us.json");
  static const rowloc::sim::Scenario rough = rowloc::sim::LoadScenario(
      std::filesystem::path(ROWLOC_SOURCE_DIR) / "config/scenarios/vineyard-002-rough-4us.json");
  return name == "rough" ? rough : smooth;
}

void Run(benchmark::State& state, const rowloc::sim::Scenario& scenario) {
  double simulated_s = 0.0;
  std::size_t bytes = 0;
  for (auto _ : state) {
    std::ostringstream sensors, truth, gnss, odometry;
    const rowloc::sim::SimulationSummary summary =
        rowloc::sim::RunSimulation(scenario, {&sensors, &truth, &gnss, &odometry});
    simulated_s += summary.duration_s;
    bytes += sensors.str().size() + truth.str().size();
    benchmark::DoNotOptimize(summary);
  }
  state.counters["real_time_factor"] = benchmark::Counter(simulated_s, benchmark::Counter::kIsRate);
  state.counters["bytes_per_run"] = static_cast<double>(bytes) / static_cast<double>(state.iterations());
}

void BM_Vineyard4UsTenMinutes(benchmark::State& state) { Run(state, Vineyard("smooth")); }
void BM_VineyardRough4UsTenMinutes(benchmark::State& state) { Run(state, Vineyard("rough")); }

BENCHMARK(BM_Vineyard4UsTenMinutes)->Unit(benchmark::kMillisecond)->UseRealTime();
BENCHMARK(BM_VineyardRough4UsTenMinutes)->Unit(benchmark::kMillisecond)->UseRealTime();

}  // namespace
