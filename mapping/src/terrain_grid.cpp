// Ground classification and DTM (see terrain_grid.hpp). Plain C++ and Eigen.
#include "rowloc/mapping/terrain_grid.hpp"

#include <Eigen/Dense>

#include <algorithm>
#include <optional>
#include <cmath>
#include <cstdint>
#include <limits>
#include <stdexcept>
#include <string>
#include <utility>

namespace rowloc::mapping {

TerrainGrid::TerrainGrid(Eigen::Vector2d origin_m, double cell_size_m, int nx, int ny,
                         std::vector<double> heights_m, std::vector<bool> ground)
    : origin_m_(std::move(origin_m)),
      cell_size_m_(cell_size_m),
      nx_(nx),
      ny_(ny),
      heights_m_(std::move(heights_m)),
      ground_(std::move(ground)) {
  if (!(cell_size_m_ > 0.0) || !std::isfinite(cell_size_m_) || nx_ < 1 || ny_ < 1 ||
      !origin_m_.allFinite()) {
    throw std::invalid_argument("TerrainGrid: cell size, counts or origin invalid");
  }
  const auto cells = static_cast<std::size_t>(nx_) * static_cast<std::size_t>(ny_);
  if (heights_m_.size() != cells || ground_.size() != cells) {
    throw std::invalid_argument("TerrainGrid: " + std::to_string(cells) + " cells, got " +
                                std::to_string(heights_m_.size()) + " heights and " +
                                std::to_string(ground_.size()) + " ground flags");
  }
  for (double h : heights_m_) {
    if (!std::isfinite(h)) throw std::invalid_argument("TerrainGrid: non-finite height");
  }
}

double TerrainGrid::HeightAt(const Eigen::Vector2d& xy_m) const {
  // Continuous cell coordinates of the centres: centre of cell i at u = i.
  const double u = std::clamp((xy_m.x() - origin_m_.x()) / cell_size_m_ - 0.5, 0.0, nx_ - 1.0);
  const double v = std::clamp((xy_m.y() - origin_m_.y()) / cell_size_m_ - 0.5, 0.0, ny_ - 1.0);
  const int i0 = std::min(static_cast<int>(u), nx_ - 1);
  const int j0 = std::min(static_cast<int>(v), ny_ - 1);
  const int i1 = std::min(i0 + 1, nx_ - 1);
  const int j1 = std::min(j0 + 1, ny_ - 1);
  const double fu = u - i0;
  const double fv = v - j0;
  const auto at = [&](int i, int j) { return heights_m_[static_cast<std::size_t>(j) * nx_ + i]; };
  return (1 - fv) * ((1 - fu) * at(i0, j0) + fu * at(i1, j0)) + fv * ((1 - fu) * at(i0, j1) + fu * at(i1, j1));
}

std::size_t TerrainGrid::GroundCellCount() const {
  return static_cast<std::size_t>(std::count(ground_.begin(), ground_.end(), true));
}

namespace {

/// The mean height of cell (i, j) and its eight neighbours inside the grid, counting only filled
/// cells when `filled` is given; nullopt when none counts.
std::optional<double> NeighbourMean(const std::vector<double>& height, int nx, int ny, int i, int j,
                                    const std::vector<bool>* filled) {
  double sum = 0.0;
  int count = 0;
  for (int jj = std::max(j - 1, 0); jj <= std::min(j + 1, ny - 1); ++jj) {
    for (int ii = std::max(i - 1, 0); ii <= std::min(i + 1, nx - 1); ++ii) {
      const std::size_t n = static_cast<std::size_t>(jj) * nx + ii;
      if (filled && !(*filled)[n]) continue;
      sum += height[n];
      ++count;
    }
  }
  if (count == 0) return std::nullopt;
  return sum / count;
}

}  // namespace

TerrainGrid BuildTerrainGrid(const PointCloud& cloud, const TerrainParams& params) {
  if (cloud.points_m.empty()) throw std::invalid_argument("BuildTerrainGrid: empty cloud");
  if (!(params.cell_size_m >= 0.05 && params.cell_size_m <= 20.0) ||
      !(params.classification_radius_m > 0.0) || !(params.ground_tolerance_m > 0.0) ||
      !(params.ground_thickness_m >= 0.0) || params.smoothing_passes < 0 || params.min_ground_points < 1) {
    throw std::invalid_argument("BuildTerrainGrid: parameter outside its domain");
  }
  const double cell = params.cell_size_m;
  Eigen::Vector2d lo = cloud.points_m.front().head<2>();
  Eigen::Vector2d hi = lo;
  for (const auto& p : cloud.points_m) {
    lo = lo.cwiseMin(p.head<2>());
    hi = hi.cwiseMax(p.head<2>());
  }
  lo = (lo / cell).array().floor() * cell;  // the lattice of multiples of the cell
  const double fx = std::floor((hi.x() - lo.x()) / cell) + 1.0;
  const double fy = std::floor((hi.y() - lo.y()) / cell) + 1.0;
  if (fx * fy > 1e8) {
    throw std::invalid_argument("BuildTerrainGrid: the grid would have " + std::to_string(fx * fy) +
                                " cells (more than 10^8); use a larger terrain.cell_size_m");
  }
  const int nx = static_cast<int>(fx);
  const int ny = static_cast<int>(fy);
  const std::size_t cells = static_cast<std::size_t>(nx) * static_cast<std::size_t>(ny);
  const auto cell_of = [&](const Eigen::Vector3d& p) {
    const int i = std::min(nx - 1, static_cast<int>((p.x() - lo.x()) / cell));
    const int j = std::min(ny - 1, static_cast<int>((p.y() - lo.y()) / cell));
    return static_cast<std::size_t>(j) * nx + i;
  };

  // 1. Lowest level per cell: the lowest z with at least min_ground_points points within
  //    ground_thickness_m above it (so an isolated point below the ground, which the outlier
  //    removal keeps when it lies near the ground's points, is skipped), and the median of those
  //    points (the cell's ground height if it is ground).
  const double inf = std::numeric_limits<double>::infinity();
  std::vector<std::pair<std::uint32_t, double>> cell_z;
  cell_z.reserve(cloud.points_m.size());
  for (const auto& p : cloud.points_m) cell_z.emplace_back(static_cast<std::uint32_t>(cell_of(p)), p.z());
  std::sort(cell_z.begin(), cell_z.end());
  std::vector<double> z_min(cells, inf);
  std::vector<double> level(cells, inf);
  // A cloud too sparse for the support everywhere (a few points in a corner tile) falls back to the
  // lowest point of each cell.
  for (const int wanted : {params.min_ground_points, 1}) {
    const auto support = static_cast<std::size_t>(std::max(wanted, 1));
    for (std::size_t begin = 0; begin < cell_z.size();) {
      std::size_t end = begin;
      while (end < cell_z.size() && cell_z[end].first == cell_z[begin].first) ++end;
      for (std::size_t i = begin; i + support <= end; ++i) {
        if (cell_z[i + support - 1].second - cell_z[i].second > params.ground_thickness_m) continue;
        std::size_t top = i + support;
        while (top < end && cell_z[top].second - cell_z[i].second <= params.ground_thickness_m) ++top;
        z_min[cell_z[i].first] = cell_z[i].second;
        level[cell_z[i].first] = cell_z[i + (top - i) / 2].second;
        break;
      }
      begin = end;
    }
    if (std::any_of(z_min.begin(), z_min.end(), [inf](double z) { return z != inf; })) break;
  }
  std::vector<std::pair<std::uint32_t, double>>().swap(cell_z);

  // 2. Robust local lower-envelope plane per occupied cell.
  const int r = std::max(1, static_cast<int>(std::ceil(params.classification_radius_m / cell)));
  const double r2 = params.classification_radius_m * params.classification_radius_m;
  std::vector<bool> ground(cells, false);
  std::vector<std::pair<Eigen::Vector2d, double>> neighbours;
  for (int j = 0; j < ny; ++j) {
    for (int i = 0; i < nx; ++i) {
      const std::size_t c = static_cast<std::size_t>(j) * nx + i;
      if (z_min[c] == inf) continue;
      neighbours.clear();
      for (int dj = -r; dj <= r; ++dj) {
        for (int di = -r; di <= r; ++di) {
          const int ii = i + di;
          const int jj = j + dj;
          if (ii < 0 || jj < 0 || ii >= nx || jj >= ny) continue;
          const Eigen::Vector2d d(di * cell, dj * cell);
          if (d.squaredNorm() > r2) continue;
          const double z = z_min[static_cast<std::size_t>(jj) * nx + ii];
          if (z != inf) neighbours.emplace_back(d, z);
        }
      }
      // Start from the lowest neighbour as a level plane, then refit on the cells below plane + tol.
      double a = inf;
      for (const auto& n : neighbours) a = std::min(a, n.second);
      Eigen::Vector3d plane(a + 0.5 * params.ground_tolerance_m, 0.0, 0.0);
      for (int iteration = 0; iteration < 5; ++iteration) {
        Eigen::Matrix3d ata = Eigen::Matrix3d::Zero();
        Eigen::Vector3d atb = Eigen::Vector3d::Zero();
        int used = 0;
        for (const auto& [d, z] : neighbours) {
          const double predicted = plane[0] + plane[1] * d.x() + plane[2] * d.y();
          if (z - predicted > params.ground_tolerance_m) continue;
          const Eigen::Vector3d row(1.0, d.x(), d.y());
          ata += row * row.transpose();
          atb += row * z;
          ++used;
        }
        if (used == 0) break;
        // Regularize the slopes (few or collinear cells): a level plane unless the data say otherwise.
        ata(1, 1) += 1e-3;
        ata(2, 2) += 1e-3;
        plane = ata.ldlt().solve(atb);
      }
      ground[c] = z_min[c] - plane[0] <= params.ground_tolerance_m;
    }
  }

  // 3. Ground height per ground cell: the median found in step 1.
  std::vector<double> height(cells, 0.0);
  std::vector<bool> filled(cells, false);
  for (std::size_t c = 0; c < cells; ++c) {
    if (!ground[c]) continue;
    height[c] = level[c];
    filled[c] = true;
  }

  // 4. Fill outward from the ground cells, then smooth.
  if (std::none_of(filled.begin(), filled.end(), [](bool f) { return f; })) {
    // No ground at all (cannot happen: the lowest cell is always ground); keep a level terrain.
    const double lowest = *std::min_element(z_min.begin(), z_min.end());
    std::fill(height.begin(), height.end(), lowest);
    std::fill(filled.begin(), filled.end(), true);
  }
  FillFromNeighbours(height, filled, nx, ny);
  for (int pass = 0; pass < params.smoothing_passes; ++pass) {
    std::vector<double> next(cells, 0.0);
    for (int j = 0; j < ny; ++j) {
      for (int i = 0; i < nx; ++i) {
        next[static_cast<std::size_t>(j) * nx + i] = *NeighbourMean(height, nx, ny, i, j, nullptr);
      }
    }
    height = std::move(next);
  }
  return TerrainGrid(lo, cell, nx, ny, std::move(height), std::move(ground));
}

void FillFromNeighbours(std::vector<double>& heights_m, std::vector<bool>& filled, int nx, int ny) {
  const std::size_t cells = static_cast<std::size_t>(std::max(nx, 0)) * static_cast<std::size_t>(std::max(ny, 0));
  if (nx <= 0 || ny <= 0 || heights_m.size() != cells || filled.size() != cells) {
    throw std::invalid_argument("FillFromNeighbours: sizes do not match nx * ny");
  }
  if (std::none_of(filled.begin(), filled.end(), [](bool f) { return f; })) {
    throw std::invalid_argument("FillFromNeighbours: no cell is filled");
  }
  bool missing = true;
  while (missing) {
    missing = false;
    std::vector<double> next = heights_m;
    std::vector<bool> next_filled = filled;
    for (int j = 0; j < ny; ++j) {
      for (int i = 0; i < nx; ++i) {
        const std::size_t c = static_cast<std::size_t>(j) * nx + i;
        if (filled[c]) continue;
        if (const std::optional<double> mean = NeighbourMean(heights_m, nx, ny, i, j, &filled)) {
          next[c] = *mean;
          next_filled[c] = true;
        } else {
          missing = true;
        }
      }
    }
    heights_m = std::move(next);
    filled = std::move(next_filled);
  }
}

std::vector<double> HeightsAboveTerrain(const PointCloud& cloud, const TerrainGrid& terrain) {
  std::vector<double> h;
  h.reserve(cloud.points_m.size());
  for (const auto& p : cloud.points_m) h.push_back(p.z() - terrain.HeightAt(p.head<2>()));
  return h;
}

}  // namespace rowloc::mapping
