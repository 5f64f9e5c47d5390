// Steps 1-3 per tile and the merge of their products (see tile_processing.hpp).
#include "rowloc/mapping/tile_processing.hpp"

#include "rowloc/mapping/cloud_cleaning.hpp"
#include "rowloc/mapping/row_outline.hpp"

#include <fmt/format.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdint>
#include <limits>
#include <stdexcept>
#include <thread>
#include <unordered_set>
#include <utility>

namespace rowloc::mapping {
namespace {

using Clock = std::chrono::steady_clock;

double SecondsSince(Clock::time_point start) { return std::chrono::duration<double>(Clock::now() - start).count(); }

/// Keeps the first point of each square cell of edge cell_m (on the lattice anchored at 0): an
/// actual point, so that the kept points spread evenly over a region up to its edges (centroids
/// would stop half a cell short of an edge aligned with the lattice).
void KeepOnePerCell(std::vector<Eigen::Vector2d>& points_m, double cell_m) {
  std::unordered_set<std::uint64_t> seen;
  seen.reserve(points_m.size() / 4);
  std::erase_if(points_m, [&](const Eigen::Vector2d& p) {
    const auto i = static_cast<std::int64_t>(std::floor(p.x() / cell_m));
    const auto j = static_cast<std::int64_t>(std::floor(p.y() / cell_m));
    const std::uint64_t key = (static_cast<std::uint64_t>(i) << 32) ^ (static_cast<std::uint64_t>(j) & 0xffffffffULL);
    return !seen.insert(key).second;
  });
  points_m.shrink_to_fit();
}

/// Replaces the points by one centroid per square cell of edge cell_m (the voxel grid of step 1).
void ThinToCells(std::vector<Eigen::Vector2d>& points_m, double cell_m) {
  if (points_m.empty()) return;
  PointCloud flat;
  flat.points_m.reserve(points_m.size());
  for (const auto& p : points_m) flat.points_m.emplace_back(p.x(), p.y(), 0.0);
  std::vector<Eigen::Vector2d>().swap(points_m);
  const CleanResult cells = CleanCloud(flat, CleanParams{cell_m, 0, 3.0});
  points_m.reserve(cells.cloud.points_m.size());
  for (const auto& p : cells.cloud.points_m) points_m.push_back(p.head<2>());
}

/// The survey's DTM lattice, and which of its cells are set.
struct DtmAssembly {
  Eigen::Vector2d origin_m;
  double cell_m = 0.0;
  int nx = 0;
  int ny = 0;
  std::vector<double> heights_m;
  std::vector<bool> ground;
  std::vector<bool> set;
  std::vector<bool> owned;  ///< set from the tile whose core holds the cell's centre

  DtmAssembly(const Eigen::Vector2d& min_m, const Eigen::Vector2d& max_m, double cell) : cell_m(cell) {
    origin_m = (min_m / cell).array().floor() * cell;
    const double fx = std::floor((max_m.x() - origin_m.x()) / cell) + 1.0;
    const double fy = std::floor((max_m.y() - origin_m.y()) / cell) + 1.0;
    if (fx * fy > 1e8) {
      throw std::invalid_argument(fmt::format(
          "the terrain grid of the survey would have {:.0f} cells (more than 10^8); use a larger terrain.cell_size_m",
          fx * fy));
    }
    nx = static_cast<int>(fx);
    ny = static_cast<int>(fy);
    const std::size_t cells = static_cast<std::size_t>(nx) * static_cast<std::size_t>(ny);
    heights_m.assign(cells, 0.0);
    ground.assign(cells, false);
    set.assign(cells, false);
    owned.assign(cells, false);
  }

  void Take(const TerrainGrid& tile, const Rect2& core_m) {
    const auto di = static_cast<int>(std::lround((tile.origin_m().x() - origin_m.x()) / cell_m));
    const auto dj = static_cast<int>(std::lround((tile.origin_m().y() - origin_m.y()) / cell_m));
    for (int j = 0; j < tile.ny(); ++j) {
      const int gj = j + dj;
      if (gj < 0 || gj >= ny) continue;
      for (int i = 0; i < tile.nx(); ++i) {
        const int gi = i + di;
        if (gi < 0 || gi >= nx) continue;
        const std::size_t g = static_cast<std::size_t>(gj) * nx + gi;
        const Eigen::Vector2d centre = origin_m + cell_m * Eigen::Vector2d(gi + 0.5, gj + 0.5);
        const bool own = core_m.Contains(centre);
        if (owned[g] || (set[g] && !own)) continue;
        const std::size_t t = static_cast<std::size_t>(j) * tile.nx() + i;
        heights_m[g] = tile.heights_m()[t];
        ground[g] = tile.ground()[t];
        set[g] = true;
        owned[g] = own;
      }
    }
  }

