// Occupancy map of the canopy as an OctoMap (Hornung et al., "OctoMap: an efficient probabilistic
// 3D mapping framework based on octrees", Autonomous Robots 2013), written as a compact .bt file
// (map build step 8, docs/mapping.md; read back later for ray casts).
//
// Voxels: OctoMap's octree of depth 16 at resolution r has voxel keys k = floor(x / r) + 32768 per
// axis, so voxel i covers [i r, (i + 1) r) and is centred at (i + 1/2) r; coordinates must lie in
// [-32768 r, 32768 r) on every axis. Every point of the cloud marks its voxel occupied (one "hit"
// with OctoMap's default sensor model, so occupancy probability 0.7 > 0.5); no ray is cast, so no
// voxel is marked free: every voxel without a point is unknown, and IsOccupied() returns false there.
//
// This header exposes Eigen and the standard library only; OctoMap stays in the .cpp (pimpl).
#pragma once

#include "rowloc/mapping/point_cloud.hpp"

#include <Eigen/Core>

#include <cstddef>
#include <cstdint>
#include <filesystem>
#include <memory>
#include <stdexcept>
#include <string>

namespace rowloc::mapping {

/// A .bt file could not be written or read. what() names the file and the reason.
class OccupancyMapError : public std::runtime_error {
 public:
  OccupancyMapError(const std::filesystem::path& path, const std::string& reason);
};

struct OctoMapOptions {
  /// Edge of the finest voxel, metres; must be in [kMinResolutionM, kMaxResolutionM].
  double resolution_m = 0.05;
};

/// Largest .bt file CanopyOccupancyMap::Load reads: 256 MiB, the limit of a row map file (the
/// canopy of config/worlds/vineyard-002.json at 5 cm voxels, `rowloc world`, is 0.3 MiB).
inline constexpr std::uintmax_t kMaxOctoMapFileBytes = std::uintmax_t{256} << 20;

/// Accepted range of OctoMapOptions::resolution_m, metres.
inline constexpr double kMinResolutionM = 1e-4;
inline constexpr double kMaxResolutionM = 1e3;

struct OctoMapSummary {
  /// Number of occupied voxels at the finest resolution (a pruned coarser leaf counts as all the
  /// finest voxels it covers), i.e. the number of distinct voxels the points fall in.
  std::size_t occupied_leaves = 0;
  double resolution_m = 0.0;  ///< voxel edge, metres
  Eigen::Vector3d min_m = Eigen::Vector3d::Zero();  ///< lower corner of the occupied voxels' box
  Eigen::Vector3d max_m = Eigen::Vector3d::Zero();  ///< upper corner of the occupied voxels' box
};

/// Builds the occupancy octree of the cloud (each point marks its voxel occupied) and writes it as
/// a binary OctoMap (.bt, maximum-likelihood, pruned). Throws std::invalid_argument for a
/// resolution out of range, an empty cloud, a non-finite point or a point outside the octree's
/// range (the message gives its index); OccupancyMapError if the file cannot be written.
OctoMapSummary WriteOctoMap(const PointCloud& cloud, const OctoMapOptions& options,
                            const std::filesystem::path& bt_path);

/// A canopy occupancy map read from a .bt file. Movable, not copyable; a moved-from map throws
/// std::logic_error on use.
class CanopyOccupancyMap {
 public:
  /// Reads a binary OctoMap (.bt). Throws OccupancyMapError if the file is missing, is not a
  /// regular file (a FIFO, a device, a directory: refused unread), is larger than
  /// kMaxOctoMapFileBytes, or is not a valid .bt file.
  static CanopyOccupancyMap Load(const std::filesystem::path& bt_path);

  ~CanopyOccupancyMap();
  CanopyOccupancyMap(CanopyOccupancyMap&&) noexcept;
  CanopyOccupancyMap& operator=(CanopyOccupancyMap&&) noexcept;
  CanopyOccupancyMap(const CanopyOccupancyMap&) = delete;
  CanopyOccupancyMap& operator=(const CanopyOccupancyMap&) = delete;

  /// True if the voxel containing point_m is known and occupied; false if it is free, unknown or
  /// outside the octree's range. Throws std::invalid_argument for a non-finite point.
  bool IsOccupied(const Eigen::Vector3d& point_m) const;
  /// Voxel edge, metres.
  double resolution_m() const;
  /// Occupied voxels at the finest resolution (same count as OctoMapSummary::occupied_leaves).
  std::size_t occupied_leaves() const;

 private:
  struct Impl;
  explicit CanopyOccupancyMap(std::unique_ptr<Impl> impl);
  const Impl& impl() const;
  std::unique_ptr<Impl> impl_;
};

}  // namespace rowloc::mapping
