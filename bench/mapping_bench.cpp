// The whole map build (`rowloc map build`: read, tile, clean, terrain, normalize, rows, outline,
// simplify, write) on synthetic surveys of 0.25 ha and 1 ha vineyards (rows of 100 m, 2.5 m apart;
// canopy faces sampled every 5 cm with 5 mm noise, the ground every 10 cm: ~600 points per m^2),
// from a binary PCD (read whole by PCL) and from a LAS 1.4 file (streamed). items_per_second is
// survey points per second, wall clock, the default configuration (tiles of 40 m, the k-NN
// queries of the outlier removal on every hardware thread). Results: docs/benchmarks.md.
#include "rowloc/mapping/las_file.hpp"
#include "rowloc/mapping/map_builder.hpp"
#include "rowloc/mapping/point_cloud.hpp"
#include "rowloc/sim/canopy_surface_sampler.hpp"
#include "rowloc/sim/row_world.hpp"

#include <benchmark/benchmark.h>

#include <filesystem>
#include <map>
#include <string>
#include <unistd.h>

namespace {

namespace fs = std::filesystem;
using rowloc::mapping::PointCloud;

struct Survey {
  fs::path pcd;
  fs::path las;
  std::size_t points = 0;
};

/// The surveys' directory, removed at exit.
struct Scratch {
  fs::path dir = fs::temp_directory_path() / ("rowloc-mapping-bench-" + std::to_string(getpid()));
  ~Scratch() {
    std::error_code ec;
    fs::remove_all(dir, ec);
  }
} scratch;

const fs::path& ScratchDirectory() { return scratch.dir; }

/// A vineyard of `rows` rows of 100 m (written once per size, removed at exit).
const Survey& SurveyOfRows(int rows) {
  static std::map<int, Survey> surveys;
  if (const auto found = surveys.find(rows); found != surveys.end()) return found->second;
  rowloc::sim::RowWorldParams params =
      rowloc::sim::LoadRowWorldParams(fs::path(ROWLOC_SOURCE_DIR) / "config/worlds/vineyard-002.json");
  params.row_count = rows;
  params.row_length_m = 100.0;
  const rowloc::sim::RowWorld world(params);
  rowloc::sim::SurveyParams survey_params;
  survey_params.include_terrain = true;
  PointCloud cloud{rowloc::sim::SampleCanopySurface(world, survey_params)};
  Survey survey;
  fs::create_directories(ScratchDirectory());
  survey.points = cloud.points_m.size();
  survey.pcd = ScratchDirectory() / ("survey-" + std::to_string(rows) + ".pcd");
  survey.las = ScratchDirectory() / ("survey-" + std::to_string(rows) + ".las");
  rowloc::mapping::WritePointCloud(cloud, survey.pcd);
  rowloc::mapping::LasCloud las;
  las.points_m = std::move(cloud.points_m);
  las.intensity.assign(las.points_m.size(), 0);
  las.classification.assign(las.points_m.size(), 0);
  rowloc::mapping::WriteLasFile(las, survey.las);
  return surveys.emplace(rows, std::move(survey)).first->second;
}

void BM_MapBuild(benchmark::State& state, bool las) {
  const Survey& survey = SurveyOfRows(static_cast<int>(state.range(0)));
  rowloc::mapping::MapBuildRequest request;
  request.survey_path = las ? survey.las : survey.pcd;
  request.output_dir = ScratchDirectory() / "out";
  request.georeference = rowloc::mapping::Georeference::Local({45.0703, 7.6869, 240.0});
  std::size_t parts = 0;
  for (auto _ : state) {
    const rowloc::mapping::MapBuildResult result = rowloc::mapping::RunMapBuild(request);
    parts = result.parts.size();
    benchmark::DoNotOptimize(parts);
  }
  state.SetItemsProcessed(static_cast<std::int64_t>(state.iterations() * survey.points));
  state.counters["points"] = static_cast<double>(survey.points);
  state.counters["parts"] = static_cast<double>(parts);
}

void BM_MapBuildPcd(benchmark::State& state) { BM_MapBuild(state, false); }
void BM_MapBuildLas(benchmark::State& state) { BM_MapBuild(state, true); }

// 10 rows: 25 m x 100 m = 0.25 ha; 40 rows: 100 m x 100 m = 1 ha.
BENCHMARK(BM_MapBuildPcd)->Arg(10)->Arg(40)->Unit(benchmark::kSecond)->UseRealTime()->Iterations(2);
BENCHMARK(BM_MapBuildLas)->Arg(10)->Arg(40)->Unit(benchmark::kSecond)->UseRealTime()->Iterations(2);

}  // namespace
