// A survey cut into square tiles with overlap, held in memory or spilled to disk, so that the map
// build's per-point steps (clean, terrain, normalize) see one tile at a time (docs/mapping.md,
// "Tiles and memory").
//
// Layout. Tile (i, j) has the core [a_x + i S, a_x + (i+1) S) x [a_y + j S, a_y + (j+1) S), S =
// size_m, a = the anchor; TiledCloud anchors at the survey's coordinate origin, so the tiles do not
// depend on the order in which points arrive, and a survey in UTM metres is cut on multiples of S
// eastings and northings. Every point lies in exactly one core. A
// tile holds the points of its core and of the overlap_m margin around it, so a point near a
// corner is stored in up to four tiles. Coordinates are kept in double, as read.
//
// Storage. In memory (TiledCloud(layout)), or on disk (TiledCloud(layout, directory)): each tile a
// file of raw little-endian doubles (x y z), appended through a buffer of kSpillBufferPoints
// points per tile, so that memory while the survey is read is at most tiles x 4096 x 24 bytes
// (96 KiB per tile), plus the caller's chunk. The directory is created and removed with the object.
#pragma once

#include <Eigen/Core>

#include <cstddef>
#include <cstdint>
#include <filesystem>
#include <map>
#include <optional>
#include <vector>

namespace rowloc::mapping {

/// A tile's column and row in the layout.
struct TileIndex {
  std::int64_t i = 0;
  std::int64_t j = 0;
  friend bool operator<(const TileIndex& a, const TileIndex& b) { return a.j != b.j ? a.j < b.j : a.i < b.i; }
  friend bool operator==(const TileIndex& a, const TileIndex& b) { return a.i == b.i && a.j == b.j; }
};

/// An axis-aligned rectangle [min, max) in metres.
struct Rect2 {
  Eigen::Vector2d min_m = Eigen::Vector2d::Zero();
  Eigen::Vector2d max_m = Eigen::Vector2d::Zero();
  bool Contains(const Eigen::Vector2d& p) const {
    return p.x() >= min_m.x() && p.x() < max_m.x() && p.y() >= min_m.y() && p.y() < max_m.y();
  }
};

class TileLayout {
 public:
  /// Throws std::invalid_argument unless size_m > 0, overlap_m >= 0 (both finite) and the anchor is finite.
  TileLayout(double size_m, double overlap_m, Eigen::Vector2d anchor_m);

  double size_m() const { return size_m_; }
  double overlap_m() const { return overlap_m_; }
  const Eigen::Vector2d& anchor_m() const { return anchor_m_; }

  /// The tile whose core holds p.
  TileIndex CoreTile(const Eigen::Vector2d& p) const;
  /// The tile's core rectangle.
  Rect2 Core(const TileIndex& tile) const;
  /// Appends the tiles whose core plus overlap holds p (1 to 4 when overlap < size).
  void TilesHolding(const Eigen::Vector2d& p, std::vector<TileIndex>& out) const;

 private:
  double size_m_;
  double overlap_m_;
  Eigen::Vector2d anchor_m_;
};

/// Horizontal coordinates beyond this (metres from the origin) are refused: no survey in metres
/// (UTM, local ENU) reaches them, and tile indices stay far from integer overflow.
inline constexpr double kMaxHorizontalCoordinateM = 1e9;

/// Points per tile buffered before a disk-backed TiledCloud appends them to the tile's file.
inline constexpr std::size_t kSpillBufferPoints = 4096;

class TiledCloud {
 public:
  /// In memory.
  TiledCloud(double size_m, double overlap_m);
  /// Spilled to files in `directory`, which must not exist (it is created, and removed by the
  /// destructor). Throws std::system_error if it cannot be created.
  TiledCloud(double size_m, double overlap_m, std::filesystem::path directory);
  ~TiledCloud();
  TiledCloud(const TiledCloud&) = delete;
  TiledCloud& operator=(const TiledCloud&) = delete;

  /// Adds points (any number of calls). Throws std::invalid_argument on a non-finite point or one
  /// beyond kMaxHorizontalCoordinateM, and std::system_error if a spill file cannot be written.
  void Add(const std::vector<Eigen::Vector3d>& points_m);

  /// The spill directory (nullopt: in memory).
  const std::optional<std::filesystem::path>& directory() const { return directory_; }
  /// The layout (nullopt before the first point).
  const std::optional<TileLayout>& layout() const { return layout_; }
  /// Tiles whose core holds at least one point, in (j, i) order.
  std::vector<TileIndex> Tiles() const;
  /// Points added (each once, however many tiles hold it).
  std::size_t point_count() const { return point_count_; }
  /// Points stored over all tiles (with the overlaps' copies).
  std::size_t stored_count() const { return stored_count_; }
  /// The largest number of points one tile holds (of the tiles not released).
  std::size_t largest_tile_points() const;
  /// Horizontal bounds of the added points (min, max); zero before the first point.
  const Eigen::Vector2d& min_m() const { return min_m_; }
  const Eigen::Vector2d& max_m() const { return max_m_; }

  /// The points of a tile (core and overlap), in the order they were added. Throws
  /// std::system_error if its spill file cannot be read back whole.
  std::vector<Eigen::Vector3d> Load(const TileIndex& tile);
  /// Frees a tile's storage (memory or file) once it is processed; the tile is then gone (Tiles()
  /// no longer lists it, Load returns nothing).
  void Release(const TileIndex& tile);

 private:
  struct Store {
    std::vector<Eigen::Vector3d> buffer;  ///< memory mode: all points; disk mode: not yet written
    std::size_t count = 0;                ///< points held (buffered and written)
    std::size_t core_count = 0;           ///< of them, in the core
  };
  void Flush(const TileIndex& tile, Store& store);
  std::filesystem::path FileOf(const TileIndex& tile) const;

  double size_m_;
  double overlap_m_;
  std::optional<TileLayout> layout_;
  std::optional<std::filesystem::path> directory_;
  std::map<TileIndex, Store> tiles_;
  std::size_t point_count_ = 0;
  std::size_t stored_count_ = 0;
  Eigen::Vector2d min_m_ = Eigen::Vector2d::Zero();
  Eigen::Vector2d max_m_ = Eigen::Vector2d::Zero();
  std::vector<TileIndex> scratch_;
};

}  // namespace rowloc::mapping
