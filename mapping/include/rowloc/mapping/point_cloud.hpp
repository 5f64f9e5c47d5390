// Survey point clouds: an in-memory cloud of 3-D points in local metres, and its PLY / PCD files
// (input of the mapping pipeline, docs/mapping.md).
//
// Files are parsed and written by PCL (pcl::io::loadPLYFile / loadPCDFile, PLYWriter / PCDWriter);
// only the x, y, z fields are read, as float or double, whatever other fields the file carries.
// Files are written binary with double-precision x, y, z, so a write/read round trip is exact.
//
// Non-finite points are rejected, not dropped: a survey cloud with NaN or infinite coordinates is
// corrupt (or an organized sensor frame, which is not a survey), and dropping points silently would
// hide that. The error says how many of the points are non-finite.
//
// This header exposes Eigen and the standard library only; PCL stays in point_cloud.cpp.
#pragma once

#include <Eigen/Core>

#include <array>
#include <filesystem>
#include <functional>
#include <stdexcept>
#include <string>
#include <vector>

namespace rowloc::mapping {

/// A point cloud in a local metric frame (e.g. ENU metres around a stated origin).
struct PointCloud {
  std::vector<Eigen::Vector3d> points_m;  ///< point positions, metres
};

/// A point cloud file could not be read or written. what() names the file and the reason.
class PointCloudError : public std::runtime_error {
 public:
  PointCloudError(const std::filesystem::path& path, const std::string& reason);
  const std::filesystem::path& path() const { return path_; }
  const std::string& reason() const { return reason_; }

 private:
  std::filesystem::path path_;
  std::string reason_;
};

/// Reads a point cloud, by extension (case-insensitive): ".ply" (ASCII or binary) or ".pcd"
/// (ASCII, binary or binary_compressed). Only the x, y, z fields are kept. ".las" (LAS 1.0-1.4,
/// uncompressed, point formats 0-10) is read by ReadLasPointCloud (las_file.hpp), in double;
/// ".laz" is refused with the command that converts it.
/// The header is checked against the file first (CheckPcdFile / CheckPlyFile, point_cloud_header.hpp),
/// so memory is bounded by what the file holds, not by what its header claims.
/// Throws PointCloudError if the file is missing or not a regular file, the extension is unknown,
/// a header claim is not backed by the file (the message names the line and the claim), PCL cannot
/// parse it, it has no x/y/z float fields, it holds no points, or any point has a non-finite
/// coordinate (the message gives the count).
PointCloud ReadPointCloud(const std::filesystem::path& path);

/// Reads a point cloud as ReadPointCloud does, handing it to `visit` in chunks of at most
/// `chunk_points` points, in file order. LAS files are streamed (memory: one chunk, whatever the
/// file's size); PLY and PCD are read whole by PCL first (memory: the whole cloud), since PCL has
/// no incremental reader. Returns the number of points. Throws as ReadPointCloud, and
/// std::invalid_argument if chunk_points is 0.
std::size_t ForEachPointChunk(const std::filesystem::path& path, std::size_t chunk_points,
                              const std::function<void(const std::vector<Eigen::Vector3d>&)>& visit);

/// Writes a point cloud as binary PLY or binary PCD (by extension, case-insensitive), with x, y, z
/// as double, through mapio::OutputFile (a temporary renamed over the target on success; never over
/// a device or directory). Throws PointCloudError on unknown extension, empty cloud, non-finite
/// points (count in the message) or a write failure (e.g. missing directory, with the OS reason).
void WritePointCloud(const PointCloud& cloud, const std::filesystem::path& path);

/// Writes a triangle mesh (vertices and counter-clockwise index triples) as a binary PLY with
/// float x, y, z (PCL's mesh writer takes no other; for a local frame: 1 mm up to 16 km from its
/// origin) and a face list (PCL's PLY writer), atomically (a temporary renamed over the
/// target). ReadPointCloud reads its vertices back. Throws PointCloudError for another extension,
/// an empty mesh, a non-finite vertex, an index out of range, or a write failure.
void WriteTriangleMeshPly(const std::vector<Eigen::Vector3d>& vertices_m,
                          const std::vector<std::array<int, 3>>& triangles, const std::filesystem::path& path);

}  // namespace rowloc::mapping
