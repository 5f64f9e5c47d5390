// LAS point cloud files (ASPRS 2019, LAS Specification 1.4 R15): a small reader of uncompressed
// LAS 1.0-1.4 and a writer, without a third-party library (no Debian package reads LAS).
//
// Read: the public header block (signature "LASF", version, header size, offset to the point data,
// point data record format 0-10 and record length, the legacy 32-bit and the LAS 1.4 64-bit point
// counts, scale and offset per axis in double, the bounding box), then per point record X, Y, Z
// (int32) as x = X * scale_x + offset_x in double, the intensity and the classification. Variable
// length records, extended VLRs, waveform packets and every other point field are skipped; a record
// longer than its format's size (extra bytes) is allowed and its tail skipped. Coordinates stay in
// double, so a projected CRS (eastings ~5e5 m, northings ~5e6 m) keeps the file's resolution: float
// would round northings to 0.5 m.
//
// Refused with PointCloudError (the message names the file, and the byte offset or field):
//   - LAZ (compressed LAS): the extension .laz, or bit 7 (LASzip) or bit 6 (early LASzip) of the
//     point data record format byte set; the message names `laszip` and `pdal translate`;
//   - a signature other than "LASF", a version other than 1.0-1.4, a header size below the
//     version's public header block (227, 235 or 375 bytes) or beyond the file;
//   - a point data record format above 10, a record length below the format's size;
//   - a point count whose records the file cannot hold (checked against the file's size before
//     anything is allocated: memory is bounded by the file, never by the header's claim), a
//     legacy count that contradicts the 64-bit one, a file that ends inside the point records;
//   - a scale that is zero or not finite, an offset that is not finite, or a scale and offset whose
//     int32 range overflows double.
// Point formats 4, 5, 9 and 10 are read (their XYZ); the waveform packets they point to are not.
//
// Write: LAS 1.2, 1.3 or 1.4, point data record formats 0-10 (X, Y, Z, intensity, classification,
// one return per pulse; every other field zero; no VLR, so no CRS record), optional zero extra bytes
// per record, through mapio::OutputFile (a temporary renamed over the target on success).
#pragma once

#include "rowloc/mapping/point_cloud.hpp"

#include <Eigen/Core>

#include <array>
#include <cstdint>
#include <filesystem>
#include <functional>
#include <istream>
#include <optional>
#include <string>
#include <vector>

namespace rowloc::mapping {

/// Sizes of the public header block per LAS 1.x minor version (1.0-1.2, 1.3, 1.4).
inline constexpr std::uint16_t kLasHeaderSize12 = 227;
inline constexpr std::uint16_t kLasHeaderSize13 = 235;
inline constexpr std::uint16_t kLasHeaderSize14 = 375;
inline constexpr int kLasMaxPointFormat = 10;

/// The size in bytes of a point record of format 0-10 (ASPRS 2019, LAS Specification 1.4 R15):
/// 20, 28, 26, 34, 57, 63, 30, 36, 38, 59, 67. Throws std::invalid_argument outside 0-10.
std::uint16_t LasPointFormatSize(int point_format);

/// The public header block, as read (or as written).
struct LasHeader {
  int version_major = 1;
  int version_minor = 4;
  std::uint16_t file_source_id = 0;
  std::uint16_t global_encoding = 0;
  std::string system_identifier;    ///< trailing NULs removed
  std::string generating_software;  ///< trailing NULs removed
  std::uint16_t header_size = kLasHeaderSize14;
  std::uint32_t offset_to_point_data = kLasHeaderSize14;
  std::uint32_t number_of_vlrs = 0;
  int point_format = 6;                    ///< 0-10 (compression bits refused)
  std::uint16_t point_record_length = 30;  ///< >= LasPointFormatSize(point_format)
  std::uint32_t legacy_point_count = 0;    ///< byte 107
  std::uint64_t point_count = 0;           ///< the records read: LAS 1.4's 64-bit count, else legacy
  Eigen::Vector3d scale = Eigen::Vector3d::Constant(0.001);
  Eigen::Vector3d offset = Eigen::Vector3d::Zero();
  Eigen::Vector3d min = Eigen::Vector3d::Zero();  ///< as the header states it (not checked)
  Eigen::Vector3d max = Eigen::Vector3d::Zero();  ///< as the header states it (not checked)

