// LAS reading and writing (see las_file.hpp). Byte offsets and field names follow the public header
// block of ASPRS 2019, LAS Specification 1.4 R15 (LAS 1.0-1.2 end at byte 227, 1.3 adds
// the waveform start at 227, 1.4 the EVLRs and 64-bit counts up to byte 375). All values are little
// endian; they are assembled byte by byte, so the code does not depend on the host's byte order.
#include "rowloc/mapping/las_file.hpp"

#include "rowloc/mapio/output_file.hpp"

#include <algorithm>
#include <array>
#include <bit>
#include <cctype>
#include <cerrno>
#include <cmath>
#include <charconv>
#include <cstring>
#include <fstream>
#include <limits>
#include <new>
#include <stdexcept>
#include <string_view>

namespace rowloc::mapping {
namespace {

// Public header block fields (byte offsets).
constexpr std::size_t kSignatureAt = 0;
constexpr std::size_t kFileSourceIdAt = 4;
constexpr std::size_t kGlobalEncodingAt = 6;
constexpr std::size_t kVersionMajorAt = 24;
constexpr std::size_t kVersionMinorAt = 25;
constexpr std::size_t kSystemIdentifierAt = 26;
constexpr std::size_t kGeneratingSoftwareAt = 58;
constexpr std::size_t kHeaderSizeAt = 94;
constexpr std::size_t kOffsetToPointDataAt = 96;
constexpr std::size_t kNumberOfVlrsAt = 100;
constexpr std::size_t kPointFormatAt = 104;
constexpr std::size_t kPointRecordLengthAt = 105;
constexpr std::size_t kLegacyPointCountAt = 107;
constexpr std::size_t kLegacyPointsByReturnAt = 111;
constexpr std::size_t kScaleAt = 131;   // x, y, z
constexpr std::size_t kOffsetAt = 155;  // x, y, z
constexpr std::size_t kMaxXAt = 179;    // then min x, max y, min y, max z, min z
constexpr std::size_t kPointCountAt = 247;  // LAS 1.4: 64-bit number of point records
constexpr std::size_t kPointsByReturnAt = 255;

constexpr std::array<std::uint16_t, 11> kPointFormatSizes = {20, 28, 26, 34, 57, 63, 30, 36, 38, 59, 67};
constexpr std::array<char, 3> kAxes = {'x', 'y', 'z'};
constexpr std::uint8_t kLaszipBit = 0x80;             // LASzip sets bit 7 of the format byte
constexpr std::uint8_t kEarlyLaszipBit = 0x40;        // experimental LASzip versions set bit 6
constexpr std::uint16_t kWktGlobalEncodingBit = 0x10;  // required with point formats 6-10

std::uint16_t U16(const unsigned char* p) { return static_cast<std::uint16_t>(p[0] | (p[1] << 8)); }
std::uint32_t U32(const unsigned char* p) {
  return static_cast<std::uint32_t>(p[0]) | (static_cast<std::uint32_t>(p[1]) << 8) |
         (static_cast<std::uint32_t>(p[2]) << 16) | (static_cast<std::uint32_t>(p[3]) << 24);
}
std::uint64_t U64(const unsigned char* p) {
  return static_cast<std::uint64_t>(U32(p)) | (static_cast<std::uint64_t>(U32(p + 4)) << 32);
}
std::int32_t I32(const unsigned char* p) { return static_cast<std::int32_t>(U32(p)); }
double F64(const unsigned char* p) { return std::bit_cast<double>(U64(p)); }

void PutU16(std::string& out, std::size_t at, std::uint16_t v) {
  for (std::size_t i = 0; i < 2; ++i) out[at + i] = static_cast<char>((v >> (8 * i)) & 0xFF);
}
void PutU32(std::string& out, std::size_t at, std::uint32_t v) {
  for (std::size_t i = 0; i < 4; ++i) out[at + i] = static_cast<char>((v >> (8 * i)) & 0xFF);
}
void PutU64(std::string& out, std::size_t at, std::uint64_t v) {
  for (std::size_t i = 0; i < 8; ++i) out[at + i] = static_cast<char>((v >> (8 * i)) & 0xFF);
}
void PutF64(std::string& out, std::size_t at, double v) { PutU64(out, at, std::bit_cast<std::uint64_t>(v)); }
void PutText(std::string& out, std::size_t at, std::size_t width, std::string_view text) {
  std::copy_n(text.begin(), std::min(width, text.size()), out.begin() + static_cast<std::ptrdiff_t>(at));
}

std::string Lower(std::string s) {
  std::transform(s.begin(), s.end(), s.begin(), [](unsigned char c) { return static_cast<char>(std::tolower(c)); });
  return s;
}

/// Bytes shown in a message: printable ASCII as is, the rest as \xNN.
std::string Printable(const unsigned char* p, std::size_t n) {
  std::string s;
  for (std::size_t i = 0; i < n; ++i) {
    if (p[i] >= 0x20 && p[i] < 0x7F && p[i] != '"' && p[i] != '\\') {
      s.push_back(static_cast<char>(p[i]));
    } else {
      constexpr const char* kHex = "0123456789abcdef";
      s += "\\x";
      s.push_back(kHex[p[i] >> 4]);
      s.push_back(kHex[p[i] & 0xF]);
    }
  }
  return s;
}

std::string FixedText(const unsigned char* p, std::size_t width) {
  std::size_t n = 0;
  while (n < width && p[n] != 0) ++n;
  return std::string(reinterpret_cast<const char*>(p), n);
}

/// The shortest text that reads back as `v`: "0.001", "500000", "1e+300", "nan", "-inf".
std::string Number(double v) {
  char buffer[64];
  const double magnitude = std::abs(v);
  const bool fixed = magnitude == 0.0 || (magnitude >= 1e-6 && magnitude < 1e16);
  const std::to_chars_result r = fixed ? std::to_chars(buffer, buffer + sizeof buffer, v, std::chars_format::fixed)
                                       : std::to_chars(buffer, buffer + sizeof buffer, v);
  return std::string(buffer, r.ptr);
}

std::uint16_t MinimumHeaderSize(int version_minor) {
  if (version_minor >= 4) return kLasHeaderSize14;
  if (version_minor == 3) return kLasHeaderSize13;
  return kLasHeaderSize12;
}

std::uint64_t StreamSize(std::istream& in, const std::filesystem::path& name) {
  in.seekg(0, std::ios::end);
  const std::streamoff end = in.tellg();
  in.seekg(0, std::ios::beg);
  if (!in || end < 0) throw PointCloudError(name, "cannot determine the size of the file");
  return static_cast<std::uint64_t>(end);
}

}  // namespace

std::uint16_t LasPointFormatSize(int point_format) {
  if (point_format < 0 || point_format > kLasMaxPointFormat) {
    throw std::invalid_argument("LAS point data record format " + std::to_string(point_format) +
                                " does not exist (0-10)");
  }
  return kPointFormatSizes[static_cast<std::size_t>(point_format)];
}

std::uint16_t LasHeader::extra_bytes() const {
  return static_cast<std::uint16_t>(point_record_length - LasPointFormatSize(point_format));
}

bool IsLasPath(const std::filesystem::path& path) {
  const std::string ext = Lower(path.extension().string());
  return ext == ".las" || ext == ".laz";
}

std::string LazRefusal(const std::filesystem::path& path) {
  std::filesystem::path out = path;
  out.replace_extension(".las");
  if (out == path) out = path.parent_path() / (path.stem().string() + "-decompressed.las");
  const std::string in = path.string();
  return "LAZ (compressed LAS) is not read: convert it with `laszip -i " + in + " -o " + out.string() +
         "` or `pdal translate " + in + " " + out.string() + "`";
}

LasHeader ReadLasHeader(std::istream& in, const std::filesystem::path& name) {
  const auto fail = [&name](const std::string& reason) { throw PointCloudError(name, reason); };
  const std::uint64_t size = StreamSize(in, name);
  std::array<unsigned char, kLasHeaderSize14> b{};
  in.read(reinterpret_cast<char*>(b.data()),
          static_cast<std::streamsize>(std::min<std::uint64_t>(size, b.size())));
  const auto have = static_cast<std::size_t>(in.gcount());  // less than the size if the file shrank

  if (have < 4 || std::memcmp(b.data() + kSignatureAt, "LASF", 4) != 0) {
    fail("not a LAS file: the signature (bytes 0-3) is \"" + Printable(b.data(), std::min<std::size_t>(have, 4)) +
         "\", expected \"LASF\"");
  }
  if (have < kLasHeaderSize12) {
    fail("truncated: the file ends at byte " + std::to_string(have) + ", inside the public header block (" +
         std::to_string(kLasHeaderSize12) + " bytes at least)");
  }
  const std::uint8_t format_byte = b[kPointFormatAt];
  if ((format_byte & (kLaszipBit | kEarlyLaszipBit)) != 0) {
    fail(LazRefusal(name) + " (the point data record format byte 104 is " + std::to_string(format_byte) + ": bit " +
         ((format_byte & kLaszipBit) != 0 ? "7" : "6") + ", LASzip compression, is set)");
  }

  LasHeader h;
  h.version_major = b[kVersionMajorAt];
  h.version_minor = b[kVersionMinorAt];
  if (h.version_major != 1 || h.version_minor > 4) {
    fail("LAS version " + std::to_string(h.version_major) + "." + std::to_string(h.version_minor) +
         " (bytes 24-25) is not read: LAS 1.0 to 1.4 are");
  }
  h.file_source_id = U16(b.data() + kFileSourceIdAt);
  h.global_encoding = U16(b.data() + kGlobalEncodingAt);
  h.system_identifier = FixedText(b.data() + kSystemIdentifierAt, 32);
  h.generating_software = FixedText(b.data() + kGeneratingSoftwareAt, 32);
  h.header_size = U16(b.data() + kHeaderSizeAt);
  const std::uint16_t minimum_header = MinimumHeaderSize(h.version_minor);
  const std::string version = "LAS 1." + std::to_string(h.version_minor);
  if (h.header_size < minimum_header) {
    fail("header size " + std::to_string(h.header_size) + " (byte 94) is smaller than the " +
         std::to_string(minimum_header) + "-byte public header block of " + version);
  }
  if (h.header_size > have) {
    fail("truncated: the header size " + std::to_string(h.header_size) + " (byte 94) runs past the end of the file (" +
         std::to_string(size) + " bytes)");
  }
  h.offset_to_point_data = U32(b.data() + kOffsetToPointDataAt);
  if (h.offset_to_point_data < h.header_size) {
    fail("offset to point data " + std::to_string(h.offset_to_point_data) + " (byte 96) lies inside the " +
         std::to_string(h.header_size) + "-byte header");
  }
  if (h.offset_to_point_data > size) {
    fail("truncated: the offset to point data " + std::to_string(h.offset_to_point_data) +
         " (byte 96) lies past the end of the file (" + std::to_string(size) + " bytes)");
  }
  h.number_of_vlrs = U32(b.data() + kNumberOfVlrsAt);
  h.point_format = format_byte;
  if (h.point_format > kLasMaxPointFormat) {
    fail("point data record format " + std::to_string(h.point_format) + " (byte 104) is not a LAS format (0-10)");
  }
  h.point_record_length = U16(b.data() + kPointRecordLengthAt);
  const std::uint16_t format_size = LasPointFormatSize(h.point_format);
  if (h.point_record_length < format_size) {
    fail("point data record length " + std::to_string(h.point_record_length) + " (byte 105) is smaller than the " +
         std::to_string(format_size) + " bytes of point format " + std::to_string(h.point_format));
  }
  h.legacy_point_count = U32(b.data() + kLegacyPointCountAt);
  h.point_count = h.legacy_point_count;
  std::size_t count_at = kLegacyPointCountAt;
  if (h.version_minor >= 4) {
    const std::uint64_t count = U64(b.data() + kPointCountAt);
    if (count != 0 && h.legacy_point_count != 0 && count != h.legacy_point_count) {
      fail("the legacy point count " + std::to_string(h.legacy_point_count) + " (byte 107) contradicts the point count " +
           std::to_string(count) + " (byte 247)");
    }
    if (count != 0) {
      h.point_count = count;
      count_at = kPointCountAt;
    }
  }
  // Memory is bounded by the file: the records must lie in it before anything is sized from the count.
  const std::uint64_t available = size - h.offset_to_point_data;
  if (h.point_count > available / h.point_record_length) {
    fail("the header announces " + std::to_string(h.point_count) + " points of " +
         std::to_string(h.point_record_length) + " bytes from byte " + std::to_string(h.offset_to_point_data) +
         " (point count, byte " + std::to_string(count_at) +
         "), but the file holds " + std::to_string(available) + " bytes there: truncated, or a wrong count");
  }
  for (std::size_t axis = 0; axis < 3; ++axis) {
    h.scale[static_cast<Eigen::Index>(axis)] = F64(b.data() + kScaleAt + 8 * axis);
    h.offset[static_cast<Eigen::Index>(axis)] = F64(b.data() + kOffsetAt + 8 * axis);
    h.max[static_cast<Eigen::Index>(axis)] = F64(b.data() + kMaxXAt + 16 * axis);
    h.min[static_cast<Eigen::Index>(axis)] = F64(b.data() + kMaxXAt + 16 * axis + 8);
  }
  for (std::size_t axis = 0; axis < 3; ++axis) {
    const double scale = h.scale[static_cast<Eigen::Index>(axis)];
    const double offset = h.offset[static_cast<Eigen::Index>(axis)];
    const std::string axis_name(1, kAxes[axis]);
    if (!std::isfinite(scale) || scale == 0.0) {
      fail(axis_name + " scale factor " + Number(scale) + " (byte " + std::to_string(kScaleAt + 8 * axis) +
           ") must be finite and non-zero");
    }
    if (!std::isfinite(offset)) {
      fail(axis_name + " offset " + Number(offset) + " (byte " + std::to_string(kOffsetAt + 8 * axis) +
           ") must be finite");
    }
    if (!std::isfinite(std::abs(scale) * 2147483648.0 + std::abs(offset))) {
      fail(axis_name + " scale factor " + Number(scale) + " and offset " + Number(offset) + " (bytes " +
           std::to_string(kScaleAt + 8 * axis) + ", " + std::to_string(kOffsetAt + 8 * axis) +
           ") overflow double over the int32 range of the coordinates");
    }
  }
  return h;
}

namespace {

/// Room for `count` points, or a PointCloudError instead of std::bad_alloc.
void Reserve(LasCloud& cloud, std::size_t count, const std::filesystem::path& name) {
  try {
    cloud.points_m.reserve(count);
    cloud.intensity.reserve(count);
    cloud.classification.reserve(count);
  } catch (const std::bad_alloc&) {
    throw PointCloudError(name, "not enough memory to read " + std::to_string(count) + " points");
  } catch (const std::length_error&) {
    throw PointCloudError(name, "not enough memory to read " + std::to_string(count) + " points");
  }
}

}  // namespace

void ForEachLasChunk(std::istream& in, const LasHeader& header, const std::filesystem::path& name,
                     std::size_t chunk_points, const std::function<void(const LasCloud&)>& visit) {
  if (chunk_points == 0) throw std::invalid_argument("ForEachLasChunk: chunk_points must be positive");
  const LasHeader& h = header;
  const std::size_t count = static_cast<std::size_t>(h.point_count);
  LasCloud chunk;
  chunk.header = header;
  Reserve(chunk, std::min(count, chunk_points), name);
  in.clear();
  in.seekg(static_cast<std::streamoff>(h.offset_to_point_data), std::ios::beg);
  const bool legacy_format = h.point_format < 6;
  const std::size_t record = h.point_record_length;
  const std::size_t per_block = std::max<std::size_t>(1, (std::size_t{1} << 16) / record);
  std::vector<unsigned char> block(per_block * record);
  for (std::size_t first = 0; first < count; first += per_block) {
    const std::size_t n = std::min(per_block, count - first);
    in.read(reinterpret_cast<char*>(block.data()), static_cast<std::streamsize>(n * record));
    const std::size_t got = in ? n * record : static_cast<std::size_t>(in.gcount());
    if (got != n * record) {
      const std::uint64_t at = h.offset_to_point_data + std::uint64_t{first} * record + got;
      throw PointCloudError(name, "truncated: the file ends at byte " + std::to_string(at) + ", inside point record " +
                                      std::to_string(first + got / record) + " of " + std::to_string(count));
    }
    for (std::size_t i = 0; i < n; ++i) {
      const unsigned char* p = block.data() + i * record;
      chunk.points_m.emplace_back(static_cast<double>(I32(p)) * h.scale.x() + h.offset.x(),
                                  static_cast<double>(I32(p + 4)) * h.scale.y() + h.offset.y(),
                                  static_cast<double>(I32(p + 8)) * h.scale.z() + h.offset.z());
      chunk.intensity.push_back(U16(p + 12));
      chunk.classification.push_back(legacy_format ? static_cast<std::uint8_t>(p[15] & 0x1F) : p[16]);
      if (chunk.points_m.size() == chunk_points) {
        visit(chunk);
        chunk.points_m.clear();
        chunk.intensity.clear();
        chunk.classification.clear();
      }
    }
  }
  if (!chunk.points_m.empty()) visit(chunk);
}

LasCloud ReadLas(std::istream& in, const std::filesystem::path& name) {
  LasCloud cloud;
  cloud.header = ReadLasHeader(in, name);
  Reserve(cloud, static_cast<std::size_t>(cloud.header.point_count), name);
  ForEachLasChunk(in, cloud.header, name, std::size_t{1} << 20, [&cloud](const LasCloud& chunk) {
    cloud.points_m.insert(cloud.points_m.end(), chunk.points_m.begin(), chunk.points_m.end());
    cloud.intensity.insert(cloud.intensity.end(), chunk.intensity.begin(), chunk.intensity.end());
    cloud.classification.insert(cloud.classification.end(), chunk.classification.begin(), chunk.classification.end());
  });
  return cloud;
}

namespace {

std::ifstream OpenLasFile(const std::filesystem::path& path) {
  std::error_code ec;
  if (!std::filesystem::exists(path, ec)) throw PointCloudError(path, "no such file");
  if (!std::filesystem::is_regular_file(path, ec)) throw PointCloudError(path, "not a regular file");
  if (Lower(path.extension().string()) == ".laz") throw PointCloudError(path, LazRefusal(path) + " (the extension is .laz)");
  std::ifstream in(path, std::ios::binary);
  if (!in) throw PointCloudError(path, std::string("cannot open: ") + std::strerror(errno));
  return in;
}

}  // namespace

LasCloud ReadLasFile(const std::filesystem::path& path) {
  std::ifstream in = OpenLasFile(path);
  return ReadLas(in, path);
}

std::uint64_t ForEachLasFileChunk(const std::filesystem::path& path, std::size_t chunk_points,
                                  const std::function<void(const LasCloud&)>& visit) {
  std::ifstream in = OpenLasFile(path);
  const LasHeader header = ReadLasHeader(in, path);
  if (header.point_count == 0) throw PointCloudError(path, "the file holds no points");
  ForEachLasChunk(in, header, path, chunk_points, visit);
  return header.point_count;
}

PointCloud ReadLasPointCloud(const std::filesystem::path& path) {
  LasCloud las = ReadLasFile(path);
  if (las.points_m.empty()) throw PointCloudError(path, "the file holds no points");
  const std::size_t bad = static_cast<std::size_t>(std::count_if(
      las.points_m.begin(), las.points_m.end(), [](const Eigen::Vector3d& p) { return !p.allFinite(); }));
  if (bad > 0) {  // unreachable after the header's overflow check; kept as ReadPointCloud's contract
    throw PointCloudError(path, std::to_string(bad) + " of " + std::to_string(las.points_m.size()) +
                                    " points have non-finite (NaN or infinite) coordinates");
  }
  return PointCloud{std::move(las.points_m)};
}

std::string EncodeLas(const LasCloud& cloud, const LasWriteOptions& options) {
  const auto fail = [](const std::string& reason) { throw std::invalid_argument("LAS writer: " + reason); };
  const int minor = options.version_minor;
  const int format = options.point_format;
  if (minor < 2 || minor > 4) fail("version 1." + std::to_string(minor) + " is not written (1.2, 1.3 or 1.4)");
  if (format < 0 || format > kLasMaxPointFormat) fail("point format " + std::to_string(format) + " does not exist (0-10)");
  if (format >= 6 && minor < 4) fail("point format " + std::to_string(format) + " needs LAS 1.4");
  if (format >= 4 && minor < 3) fail("point format " + std::to_string(format) + " needs LAS 1.3 or later");
  const std::size_t n = cloud.points_m.size();
  if (!cloud.intensity.empty() && cloud.intensity.size() != n) fail("intensity is not one per point");
  if (!cloud.classification.empty() && cloud.classification.size() != n) fail("classification is not one per point");
  if (minor < 4 && n > std::numeric_limits<std::uint32_t>::max()) fail("more than 2^32 - 1 points need LAS 1.4");
  const std::size_t record = std::size_t{LasPointFormatSize(format)} + options.extra_bytes;
  if (record > std::numeric_limits<std::uint16_t>::max()) fail("a record of " + std::to_string(record) + " bytes");
  Eigen::Vector3d lo = Eigen::Vector3d::Zero();
  Eigen::Vector3d hi = Eigen::Vector3d::Zero();
  for (std::size_t i = 0; i < n; ++i) {
    const Eigen::Vector3d& p = cloud.points_m[i];
    if (!p.allFinite()) fail("point " + std::to_string(i) + " is not finite");
    if (i == 0) {
      lo = p;
      hi = p;
    } else {
      lo = lo.cwiseMin(p);
      hi = hi.cwiseMax(p);
    }
  }
  const Eigen::Vector3d offset = options.offset.value_or(Eigen::Vector3d(lo.array().floor()));
  for (Eigen::Index axis = 0; axis < 3; ++axis) {
    if (!std::isfinite(options.scale[axis]) || options.scale[axis] <= 0.0) {
      fail(std::string(1, kAxes[static_cast<std::size_t>(axis)]) + " scale " + Number(options.scale[axis]) +
           " must be finite and positive");
    }
    if (!std::isfinite(offset[axis])) fail(std::string(1, kAxes[static_cast<std::size_t>(axis)]) + " offset is not finite");
  }

  const std::uint16_t header_size = MinimumHeaderSize(minor);
  std::string out(header_size + n * record, '\0');
  Eigen::Vector3d stored_lo = Eigen::Vector3d::Zero();
  Eigen::Vector3d stored_hi = Eigen::Vector3d::Zero();
  for (std::size_t i = 0; i < n; ++i) {
    const std::size_t at = header_size + i * record;
    for (Eigen::Index axis = 0; axis < 3; ++axis) {
      const double counts = std::round((cloud.points_m[i][axis] - offset[axis]) / options.scale[axis]);
      if (!(counts >= std::numeric_limits<std::int32_t>::min() && counts <= std::numeric_limits<std::int32_t>::max())) {
        fail("point " + std::to_string(i) + ": " + kAxes[static_cast<std::size_t>(axis)] + " = " +
             Number(cloud.points_m[i][axis]) + " is " + Number(counts) + " counts of " + Number(options.scale[axis]) +
             " from the offset " + Number(offset[axis]) + ", outside int32");
      }
      const auto value = static_cast<std::int32_t>(counts);
      PutU32(out, at + 4 * static_cast<std::size_t>(axis), static_cast<std::uint32_t>(value));
      const double stored = static_cast<double>(value) * options.scale[axis] + offset[axis];
      stored_lo[axis] = i == 0 ? stored : std::min(stored_lo[axis], stored);
      stored_hi[axis] = i == 0 ? stored : std::max(stored_hi[axis], stored);
    }
    if (!cloud.intensity.empty()) PutU16(out, at + 12, cloud.intensity[i]);
    const std::uint8_t classification = cloud.classification.empty() ? 0 : cloud.classification[i];
    if (format < 6) {
      if (classification > 31) fail("classification " + std::to_string(classification) + " needs point format 6-10");
      out[at + 14] = static_cast<char>(0x09);  // return 1 of 1
      out[at + 15] = static_cast<char>(classification);
    } else {
      out[at + 14] = static_cast<char>(0x11);  // return 1 of 1
      out[at + 16] = static_cast<char>(classification);
    }
  }

  PutText(out, kSignatureAt, 4, "LASF");
  if (format >= 6) PutU16(out, kGlobalEncodingAt, kWktGlobalEncodingBit);
  out[kVersionMajorAt] = 1;
  out[kVersionMinorAt] = static_cast<char>(minor);
  PutText(out, kSystemIdentifierAt, 32, "OTHER");
  PutText(out, kGeneratingSoftwareAt, 32, "rowloc");
  PutU16(out, kHeaderSizeAt, header_size);
  PutU32(out, kOffsetToPointDataAt, header_size);
  out[kPointFormatAt] = static_cast<char>(format);
  PutU16(out, kPointRecordLengthAt, static_cast<std::uint16_t>(record));
  // LAS 1.4: the legacy count is 0 for formats 6-10 and for more than 2^32 - 1 points.
  const bool legacy = minor < 4 || (format < 6 && n <= std::numeric_limits<std::uint32_t>::max());
  const auto legacy_count = static_cast<std::uint32_t>(legacy ? n : 0);
  PutU32(out, kLegacyPointCountAt, legacy_count);
  PutU32(out, kLegacyPointsByReturnAt, legacy_count);  // every point is return 1 of 1
  for (Eigen::Index axis = 0; axis < 3; ++axis) {
    const auto a = static_cast<std::size_t>(axis);
    PutF64(out, kScaleAt + 8 * a, options.scale[axis]);
    PutF64(out, kOffsetAt + 8 * a, offset[axis]);
    PutF64(out, kMaxXAt + 16 * a, stored_hi[axis]);
    PutF64(out, kMaxXAt + 16 * a + 8, stored_lo[axis]);
  }
  if (minor >= 4) {
    PutU64(out, kPointCountAt, n);
    PutU64(out, kPointsByReturnAt, n);
  }
  return out;
}

void WriteLasFile(const LasCloud& cloud, const std::filesystem::path& path, const LasWriteOptions& options) {
  std::string bytes;
  try {
    bytes = EncodeLas(cloud, options);
  } catch (const std::invalid_argument& e) {
    throw PointCloudError(path, e.what());
  }
  try {
    mapio::WriteFileAtomically(path, bytes);
  } catch (const mapio::OutputFileError& e) {
    throw PointCloudError(path, e.what());
  }
}

}  // namespace rowloc::mapping
