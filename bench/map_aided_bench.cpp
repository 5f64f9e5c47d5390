// Cost of the map-aided ultrasonic update (issue 5): "a 4-sensor map-aided update on a 10^5-segment
// map <= 5 us median". One 4-sensor update = one echo of each of the four sensors of the vineyard UGV
// (config/vehicles/vineyard-ugv-4ws.json), 0.0025 s apart, through VehicleEkf::Process: per echo a
// prediction to its time stamp, the candidate segments (an R-tree cone cast of every segment in the
// sound cone), the choice of one by range NIS and the update of config.map_aided.method.
// Map: the vineyard of segment_index_bench (MakeSampleRowMap, 495 slightly bowed rows 2.5 m apart,
// closed canopy outlines of 1 m segments: 99 990 segments), in the filter's frame. The vehicle stands
// in a lane, along the row; the echoes are the ranges of the true pose's cone casts (the echo model)
// plus N(0, range_sigma) noise. The filter (config/filters/default.json, the method changed) starts
// from the true pose plus an error drawn from the SetPose covariance (5 cm, 1.1 deg). Every 100
// updates (1 s) the filter is reset outside the timing to a fresh one in the next of 64 lanes (so
// the covariance does not drift, and not every update hits the same part of the R-tree). A setup
// pass over all 64 lanes checks the updates: the benchmark fails if an echo finds no segment or no
// usable geometry, a state becomes non-finite, a lane sees no accepted update or over 1 % of the
// echoes are gated out. Counters: per_echo (time / 4), the shares of the echoes that updated the
// filter, were gated out, had two candidate rows, or (cut methods) whose slab held the whole
// ellipse (no_info) or missed it (contra), and the share of the R-tree box queries answered from
// the filter's query cache (cache_hit; standing still, only the first queries after a reset miss);
// states = the filter's state dimension.
// BM_MapAidedUpdate4SensorsOneStamp/range: the same with the four echoes at one time stamp (one
// prediction per update instead of four), to tell the predictions from the rest.
// BM_MapAidedUpdate4SensorsDriving/range: the vehicle drives along its lane instead, 10 cm between
// two echoes of one sensor (as at 1 m/s with 10 Hz sensors), 10 m per block; the filter learns the
// speed from a wheels message at each reset (RunUpdates), so its cone casts move with the truth and
// the cache misses as it would in a run.
// BM_RowMapRangingCandidates: RowMapRanging::Candidates alone, one sensor (us_front_left), from 4096
// filter poses in random lanes, with the window the filter uses at the SetPose covariance.
// BM_RowMapRangingConstruction: loading that map into the filter (VehicleEkf::AttachRowMap's work):
// the R-tree, the smoothed row directions and the lane clearances (two ray casts per segment).
// Run the Release build with
//   map_aided_bench --benchmark_repetitions=5 --benchmark_report_aggregates_only=true
#include "rowloc/formats/sensor_messages.hpp"
#include "rowloc/geometry/row_map.hpp"
#include "rowloc/geometry/segment_index.hpp"
#include "rowloc/localization/filter_config.hpp"
#include "rowloc/localization/map_aided_ranging.hpp"
#include "rowloc/localization/vehicle_ekf.hpp"
#include "rowloc/mapio/vehicle_config.hpp"

#include <Eigen/Geometry>
#include <benchmark/benchmark.h>

#include <algorithm>
#include <cmath>
#include <cstddef>
#include <filesystem>
#include <numbers>
#include <optional>
#include <random>
#include <stdexcept>
#include <string>
#include <variant>
#include <vector>