  /// Bytes of each record after the format's fields (point_record_length - format size).
  std::uint16_t extra_bytes() const;
};

/// The points of a LAS file, in the file's coordinates (metres of its CRS), in double.
struct LasCloud {
  LasHeader header;
  std::vector<Eigen::Vector3d> points_m;     ///< x = X * scale_x + offset_x, ...
  std::vector<std::uint16_t> intensity;       ///< one per point
  std::vector<std::uint8_t> classification;   ///< one per point (formats 0-5: the low 5 bits)
};

/// True if the extension is .las or .laz (case-insensitive): ReadPointCloud reads such files here.
bool IsLasPath(const std::filesystem::path& path);

/// The refusal of a compressed file, naming the conversion: "LAZ (compressed LAS) is not read:
/// convert it with `laszip -i F.laz -o F.las` or `pdal translate F.laz F.las`" with the file's names.
std::string LazRefusal(const std::filesystem::path& path);

/// Reads and checks the public header block from `in` (at its start) against the stream's size.
/// `name` is used in messages only. Throws PointCloudError.
LasHeader ReadLasHeader(std::istream& in, const std::filesystem::path& name);

/// Reads the point records of `in` (whose header `header` was read by ReadLasHeader) in chunks of
/// at most `chunk_points` points, calling `visit` with each (its header is `header`); memory is one
/// chunk, whatever the file's size. Throws PointCloudError on a truncated file (after the chunks
/// before it were visited) and std::invalid_argument if chunk_points is 0.
void ForEachLasChunk(std::istream& in, const LasHeader& header, const std::filesystem::path& name,
                     std::size_t chunk_points, const std::function<void(const LasCloud&)>& visit);

/// Reads a whole LAS file from `in` (at its start). Throws PointCloudError (a file of zero points
/// is returned, not refused: ReadLasPointCloud refuses it).
LasCloud ReadLas(std::istream& in, const std::filesystem::path& name);

/// Reads a LAS file; .laz is refused by name before it is opened. Throws PointCloudError.
LasCloud ReadLasFile(const std::filesystem::path& path);

/// ReadLasFile in chunks (ForEachLasChunk): memory is one chunk. Returns the number of points.
/// Throws PointCloudError as ReadLasFile, and for a file of zero points.
std::uint64_t ForEachLasFileChunk(const std::filesystem::path& path, std::size_t chunk_points,
                                  const std::function<void(const LasCloud&)>& visit);

/// ReadPointCloud's LAS branch: ReadLasFile's points, refusing a missing or non-regular file, a file
/// without points and non-finite points with the messages of ReadPointCloud.
PointCloud ReadLasPointCloud(const std::filesystem::path& path);

/// How WriteLasFile writes.
struct LasWriteOptions {
  int version_minor = 4;  ///< LAS 1.2, 1.3 or 1.4
  int point_format = 6;   ///< 0-10; 4 and 5 need 1.3 or later, 6-10 need 1.4
  Eigen::Vector3d scale = Eigen::Vector3d::Constant(0.001);  ///< metres per count, > 0
  std::optional<Eigen::Vector3d> offset = std::nullopt;  ///< default: per axis the floor of the minimum coordinate
  std::uint16_t extra_bytes = 0;          ///< zero bytes appended to every record
};

/// The bytes of a LAS file holding `cloud`'s points (header ignored; intensity and classification
/// empty or one per point). Each coordinate is rounded to the nearest multiple of the scale from the
/// offset. Throws std::invalid_argument for an unsupported version/format pair, a bad scale or
/// offset, non-finite points, a coordinate whose count does not fit int32, mismatched sizes, or a
/// record longer than 65535 bytes.
std::string EncodeLas(const LasCloud& cloud, const LasWriteOptions& options = {});

/// Writes EncodeLas(cloud, options) to `path` through mapio::OutputFile. Throws PointCloudError
/// (with the reason of EncodeLas or of the write).
void WriteLasFile(const LasCloud& cloud, const std::filesystem::path& path, const LasWriteOptions& options = {});

}  // namespace rowloc::mapping
