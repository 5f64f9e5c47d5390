// PLY / PCD reading and writing through PCL (see point_cloud.hpp).
#include "rowloc/mapping/point_cloud.hpp"

#include "rowloc/mapio/output_file.hpp"
#include "rowloc/mapping/las_file.hpp"
#include "rowloc/mapping/point_cloud_header.hpp"

#include <pcl/PCLPointCloud2.h>
#include <pcl/PolygonMesh.h>
#include <pcl/conversions.h>
#include <pcl/point_cloud.h>
#include <pcl/point_types.h>
#include <pcl/io/pcd_io.h>
#include <pcl/io/ply_io.h>

#include <algorithm>
#include <cctype>
#include <cerrno>
#include <cmath>
#include <cstdint>
#include <cstring>
#include <exception>
#include <fstream>
#include <functional>
#include <new>
#include <optional>
#include <stdexcept>
#include <string_view>
#include <utility>

namespace rowloc::mapping {
namespace {

enum class CloudFormat { kPly, kPcd };

std::optional<CloudFormat> FormatOf(const std::filesystem::path& path) {
  std::string ext = path.extension().string();
  std::transform(ext.begin(), ext.end(), ext.begin(),
                 [](unsigned char c) { return static_cast<char>(std::tolower(c)); });
  if (ext == ".ply") return CloudFormat::kPly;
  if (ext == ".pcd") return CloudFormat::kPcd;
  return std::nullopt;
}

CloudFormat RequireFormat(const std::filesystem::path& path) {
  const std::optional<CloudFormat> format = FormatOf(path);
  if (!format) {
    throw PointCloudError(path, "unknown extension '" + path.extension().string() +
                                    "' (expected .ply or .pcd; .las is also read)");
  }
  return *format;
}

std::size_t CountNonFinite(const std::vector<Eigen::Vector3d>& points) {
  return static_cast<std::size_t>(std::count_if(
      points.begin(), points.end(), [](const Eigen::Vector3d& p) { return !p.allFinite(); }));
}

void RejectNonFinite(const std::vector<Eigen::Vector3d>& points, const std::filesystem::path& path) {
  const std::size_t bad = CountNonFinite(points);
  if (bad > 0) {
    throw PointCloudError(path, std::to_string(bad) + " of " + std::to_string(points.size()) +
                                    " points have non-finite (NaN or infinite) coordinates");
  }
}

/// Reads one coordinate field of point i, stored as float or double.
double ReadCoordinate(const pcl::PCLPointCloud2& blob, const pcl::PCLPointField& field,
                      std::size_t i) {
  const std::uint8_t* at = blob.data.data() + i * blob.point_step + field.offset;
  if (field.datatype == pcl::PCLPointField::FLOAT64) {
    double value = 0.0;
    std::memcpy(&value, at, sizeof value);
    return value;
  }
  float value = 0.0F;
  std::memcpy(&value, at, sizeof value);
  return static_cast<double>(value);
}

const pcl::PCLPointField& RequireCoordinateField(const pcl::PCLPointCloud2& blob,
                                                 std::string_view name,
                                                 const std::filesystem::path& path) {
  const auto it = std::find_if(blob.fields.begin(), blob.fields.end(),
                               [&](const pcl::PCLPointField& f) { return f.name == name; });
  if (it == blob.fields.end()) {
    throw PointCloudError(path, "no '" + std::string(name) + "' field");
  }
  if (it->datatype != pcl::PCLPointField::FLOAT32 && it->datatype != pcl::PCLPointField::FLOAT64) {
    throw PointCloudError(path, "field '" + std::string(name) + "' is not float or double");
  }
  const std::size_t size = it->datatype == pcl::PCLPointField::FLOAT64 ? 8 : 4;
  if (it->offset + size > blob.point_step) {
    throw PointCloudError(path, "field '" + std::string(name) + "' lies outside the point record");
  }
  return *it;
}

std::vector<Eigen::Vector3d> ExtractPoints(const pcl::PCLPointCloud2& blob,
                                           const std::filesystem::path& path) {
  const pcl::PCLPointField& fx = RequireCoordinateField(blob, "x", path);
  const pcl::PCLPointField& fy = RequireCoordinateField(blob, "y", path);
  const pcl::PCLPointField& fz = RequireCoordinateField(blob, "z", path);
  const std::size_t count = std::size_t{blob.width} * std::size_t{blob.height};
  if (blob.data.size() < count * blob.point_step) {
    throw PointCloudError(path, "PCL returned less data than the point count announces");
  }
  std::vector<Eigen::Vector3d> points;
  points.reserve(count);
  for (std::size_t i = 0; i < count; ++i) {
    points.emplace_back(ReadCoordinate(blob, fx, i), ReadCoordinate(blob, fy, i),
                        ReadCoordinate(blob, fz, i));
  }
  return points;
}

constexpr const char* kNoPoints = "the file holds no points";

/// PCL refused a file whose header passed CheckPcdFile / CheckPlyFile: its own message (printed by
/// PCL on stderr just before) has the detail; ours says which call and what was checked.
[[noreturn]] void ThrowParseFailure(const std::filesystem::path& path, const char* call, int status) {
  throw PointCloudError(path, std::string(call) + " refused the body of the file (status " + std::to_string(status) +
                                  "; the header's sizes were consistent with the file, see PCL's message above)");
}

/// PLY through pcl::io::loadPLYFile into a PolygonMesh: unlike the PCLPointCloud2 overload, it
/// accepts files that also carry faces (meshes), whose vertices are then read as the points.
pcl::PCLPointCloud2 LoadPly(const std::filesystem::path& path) {
  pcl::PolygonMesh mesh;
  int status = -1;
  try {
    status = pcl::io::loadPLYFile(path.string(), mesh);
  } catch (const std::bad_alloc&) {
    throw;  // ReadPointCloud names the point count
  } catch (const std::exception& e) {
    throw PointCloudError(path, std::string("PCL could not parse the file: ") + e.what());
  }
  if (status < 0) ThrowParseFailure(path, "pcl::io::loadPLYFile", status);
  return std::move(mesh.cloud);
}

/// PCD through pcl::io::loadPCDFile, after checking the header with PCDReader::readHeader: PCL
/// 1.13 only warns about a header without points or fields and then crashes reading the body
/// (segmentation fault on garbage input), and without a DATA line it silently reads the header
/// text as points, so such files are rejected first.
pcl::PCLPointCloud2 LoadPcd(const std::filesystem::path& path) {
  try {
    pcl::PCDReader reader;
    pcl::PCLPointCloud2 header;
    Eigen::Vector4f origin;
    Eigen::Quaternionf orientation;
    int version = 0;
    int data_type = 0;          // 0 ascii, 1 binary, 2 binary_compressed
    unsigned int data_index = 0;  // offset of the body: 0 if the header has no DATA line
    const int status =
        reader.readHeader(path.string(), header, origin, orientation, version, data_type, data_index);
    if (status < 0) ThrowParseFailure(path, "pcl::PCDReader::readHeader", status);
    // Without a DATA line PCL reads the header text itself as ASCII points (all zeros).
    if (data_index == 0) throw PointCloudError(path, "PCD header has no DATA line");
    for (const char* axis : {"x", "y", "z"}) RequireCoordinateField(header, axis, path);
    if (std::size_t{header.width} * std::size_t{header.height} == 0) {
      throw PointCloudError(path, kNoPoints);
    }
    pcl::PCLPointCloud2 blob;
    const int read_status = pcl::io::loadPCDFile(path.string(), blob);
    if (read_status < 0) ThrowParseFailure(path, "pcl::io::loadPCDFile", read_status);
    return blob;
  } catch (const PointCloudError&) {
    throw;
  } catch (const std::bad_alloc&) {
    throw;  // ReadPointCloud names the point count
  } catch (const std::exception& e) {
    throw PointCloudError(path, std::string("PCL could not parse the file: ") + e.what());
  }
}

pcl::PCLPointCloud2 ToBlob(const std::vector<Eigen::Vector3d>& points) {
  pcl::PCLPointCloud2 blob;
  constexpr std::uint32_t kCoordinateBytes = sizeof(double);
  const char* names[3] = {"x", "y", "z"};
  for (std::uint32_t axis = 0; axis < 3; ++axis) {
    pcl::PCLPointField field;
    field.name = names[axis];
    field.offset = axis * kCoordinateBytes;
    field.datatype = pcl::PCLPointField::FLOAT64;
    field.count = 1;
    blob.fields.push_back(field);
  }
  blob.point_step = 3 * kCoordinateBytes;
  blob.width = static_cast<std::uint32_t>(points.size());
  blob.height = 1;
  blob.row_step = blob.point_step * blob.width;
  blob.is_bigendian = false;
  blob.is_dense = true;
  blob.data.resize(std::size_t{blob.row_step});
  for (std::size_t i = 0; i < points.size(); ++i) {
    std::memcpy(blob.data.data() + i * blob.point_step, points[i].data(), blob.point_step);
  }
  return blob;
}

}  // namespace

PointCloudError::PointCloudError(const std::filesystem::path& path, const std::string& reason)
    : std::runtime_error("point cloud '" + path.string() + "': " + reason),
      path_(path),
      reason_(reason) {}

PointCloud ReadPointCloud(const std::filesystem::path& path) {
  if (IsLasPath(path)) return ReadLasPointCloud(path);  // LAS/LAZ: las_file.cpp, without PCL
  const CloudFormat format = RequireFormat(path);
  std::error_code ec;
  if (!std::filesystem::exists(path, ec)) throw PointCloudError(path, "no such file");
  if (!std::filesystem::is_regular_file(path, ec)) throw PointCloudError(path, "not a regular file");

  // The header's claims are checked against the file before PCL sizes its buffers from them.
  std::ifstream in(path, std::ios::binary);
  if (!in) throw PointCloudError(path, std::string("cannot open: ") + std::strerror(errno));
  const PointCloudFileSummary summary = format == CloudFormat::kPly ? CheckPlyFile(in, path) : CheckPcdFile(in, path);
  in.close();
  pcl::PCLPointCloud2 blob;
  try {
    blob = format == CloudFormat::kPly ? LoadPly(path) : LoadPcd(path);
  } catch (const std::bad_alloc&) {
    throw PointCloudError(path, "not enough memory to read " + std::to_string(summary.points) + " points");
  }
  PointCloud cloud{ExtractPoints(blob, path)};
  if (cloud.points_m.empty()) throw PointCloudError(path, kNoPoints);
  RejectNonFinite(cloud.points_m, path);
  return cloud;
}

std::size_t ForEachPointChunk(const std::filesystem::path& path, std::size_t chunk_points,
                              const std::function<void(const std::vector<Eigen::Vector3d>&)>& visit) {
  if (chunk_points == 0) throw std::invalid_argument("ForEachPointChunk: chunk_points must be positive");
  if (IsLasPath(path)) {
    return static_cast<std::size_t>(ForEachLasFileChunk(path, chunk_points, [&visit](const LasCloud& chunk) {
      // Finite by construction (the header's scale and offset are checked for overflow).
      visit(chunk.points_m);
    }));
  }
  PointCloud cloud = ReadPointCloud(path);
  std::vector<Eigen::Vector3d> chunk;
  for (std::size_t first = 0; first < cloud.points_m.size(); first += chunk_points) {
    const auto begin = cloud.points_m.begin() + static_cast<std::ptrdiff_t>(first);
    const auto end = cloud.points_m.begin() + static_cast<std::ptrdiff_t>(std::min(cloud.points_m.size(), first + chunk_points));
    chunk.assign(begin, end);
    visit(chunk);
  }
  return cloud.points_m.size();
}

namespace {

/// Runs `write` (PCL, returning its status) on a temporary next to `path`, renamed over it on
/// success (mapio::OutputFile); every failure is a PointCloudError naming `path`.
void WriteThroughTemporary(const std::filesystem::path& path, const std::function<int(const std::string&)>& write) {
  std::optional<mapio::OutputFile> file;
  try {
    file.emplace(path);
  } catch (const mapio::OutputFileError& e) {
    throw PointCloudError(path, e.what());
  }
  int status = -1;
  try {
    status = write(file->temporary_path().string());
  } catch (const std::exception& e) {
    throw PointCloudError(path, std::string("PCL could not write the file: ") + e.what());
  }
  if (status < 0) {
    throw PointCloudError(path, "PCL could not write the file (status " + std::to_string(status) + ")");
  }
  try {
    file->Commit();
  } catch (const mapio::OutputFileError& e) {
    throw PointCloudError(path, e.what());
  }
}

}  // namespace

void WritePointCloud(const PointCloud& cloud, const std::filesystem::path& path) {
  const CloudFormat format = RequireFormat(path);
  if (cloud.points_m.empty()) throw PointCloudError(path, "refusing to write an empty cloud");
  RejectNonFinite(cloud.points_m, path);
  if (cloud.points_m.size() > std::size_t{UINT32_MAX} / (3 * sizeof(double))) {
    throw PointCloudError(path, "too many points for one PCL cloud");
  }
  const pcl::PCLPointCloud2 blob = ToBlob(cloud.points_m);
  WriteThroughTemporary(path, [&](const std::string& temporary) {
    if (format == CloudFormat::kPly) {
      pcl::PLYWriter writer;
      return writer.writeBinary(temporary, blob, Eigen::Vector4f::Zero(), Eigen::Quaternionf::Identity(),
                                /*use_camera=*/false);
    }
    pcl::PCDWriter writer;
    return writer.writeBinary(temporary, blob);
  });
}

void WriteTriangleMeshPly(const std::vector<Eigen::Vector3d>& vertices_m,
                          const std::vector<std::array<int, 3>>& triangles, const std::filesystem::path& path) {
  if (RequireFormat(path) != CloudFormat::kPly) throw PointCloudError(path, "a mesh is written as .ply only");
  if (vertices_m.empty() || triangles.empty()) throw PointCloudError(path, "refusing to write an empty mesh");
  RejectNonFinite(vertices_m, path);
  if (vertices_m.size() > std::size_t{UINT32_MAX} / (3 * sizeof(double))) {
    throw PointCloudError(path, "too many vertices for one PCL mesh");
  }
  // PCL's mesh writer takes float x, y, z only: fine in the map's local frame (1 mm up to 16 km).
  pcl::PointCloud<pcl::PointXYZ> vertices;
  for (const auto& v : vertices_m) {
    vertices.push_back(pcl::PointXYZ(static_cast<float>(v.x()), static_cast<float>(v.y()), static_cast<float>(v.z())));
  }
  pcl::PolygonMesh mesh;
  pcl::toPCLPointCloud2(vertices, mesh.cloud);
  mesh.polygons.reserve(triangles.size());
  for (const auto& t : triangles) {
    for (const int v : t) {
      if (v < 0 || static_cast<std::size_t>(v) >= vertices_m.size()) {
        throw PointCloudError(path, "a triangle refers to vertex " + std::to_string(v) + " of " +
                                        std::to_string(vertices_m.size()));
      }
    }
    pcl::Vertices face;
    face.vertices = {static_cast<pcl::index_t>(t[0]), static_cast<pcl::index_t>(t[1]), static_cast<pcl::index_t>(t[2])};
    mesh.polygons.push_back(std::move(face));
  }
  WriteThroughTemporary(path, [&](const std::string& temporary) { return pcl::io::savePLYFileBinary(temporary, mesh); });
}

}  // namespace rowloc::mapping