  TerrainGrid Finish() {
    std::vector<bool> filled = set;
    FillFromNeighbours(heights_m, filled, nx, ny);
    return TerrainGrid(origin_m, cell_m, nx, ny, std::move(heights_m), std::move(ground));
  }
};

int ThreadCount(int configured) {
  if (configured > 0) return configured;
  return static_cast<int>(std::clamp(std::thread::hardware_concurrency(), 1U, 64U));
}

}  // namespace

CleanedTile CleanTile(std::vector<Eigen::Vector3d> points_m, const Rect2& core_m, const MapBuildConfig& config,
                      int threads) {
  CleanedTile out;
  // Only the core and a margin that holds its points' nearest neighbours are cleaned.
  const Rect2 cleaned_area{core_m.min_m.array() - kCleanMarginM, core_m.max_m.array() + kCleanMarginM};
  std::erase_if(points_m, [&](const Eigen::Vector3d& p) { return !cleaned_area.Contains(p.head<2>()); });
  for (const auto& p : points_m) out.core_points_in += core_m.Contains(p.head<2>()) ? 1 : 0;
  if (points_m.empty()) return out;
  PointCloud tile{std::move(points_m)};
  CleanParams voxel_only = config.clean;
  voxel_only.outlier_neighbours = 0;
  CleanResult voxels = CleanCloud(tile, voxel_only, threads);
  PointCloud().points_m.swap(tile.points_m);
  out.voxel_seconds = voxels.voxel_seconds;
  for (const auto& p : voxels.cloud.points_m) out.core_after_voxel += core_m.Contains(p.head<2>()) ? 1 : 0;
  CleanParams outliers_only = config.clean;
  outliers_only.voxel_size_m = 0.0;
  CleanResult clean = CleanCloud(voxels.cloud, outliers_only, threads);
  out.outlier_seconds = clean.outlier_seconds;
  for (auto& p : clean.cloud.points_m) {
    if (core_m.Contains(p.head<2>())) out.core_points_m.push_back(p);
  }
  return out;
}

TileProducts NormalizeTile(const std::vector<Eigen::Vector3d>& cleaned_m, const TileJob& job,
                           const MapBuildConfig& config) {
  TileProducts out;
  if (cleaned_m.empty()) return out;
  // 2. Terrain over the whole tile, so that the core's cells see their neighbourhood.
  auto start = Clock::now();
  out.terrain = BuildTerrainGrid(PointCloud{cleaned_m}, config.terrain);
  out.terrain_seconds = SecondsSince(start);

  // 3. Heights above it and the band (and the mesh levels' bands), for the core's points only.
  start = Clock::now();
  const std::vector<double> levels = MeshLevelHeights(config.mesh);
  out.level_band_m.resize(levels.size());
  const bool keep_top = config.outline.one_sided_max_width_m > 0.0;
  const double top_from_m = config.band.reference_height_m + config.band.band_half_width_m;
  std::size_t core_index = 0;
  for (const Eigen::Vector3d& p : cleaned_m) {
    const Eigen::Vector2d xy = p.head<2>();
    if (!job.core_m.Contains(xy)) continue;
    ++out.core_cleaned;
    const double h = p.z() - out.terrain->HeightAt(xy);
    if (std::abs(h - config.band.reference_height_m) <= config.band.band_half_width_m) out.band_m.push_back(xy);
    if (keep_top && h > top_from_m) out.top_m.push_back(xy);
    for (std::size_t k = 0; k < levels.size(); ++k) {
      if (std::abs(h - levels[k]) <= config.band.band_half_width_m) out.level_band_m[k].push_back(xy);
    }
    if (core_index++ % job.sample_stride == 0) {
      out.sample_m.push_back(xy);
      out.sample_height_m.push_back(h);
    }
    if (job.keep_canopy && h > config.terrain.ground_tolerance_m) out.canopy_m.emplace_back(xy.x(), xy.y(), p.z());
  }
  // The mesh levels' bands thinned to one centroid per 2 cm cell: the stack of a face's points at
  // one station collapses, the outline's edges keep their centimetres, memory drops 3-6 times.
  for (auto& band : out.level_band_m) ThinToCells(band, kLevelBandCellM);
  KeepOnePerCell(out.top_m, kTopCellM);
  out.normalize_seconds = SecondsSince(start);
  return out;
}

TileProducts ProcessTile(std::vector<Eigen::Vector3d> points_m, const TileJob& job, const MapBuildConfig& config) {
  // One tile alone: every point given is cleaned (its bounding box is the "core" of the clean step).
  Rect2 all{Eigen::Vector2d::Constant(std::numeric_limits<double>::infinity()),
            Eigen::Vector2d::Constant(-std::numeric_limits<double>::infinity())};
  for (const auto& p : points_m) {
    all.min_m = all.min_m.cwiseMin(p.head<2>());
    all.max_m = all.max_m.cwiseMax(p.head<2>() + Eigen::Vector2d::Constant(1e-9));
  }
  const std::size_t points_in = points_m.size();
  std::size_t core_points_in = 0;
  for (const auto& p : points_m) core_points_in += job.core_m.Contains(p.head<2>()) ? 1 : 0;
  const CleanedTile cleaned = CleanTile(std::move(points_m), all, config, job.threads);
  TileProducts out = NormalizeTile(cleaned.core_points_m, job, config);
  out.points_in = points_in;
  out.core_points_in = core_points_in;
  out.voxel_seconds = cleaned.voxel_seconds;
  out.outlier_seconds = cleaned.outlier_seconds;
  return out;
}

SurveyProducts ProcessTiles(TiledCloud& cloud, const Eigen::Vector2d& offset_m, const MapBuildConfig& config,
                            bool keep_canopy, const ProgressCallback& progress) {
  if (cloud.point_count() == 0 || !cloud.layout()) throw std::invalid_argument("the cloud has no points");
  if (const auto problem = ValidateMapBuildConfig(config)) throw std::invalid_argument("configuration: " + *problem);
  const auto wall_start = Clock::now();
  SurveyProducts survey;
  survey.threads = ThreadCount(config.tiles.threads);
  survey.largest_tile_points = cloud.largest_tile_points();
  survey.stored_points = cloud.stored_count();
  DtmAssembly dtm(cloud.min_m() - offset_m, cloud.max_m() - offset_m, config.terrain.cell_size_m);
  const std::vector<TileIndex> tiles = cloud.Tiles();
  survey.tiles = tiles.size();
  TileJob job;
  job.sample_stride = std::max<std::size_t>(1, cloud.point_count() / 20000);
  job.keep_canopy = keep_canopy;
  job.threads = survey.threads;

  const auto to_working = [&offset_m](std::vector<Eigen::Vector3d>& points) {
    for (auto& p : points) p.head<2>() -= offset_m;
  };
  const auto core_of = [&](const TileIndex& tile) {
    const Rect2 core = cloud.layout()->Core(tile);
    return Rect2{core.min_m - offset_m, core.max_m - offset_m};
  };
  // Phase 1: clean each tile's core (and a margin for its neighbours' search) into a second tiled
  // cloud, so that phase 2 sees cleaned points in its whole overlap.
  std::optional<TiledCloud> cleaned;
  if (cloud.directory()) {
    cleaned.emplace(config.tiles.size_m, config.tiles.overlap_m, *cloud.directory() / "cleaned");
  } else {
    cleaned.emplace(config.tiles.size_m, config.tiles.overlap_m);
  }
  for (std::size_t k = 0; k < tiles.size(); ++k) {
    std::vector<Eigen::Vector3d> points = cloud.Load(tiles[k]);
    cloud.Release(tiles[k]);
    to_working(points);
    CleanedTile c = CleanTile(std::move(points), core_of(tiles[k]), config, survey.threads);
    survey.points_after_voxel += c.core_after_voxel;
    survey.voxel_seconds += c.voxel_seconds;
    survey.outlier_seconds += c.outlier_seconds;
    cleaned->Add(c.core_points_m);
    if (progress) progress("clean", k + 1, tiles.size());
  }
  // Phase 2: terrain and band per tile of cleaned points (core and overlap).
  const std::vector<TileIndex> cleaned_tiles = cleaned->Tiles();
  for (std::size_t k = 0; k < cleaned_tiles.size(); ++k) {
    const std::vector<Eigen::Vector3d> points = cleaned->Load(cleaned_tiles[k]);
    cleaned->Release(cleaned_tiles[k]);
    job.core_m = cleaned->layout()->Core(cleaned_tiles[k]);  // the working frame's tiles
    const TileProducts p = NormalizeTile(points, job, config);
    survey.points_cleaned += p.core_cleaned;
    survey.terrain_seconds += p.terrain_seconds;
    survey.normalize_seconds += p.normalize_seconds;
    if (p.terrain) dtm.Take(*p.terrain, job.core_m);
    survey.band_m.insert(survey.band_m.end(), p.band_m.begin(), p.band_m.end());
    survey.sample_m.insert(survey.sample_m.end(), p.sample_m.begin(), p.sample_m.end());
    survey.sample_height_m.insert(survey.sample_height_m.end(), p.sample_height_m.begin(), p.sample_height_m.end());
    survey.canopy_m.insert(survey.canopy_m.end(), p.canopy_m.begin(), p.canopy_m.end());
    survey.top_m.insert(survey.top_m.end(), p.top_m.begin(), p.top_m.end());
    survey.level_band_m.resize(p.level_band_m.size());
    for (std::size_t level = 0; level < p.level_band_m.size(); ++level) {
      survey.level_band_m[level].insert(survey.level_band_m[level].end(), p.level_band_m[level].begin(),
                                        p.level_band_m[level].end());
    }
    if (progress) progress("terrain", k + 1, cleaned_tiles.size());
  }
  if (std::none_of(dtm.set.begin(), dtm.set.end(), [](bool s) { return s; })) {
    throw std::invalid_argument("no points left after cleaning");
  }
  survey.terrain = dtm.Finish();
  survey.wall_seconds = SecondsSince(wall_start);
  return survey;
}

}  // namespace rowloc::mapping