namespace {

namespace geo = rowloc::geometry;
namespace formats = rowloc::formats;
namespace loc = rowloc::localization;
using rowloc::mapio::VehicleConfig;

constexpr double kMessageStepS = 0.0025;  // between two echoes
// The driving variant: 10 cm between two echoes of one sensor, as at 1 m/s and 10 Hz, with the echo
// stream's step below max_prediction_step_s (0.02 s; a 0.02 s step rounds to two predictions).
constexpr double kDrivingStepS = 0.0125;
constexpr double kDrivingSpeedMps = 2.0;
constexpr int kUpdatesPerBlock = 100;     // 4-sensor updates between two resets of the filter
constexpr std::size_t kBlocks = 64;       // lanes visited in turn
constexpr std::size_t kPoses = 4096;      // poses of the candidates benchmark
const Eigen::Vector3d kPoseSigma(0.05, 0.05, 0.02);  // m, m, rad: the SetPose covariance

// 495 rows x 202 segments = 99 990 segments (segment_index_bench's vineyard).
geo::SampleRowMapParams MapParams() {
  geo::SampleRowMapParams params;
  params.row_count = 495;
  params.row_length_m = 100.0;
  params.vertex_spacing_m = 1.0;
  return params;
}

VehicleConfig Vehicle() {
  return rowloc::mapio::LoadVehicleConfig(std::filesystem::path(ROWLOC_SOURCE_DIR) / "config/vehicles/vineyard-ugv-4ws.json");
}

loc::FilterConfig Config(loc::MapAidedMethod method) {
  loc::FilterConfig config = loc::LoadFilterConfig(std::filesystem::path(ROWLOC_SOURCE_DIR) / "config/filters/default.json");
  config.map_aided.method = method;
  return config;
}

std::vector<std::string> WheelNames(const VehicleConfig& v) {
  std::vector<std::string> names;
  for (const auto& w : v.wheels) names.push_back(w.name);
  return names;
}

std::vector<loc::RangeSensorMount> Mounts(const VehicleConfig& v, const loc::FilterConfig& config) {
  std::vector<loc::RangeSensorMount> mounts;
  for (const auto& s : v.ultrasonic) {
    mounts.push_back({s.position_m.head<2>(), s.yaw_rad, config.map_aided.cone_half_angle_rad});
  }
  return mounts;
}

/// The pose on the centre line of lane `corridor` at arc parameter u along the (bowed) rows, facing
/// along the rows (or against them: backwards).
Eigen::Vector3d LanePoseAt(const geo::SampleRowMapParams& params, int corridor, double u, bool backwards) {
  const Eigen::Vector2d t(std::cos(params.heading_rad), std::sin(params.heading_rad));
  const Eigen::Vector2d n(-t.y(), t.x());
  const double xi = 2.0 * u / params.row_length_m - 1.0;
  const double offset = (corridor + 0.5) * params.row_spacing_m + params.bow_m * (1.0 - xi * xi);
  const double slope = -4.0 * params.bow_m * xi / params.row_length_m;  // d offset / du
  const Eigen::Vector2d p = u * t + offset * n;
  return {p.x(), p.y(), params.heading_rad + std::atan(slope) + (backwards ? std::numbers::pi : 0.0)};
}

/// A pose in the middle of a random lane, along the (bowed) row, forwards or backwards.
Eigen::Vector3d LanePose(const geo::SampleRowMapParams& params, std::mt19937_64& rng) {
  std::uniform_real_distribution<double> along(5.0, params.row_length_m - 5.0);
  std::uniform_int_distribution<int> corridor(0, params.row_count - 2);
  std::bernoulli_distribution backwards(0.5);
  const double u = along(rng);
  const int lane = corridor(rng);
  return LanePoseAt(params, lane, u, backwards(rng));
}

Eigen::Vector3d Perturbed(const Eigen::Vector3d& pose, std::mt19937_64& rng) {
  std::normal_distribution<double> n01;
  return pose + Eigen::Vector3d(kPoseSigma.x() * n01(rng), kPoseSigma.y() * n01(rng), kPoseSigma.z() * n01(rng));
}

/// The map, its index in the filter's frame (the same as the map's) and the benchmark's lanes.
struct World {
  geo::SampleRowMapParams params = MapParams();
  geo::RowMap map = geo::MakeSampleRowMap(params);
  VehicleConfig vehicle = Vehicle();
  loc::FilterConfig config = Config(loc::MapAidedMethod::kRange);
  std::vector<loc::RangeSensorMount> mounts = Mounts(vehicle, config);
  loc::RowMapRanging ranging = loc::RowMapRanging(map, map.origin, config.map_aided.row_smoothing_m);

  struct Block {
    Eigen::Vector3d start;                      ///< the filter's pose at the reset
    std::vector<formats::SensorMessage> messages;   ///< kUpdatesPerBlock x 4 echoes, from t = kMessageStepS
  };
  std::vector<Block> blocks;
  /// The same number of blocks for the driving variant: the truth drives along its lane at
  /// kDrivingSpeedMps, the four sensors echo in turn kDrivingStepS apart (10 m per block).
  std::vector<Block> driving_blocks;

