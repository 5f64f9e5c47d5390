// Cost of the ranger mount fit (localization/ranger_mount_fit.hpp): the least-squares problem that
// `rowloc calibrate` solves over a whole drive and the localization session's mount check over its
// last 20 s (docs/calibration.md). The drive is the synthetic straight lane of the tests
// (tests/localization/synthetic_row_drive.hpp: two canopies, four side rangers, an echo of each
// ranger every 0.2 s, a reference off by 4-6 cm and 8 mrad), cut to its first `seconds`, with
// us_front_left written 5 cm off; the reference carries the body rates (the dead-reckoned motion
// of the session's check). Each iteration is one FitRangerMounts call with the default settings
// (three passes; the mount covariance in the last) or, for the check, the monitor's (two passes).
// The benchmark fails if the estimate is not within 5 mm of the offset.
// Run the Release build with
//   ranger_mount_fit_bench --benchmark_repetitions=5 --benchmark_report_aggregates_only=true
#include "rowloc/localization/ranger_mount_fit.hpp"
#include "rowloc/localization/ranger_mount_monitor.hpp"

#include "../tests/localization/synthetic_row_drive.hpp"

#include <benchmark/benchmark.h>

#include <cmath>

namespace {

using namespace rowloc::localization;

void BM_FitRangerMounts(benchmark::State& state, bool monitor_settings) {
  const rowloc::geometry::RowMap map = test::StraightRows();
  const RowMapRanging ranging(map, map.origin, 2.0);
  const test::SyntheticDrive full = test::Drive(ranging, test::Rangers());
  const double seconds = static_cast<double>(state.range(0));
  std::vector<ReferenceKnot> knots;
  std::vector<EchoRecord> echoes;
  for (const ReferenceKnot& k : full.reference) {
    if (k.time_s <= seconds) knots.push_back(k);
  }
  for (const EchoRecord& e : full.echoes) {
    if (e.time_s <= seconds) echoes.push_back(e);
  }
  std::vector<rowloc::mapio::SensorMount> configured = test::Rangers();
  configured[0].position_m.y() = 0.55;
  const RangerMountFitConfig config = monitor_settings ? RangerMountMonitorConfig{}.fit : RangerMountFitConfig{};
  for (auto _ : state) {
    const RangerMountFit fit = FitRangerMounts(ranging, configured, test::kCone, 4.0, knots, echoes, config);
    if (std::abs(fit.rangers[0].along_beam_m + 0.05) > 0.005) {
      state.SkipWithError("the fit missed the 5 cm offset");
      break;
    }
    benchmark::DoNotOptimize(fit);
  }
  state.counters["knots"] = static_cast<double>(knots.size());
  state.counters["echoes"] = static_cast<double>(echoes.size());
}

}  // namespace

BENCHMARK_CAPTURE(BM_FitRangerMounts, calibrate, false)->Arg(20)->Arg(90)->Unit(benchmark::kMillisecond);
BENCHMARK_CAPTURE(BM_FitRangerMounts, check, true)->Arg(20)->Unit(benchmark::kMillisecond);
