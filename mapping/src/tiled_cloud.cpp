// Tiles with overlap, in memory or spilled to disk (see tiled_cloud.hpp).
#include "rowloc/mapping/tiled_cloud.hpp"

#include <fmt/format.h>

#include <algorithm>
#include <cerrno>
#include <cmath>
#include <cstring>
#include <fstream>
#include <stdexcept>
#include <system_error>
#include <utility>

namespace rowloc::mapping {

TileLayout::TileLayout(double size_m, double overlap_m, Eigen::Vector2d anchor_m)
    : size_m_(size_m), overlap_m_(overlap_m), anchor_m_(std::move(anchor_m)) {
  if (!(size_m > 0.0) || !std::isfinite(size_m) || !(overlap_m >= 0.0) || !std::isfinite(overlap_m) ||
      !anchor_m_.allFinite()) {
    throw std::invalid_argument(fmt::format("TileLayout: size {} m, overlap {} m: need size > 0, overlap >= 0",
                                            size_m, overlap_m));
  }
}

TileIndex TileLayout::CoreTile(const Eigen::Vector2d& p) const {
  const Eigen::Vector2d u = (p - anchor_m_) / size_m_;
  return {static_cast<std::int64_t>(std::floor(u.x())), static_cast<std::int64_t>(std::floor(u.y()))};
}

Rect2 TileLayout::Core(const TileIndex& tile) const {
  const Eigen::Vector2d min = anchor_m_ + size_m_ * Eigen::Vector2d(static_cast<double>(tile.i), static_cast<double>(tile.j));
  return {min, min + Eigen::Vector2d::Constant(size_m_)};
}

void TileLayout::TilesHolding(const Eigen::Vector2d& p, std::vector<TileIndex>& out) const {
  const Eigen::Vector2d lo = (p - anchor_m_ - Eigen::Vector2d::Constant(overlap_m_)) / size_m_;
  const Eigen::Vector2d hi = (p - anchor_m_ + Eigen::Vector2d::Constant(overlap_m_)) / size_m_;
  // Tile k holds p if a + k S - overlap <= p < a + (k+1) S + overlap.
  const auto first_i = static_cast<std::int64_t>(std::floor(lo.x()));
  const auto last_i = static_cast<std::int64_t>(std::floor(hi.x()));
  const auto first_j = static_cast<std::int64_t>(std::floor(lo.y()));
  const auto last_j = static_cast<std::int64_t>(std::floor(hi.y()));
  for (std::int64_t j = first_j; j <= last_j; ++j) {
    for (std::int64_t i = first_i; i <= last_i; ++i) out.push_back({i, j});
  }
}

TiledCloud::TiledCloud(double size_m, double overlap_m) : size_m_(size_m), overlap_m_(overlap_m) {
  TileLayout(size_m, overlap_m, Eigen::Vector2d::Zero());  // validates the sizes now
}

TiledCloud::TiledCloud(double size_m, double overlap_m, std::filesystem::path directory)
    : TiledCloud(size_m, overlap_m) {
  std::error_code ec;
  if (std::filesystem::exists(directory, ec)) {
    throw std::system_error(std::make_error_code(std::errc::file_exists),
                            "tile spill directory " + directory.string() + " exists already");
  }
  std::filesystem::create_directories(directory, ec);
  if (ec) throw std::system_error(ec, "cannot create the tile spill directory " + directory.string());
  directory_ = std::move(directory);
}

TiledCloud::~TiledCloud() {
  if (directory_) {
    std::error_code ec;
    std::filesystem::remove_all(*directory_, ec);  // best effort: a destructor must not throw
  }
}

std::filesystem::path TiledCloud::FileOf(const TileIndex& tile) const {
  return *directory_ / fmt::format("tile_{}_{}.xyz", tile.i, tile.j);
}

void TiledCloud::Flush(const TileIndex& tile, Store& store) {
  if (store.buffer.empty()) return;
  std::ofstream out(FileOf(tile), std::ios::binary | std::ios::app);
  out.write(reinterpret_cast<const char*>(store.buffer.data()),
            static_cast<std::streamsize>(store.buffer.size() * sizeof(Eigen::Vector3d)));
  out.close();
  if (!out) {
    throw std::system_error(errno != 0 ? errno : EIO, std::generic_category(),
                            "cannot write the tile spill file " + FileOf(tile).string());
  }
  store.buffer.clear();
}

void TiledCloud::Add(const std::vector<Eigen::Vector3d>& points_m) {
  static_assert(sizeof(Eigen::Vector3d) == 3 * sizeof(double), "spill files hold packed x y z doubles");
  for (const Eigen::Vector3d& p : points_m) {
    if (!p.allFinite()) {
      throw std::invalid_argument(fmt::format("TiledCloud: point {} is not finite", point_count_ + 1));
    }
    if (std::abs(p.x()) > kMaxHorizontalCoordinateM || std::abs(p.y()) > kMaxHorizontalCoordinateM) {
      throw std::invalid_argument(fmt::format(
          "TiledCloud: point {} at ({:g}, {:g}) m lies beyond 10^9 m of the origin: not a survey in metres",
          point_count_ + 1, p.x(), p.y()));
    }
    const Eigen::Vector2d xy = p.head<2>();
    if (!layout_) {
      layout_.emplace(size_m_, overlap_m_, Eigen::Vector2d::Zero());
      min_m_ = max_m_ = xy;
    }
    min_m_ = min_m_.cwiseMin(xy);
    max_m_ = max_m_.cwiseMax(xy);
    ++point_count_;
    ++tiles_[layout_->CoreTile(xy)].core_count;
    scratch_.clear();
    layout_->TilesHolding(xy, scratch_);
    for (const TileIndex& tile : scratch_) {
      Store& store = tiles_[tile];
      store.buffer.push_back(p);
      ++store.count;
      ++stored_count_;
      if (directory_ && store.buffer.size() >= kSpillBufferPoints) Flush(tile, store);
    }
  }
}

std::vector<TileIndex> TiledCloud::Tiles() const {
  std::vector<TileIndex> out;
  for (const auto& [tile, store] : tiles_) {
    if (store.core_count > 0) out.push_back(tile);
  }
  return out;
}

std::size_t TiledCloud::largest_tile_points() const {
  std::size_t largest = 0;
  for (const auto& entry : tiles_) largest = std::max(largest, entry.second.count);
  return largest;
}

std::vector<Eigen::Vector3d> TiledCloud::Load(const TileIndex& tile) {
  const auto found = tiles_.find(tile);
  if (found == tiles_.end()) return {};
  Store& store = found->second;
  if (!directory_) return store.buffer;
  std::vector<Eigen::Vector3d> points(store.count);
  const std::size_t written = store.count - store.buffer.size();
  if (written > 0) {
    std::ifstream in(FileOf(tile), std::ios::binary);
    in.read(reinterpret_cast<char*>(points.data()), static_cast<std::streamsize>(written * sizeof(Eigen::Vector3d)));
    if (!in || static_cast<std::size_t>(in.gcount()) != written * sizeof(Eigen::Vector3d)) {
      throw std::system_error(std::make_error_code(std::errc::io_error),
                              fmt::format("cannot read back the tile spill file {} ({} points expected)",
                                          FileOf(tile).string(), written));
    }
  }
  std::copy(store.buffer.begin(), store.buffer.end(), points.begin() + static_cast<std::ptrdiff_t>(written));
  return points;
}

void TiledCloud::Release(const TileIndex& tile) {
  const auto found = tiles_.find(tile);
  if (found == tiles_.end()) return;
  tiles_.erase(found);
  if (directory_) {
    std::error_code ec;
    std::filesystem::remove(FileOf(tile), ec);
  }
}

}  // namespace rowloc::mapping