  World() {
    std::mt19937_64 rng(5);
    std::normal_distribution<double> n01;
    for (std::size_t b = 0; b < kBlocks; ++b) {
      const Eigen::Vector3d truth = LanePose(params, rng);
      const std::vector<double> ranges = TrueRanges(truth);
      Block block{Perturbed(truth, rng), {}};
      for (int k = 0; k < kUpdatesPerBlock; ++k) {
        for (std::size_t s = 0; s < mounts.size(); ++s) {
          const double t = kMessageStepS * static_cast<double>(4 * k + static_cast<int>(s) + 1);
          const double range = ranges[s] + config.map_aided.range_sigma_m * n01(rng);
          block.messages.push_back(formats::UltrasonicMessage{t, vehicle.ultrasonic[s].name, s, range});
        }
      }
      blocks.push_back(std::move(block));
    }
    AddDrivingBlocks();
  }
  void AddDrivingBlocks() {
    std::mt19937_64 rng(7);
    std::normal_distribution<double> n01;
    std::uniform_int_distribution<int> corridor(0, params.row_count - 2);
    std::bernoulli_distribution backwards(0.5);
    const double drive_m = kDrivingSpeedMps * kDrivingStepS * 4.0 * kUpdatesPerBlock;
    for (std::size_t b = 0; b < kBlocks; ++b) {
      const int lane = corridor(rng);
      const bool back = backwards(rng);  // facing -u: the vehicle drives forwards, u decreases
      std::uniform_real_distribution<double> start(back ? 5.0 + drive_m : 5.0,
                                                   params.row_length_m - 5.0 - (back ? 0.0 : drive_m));
      const double u0 = start(rng);
      const double direction = back ? -1.0 : 1.0;
      Block block{Perturbed(LanePoseAt(params, lane, u0, back), rng), {}};
      for (int k = 0; k < kUpdatesPerBlock; ++k) {
        for (std::size_t s = 0; s < mounts.size(); ++s) {
          const double t = kDrivingStepS * static_cast<double>(4 * k + static_cast<int>(s) + 1);
          const Eigen::Vector3d truth = LanePoseAt(params, lane, u0 + direction * kDrivingSpeedMps * t, back);
          const double range = TrueRanges(truth)[s] + config.map_aided.range_sigma_m * n01(rng);
          block.messages.push_back(formats::UltrasonicMessage{t, vehicle.ultrasonic[s].name, s, range});
        }
      }
      driving_blocks.push_back(std::move(block));
    }
  }
  /// The echo of each sensor at `pose`: the nearest point of the outlines in its cone.
  std::vector<double> TrueRanges(const Eigen::Vector3d& pose) const {
    std::vector<double> ranges;
    const Eigen::Rotation2Dd rotation(pose.z());
    for (const loc::RangeSensorMount& m : mounts) {
      const double beam = pose.z() + m.beam_angle_rad;
      const geo::Cone2 cone{pose.head<2>() + rotation * m.lever_arm_m, Eigen::Vector2d(std::cos(beam), std::sin(beam)),
                            m.cone_half_angle_rad, config.map_aided.max_range_m};
      const auto hit = ranging.index().ConeCast(cone);
      if (!hit) throw std::logic_error("map_aided_bench: a sensor sees no row from its lane");
      ranges.push_back(hit->hit.range_m);
    }
    return ranges;
  }
};

const World& TheWorld() {
  static const World w;
  return w;
}

Eigen::Matrix3d PoseCovariance() { return kPoseSigma.cwiseAbs2().asDiagonal(); }

struct Tally {
  long updates = 0, accepted = 0;
  loc::MapAidedStats stats;
  std::size_t cache_hits = 0, cache_queries = 0;  ///< the filter's R-tree query cache
  void Add(const loc::VehicleEkf& ekf) {
    const geo::SegmentQueryCache& cache = ekf.row_search_cache();  // a reset copies the empty one of `base`
    cache_hits += cache.hits();
    cache_queries += cache.hits() + cache.misses();
    Add(ekf.map_aided_stats());
  }
  void Add(const loc::MapAidedStats& s) {
    stats.echoes += s.echoes;
    stats.no_segment += s.no_segment;
    stats.ambiguous += s.ambiguous;
    stats.contradicting += s.contradicting;
    stats.uninformative += s.uninformative;
    stats.degenerate += s.degenerate;
  }
};

/// Processes the four echoes of update k of the block; adds the filter updates made to `tally`.
inline void FourEchoes(loc::VehicleEkf& ekf, const World::Block& block, int k, Tally& tally) {
  for (std::size_t s = 0; s < 4; ++s) {
    const loc::ProcessResult result = ekf.Process(block.messages[4 * static_cast<std::size_t>(k) + s]);
    for (const loc::UpdateRecord& u : result.updates) {
      ++tally.updates;
      tally.accepted += u.outcome.accepted ? 1 : 0;
    }
    benchmark::DoNotOptimize(result);
  }
}

/// kStanding: the echoes of a vehicle standing in its lane, kMessageStepS apart (four predictions
/// per update); kOneStamp: the same with the four echoes of an update at one time stamp (one
/// prediction per update, of 4 kMessageStepS); kDriving: World::driving_blocks. There the filter
/// learns the speed from one wheels message at each reset (outside the timing) and keeps it over
/// the block: its velocity starts with sigma 5 m/s (so that message is not gated out), its
/// acceleration states at 1 mm/s^2 with a jerk noise of 1 mm/s^3/sqrt(Hz) (default: 0.3, 0.5 and
/// 2), since the benchmark feeds no IMU or odometry between the echoes. The same operations run
/// whatever these values.
enum class Variant { kStanding, kOneStamp, kDriving };

void RunUpdates(benchmark::State& state, loc::MapAidedMethod method, Variant variant) {
  const World& w = TheWorld();
  std::vector<World::Block> blocks = variant == Variant::kDriving ? w.driving_blocks : w.blocks;
  if (variant == Variant::kOneStamp) {
    for (World::Block& block : blocks) {
      for (std::size_t i = 0; i < block.messages.size(); ++i) {
        std::get<formats::UltrasonicMessage>(block.messages[i]).time_s =
            4.0 * kMessageStepS * static_cast<double>(i / 4 + 1);
      }
    }
  }
  if (w.vehicle.ultrasonic.size() != 4) {
    state.SkipWithError("the vehicle does not have 4 ultrasonic sensors");
    return;
  }
  loc::FilterConfig config = Config(method);
  if (variant == Variant::kDriving) {
    config.initialisation.velocity_sigma_mps = 5.0;  // the reset's wheels message is not gated out
    config.initialisation.acceleration_sigma_mps2 = 0.001;
    config.process_noise.jerk_mps3_per_sqrt_hz = 0.001;
  }
  loc::VehicleEkf base(w.vehicle, config, w.map.origin, WheelNames(w.vehicle));
  base.AttachRowMap(w.map);
  base.SetPose(0.0, blocks[0].start, PoseCovariance());
  std::vector<double> wheel_speeds;
  for (const auto& wheel : w.vehicle.wheels) wheel_speeds.push_back(kDrivingSpeedMps / wheel.nominal_radius_m);
  const auto reset = [&](loc::VehicleEkf& ekf, std::size_t b) {
    ekf = base;
    ekf.SetPose(0.0, blocks[b].start, PoseCovariance());
    if (variant == Variant::kDriving) {
      ekf.Process(formats::WheelsMessage{0.0, wheel_speeds, std::nullopt, std::nullopt});
    }
  };

  // Setup check: one pass over every block, untimed. Every echo must find its row, no state may
  // become non-finite, every lane must see updates (the cut methods then stop updating when the slab
  // holds the whole ellipse: "no_info") and gating must stay at the level of the gate probability.
  Tally check;
  loc::VehicleEkf ekf = base;
  for (std::size_t b = 0; b < kBlocks; ++b) {
    reset(ekf, b);
    const long accepted_before = check.accepted;
    for (int k = 0; k < kUpdatesPerBlock; ++k) FourEchoes(ekf, blocks[b], k, check);
    check.Add(ekf);
    if (!ekf.state().allFinite() || !ekf.covariance().allFinite() || check.accepted == accepted_before) {
      state.SkipWithError(("lane " + std::to_string(b) + ": state not finite or no echo accepted").c_str());
      return;
    }
  }
  const loc::MapAidedStats& s = check.stats;
  if (s.no_segment != 0 || s.degenerate != 0 || check.updates - check.accepted > static_cast<long>(s.echoes) / 100) {
    state.SkipWithError(("of " + std::to_string(s.echoes) + " echoes, " + std::to_string(s.no_segment) +
                         " found no segment, " + std::to_string(s.degenerate) + " were degenerate, " +
                         std::to_string(check.updates - check.accepted) + " were gated out")
                            .c_str());
    return;
  }

  Tally tally;
  std::size_t b = 0;
  int k = 0;
  reset(ekf, b);
  for (auto _ : state) {
    if (k == kUpdatesPerBlock) {
      state.PauseTiming();
      tally.Add(ekf);
      b = (b + 1) % kBlocks;
      reset(ekf, b);
      k = 0;
      state.ResumeTiming();
    }
    FourEchoes(ekf, blocks[b], k++, tally);
  }
  tally.Add(ekf);
  benchmark::DoNotOptimize(ekf.state().data());

  const double echoes = static_cast<double>(tally.stats.echoes);
  state.SetItemsProcessed(state.iterations());  // items = 4-sensor updates
  state.counters["states"] = static_cast<double>(ekf.layout().size);
  state.counters["per_echo"] =
      benchmark::Counter(4.0 * static_cast<double>(state.iterations()), benchmark::Counter::kIsRate | benchmark::Counter::kInvert);
  state.counters["updated"] = static_cast<double>(tally.accepted) / echoes;  // share of echoes that updated x
  state.counters["gated"] = static_cast<double>(tally.updates - tally.accepted) / echoes;
  state.counters["ambiguous"] = static_cast<double>(tally.stats.ambiguous) / echoes;
  state.counters["no_info"] = static_cast<double>(tally.stats.uninformative) / echoes;   // cut methods
  state.counters["contra"] = static_cast<double>(tally.stats.contradicting) / echoes;  // cut methods
  const double queries = static_cast<double>(std::max<std::size_t>(tally.cache_queries, 1));
  state.counters["cache_hit"] = static_cast<double>(tally.cache_hits) / queries;
}

void BM_MapAidedUpdate4Sensors(benchmark::State& state, loc::MapAidedMethod method) {
  RunUpdates(state, method, Variant::kStanding);
}
void BM_MapAidedUpdate4SensorsOneStamp(benchmark::State& state, loc::MapAidedMethod method) {
  RunUpdates(state, method, Variant::kOneStamp);
}
void BM_MapAidedUpdate4SensorsDriving(benchmark::State& state, loc::MapAidedMethod method) {
  RunUpdates(state, method, Variant::kDriving);
}

void BM_RowMapRangingCandidates(benchmark::State& state) {
  const World& w = TheWorld();
  const loc::RangeSensorMount& mount = w.mounts[0];  // us_front_left
  const loc::MapAidedConfig& c = w.config.map_aided;
  const double window_m = c.k_sigma * (std::sqrt(PoseCovariance().topLeftCorner<2, 2>().trace()) + c.range_sigma_m);
  std::mt19937_64 rng(6);
  std::vector<Eigen::Vector3d> poses;
  for (std::size_t i = 0; i < kPoses; ++i) poses.push_back(Perturbed(LanePose(w.params, rng), rng));
  std::size_t i = 0, found = 0, candidates = 0;
  for (auto _ : state) {
    const std::vector<loc::EchoCandidate> result = w.ranging.Candidates(poses[i++ % kPoses], mount, c.max_range_m, window_m);
    found += result.empty() ? 0 : 1;
    candidates += result.size();
    benchmark::DoNotOptimize(result.data());
  }
  const double calls = static_cast<double>(std::max<std::size_t>(i, 1));
  state.counters["hit_rate"] = static_cast<double>(found) / calls;
  state.counters["candidates"] = static_cast<double>(candidates) / calls;
  state.counters["segments"] = static_cast<double>(w.map.SegmentCount());
}

void BM_RowMapRangingConstruction(benchmark::State& state) {
  const World& w = TheWorld();
  for (auto _ : state) {
    const loc::RowMapRanging ranging(w.map, w.map.origin, w.config.map_aided.row_smoothing_m);
    benchmark::DoNotOptimize(&ranging);
  }
  state.counters["segments"] = static_cast<double>(w.map.SegmentCount());
}

}  // namespace

BENCHMARK_CAPTURE(BM_MapAidedUpdate4Sensors, range, loc::MapAidedMethod::kRange);
BENCHMARK_CAPTURE(BM_MapAidedUpdate4Sensors, ellipsoid_cut, loc::MapAidedMethod::kEllipsoidCut);
BENCHMARK_CAPTURE(BM_MapAidedUpdate4Sensors, ellipsoid_cut_deprior, loc::MapAidedMethod::kEllipsoidCutDeprior);
BENCHMARK_CAPTURE(BM_MapAidedUpdate4SensorsOneStamp, range, loc::MapAidedMethod::kRange);
BENCHMARK_CAPTURE(BM_MapAidedUpdate4SensorsDriving, range, loc::MapAidedMethod::kRange);
BENCHMARK(BM_RowMapRangingCandidates);
BENCHMARK(BM_RowMapRangingConstruction)->Unit(benchmark::kMillisecond);
