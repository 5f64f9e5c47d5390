// Checks of a PLY or PCD file's header against what the file really holds, before PCL reads it.
//
// PCL (1.13) sizes its buffers from the header: a 200-byte PCD with COUNT 1000000000 or POINTS
// 50000000 and no data makes it allocate gigabytes, and an ASCII line with fewer values than the
// FIELDS/COUNT announce is read as zeros without a word. These checks parse the header themselves
// and bound every claim by the bytes that follow it:
//   - PCD (Rusu and Cousins 2011, the PCD v0.7 format): FIELDS/SIZE/TYPE/COUNT agree, SIZE in
//     {1, 2, 4, 8}, TYPE in {I, U, F}, at most kMaxFields fields and kMaxValuesPerPoint values per
//     point, POINTS = WIDTH x HEIGHT. DATA binary: at least POINTS x point size bytes follow (PCL pads
//     its binary files, so more may).
//     DATA binary_compressed: the compressed block lies in the file, its uncompressed size is
//     POINTS x point size and at most kMaxLzfExpansion times the compressed size (an LZF back
//     reference of 3 bytes yields at most 264 bytes: Lehmann 2000, liblzf). DATA ascii: every
//     non-empty line holds exactly the announced number of values, and there are POINTS lines; a
//     line of white space only is refused (PCL reads it as a point of zeros).
//   - PLY (Turk 1994): "ply", a format line, elements with properties (scalars and lists).
//     Binary: the bytes that follow are at least the sum over elements of count x the smallest
//     record (scalars plus list counts), and exactly that when no element has a list.
//     ASCII: one line per element record, scalar-only records with exactly one value per property,
//     and as many non-empty lines as records.
// A failed check throws PointCloudError naming the file, the line where it applies, and the claim.
// Time is linear in the file size (the ASCII body is scanned once in blocks), memory is constant;
// a header line longer than kMaxHeaderLineBytes, a header beyond kMaxHeaderBytes or an ASCII body
// line longer than kMaxAsciiLineBytes (PCL reads each line whole) is refused.
#pragma once

#include "rowloc/mapping/point_cloud.hpp"

#include <cstdint>
#include <filesystem>
#include <istream>

namespace rowloc::mapping {

inline constexpr std::size_t kMaxHeaderBytes = 1 << 20;      ///< 1 MiB of header text at most
inline constexpr std::size_t kMaxHeaderLineBytes = 1 << 16;  ///< 64 KiB per header line at most
inline constexpr std::size_t kMaxAsciiLineBytes = 1 << 20;   ///< 1 MiB per ASCII body line at most
inline constexpr std::size_t kMaxFields = 256;               ///< fields (PCD) / properties per element (PLY)
inline constexpr std::uint64_t kMaxValuesPerPoint = 4096;     ///< sum of COUNT (PCD)
inline constexpr std::uint64_t kMaxLzfExpansion = 88;         ///< 264 output bytes per 3-byte back reference

enum class PointCloudEncoding { kAscii, kBinary, kBinaryCompressed };

/// What a checked header announces, now known to be backed by the file.
struct PointCloudFileSummary {
  PointCloudEncoding encoding = PointCloudEncoding::kAscii;
  std::uint64_t points = 0;        ///< PCD: POINTS; PLY: records of the "vertex" element
  std::uint64_t point_bytes = 0;   ///< bytes of one point record (binary)
  std::uint64_t header_bytes = 0;  ///< offset of the body
};

/// Checks a PCD file read from `in` (from its start). `name` is used in messages only.
PointCloudFileSummary CheckPcdFile(std::istream& in, const std::filesystem::path& name);

/// Checks a PLY file read from `in` (from its start). `name` is used in messages only.
PointCloudFileSummary CheckPlyFile(std::istream& in, const std::filesystem::path& name);

}  // namespace rowloc::mapping
