// Tests of the LAS reader and writer (mapping/las_file.hpp): round trips of every point format
// with LAS 1.2, 1.3 and 1.4 and extra bytes, a file assembled byte by byte from the specification
// (ASPRS 2019, LAS Specification 1.4 R15), precision at UTM magnitudes through ReadPointCloud, and
// every refusal with its message, on hand-made byte buffers.
#include "rowloc/mapping/las_file.hpp"

#include "rowloc/mapping/point_cloud.hpp"
#include "point_cloud_errors.hpp"
#include "test_support.hpp"

#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include <bit>
#include <cmath>
#include <cstdint>
#include <fstream>
#include <limits>
#include <random>
#include <sstream>
#include <string>
#include <tuple>

namespace rowloc::mapping {
namespace {

using ::testing::HasSubstr;

void PutLe(std::string& bytes, std::size_t at, std::uint64_t value, std::size_t width) {
  for (std::size_t i = 0; i < width; ++i) bytes[at + i] = static_cast<char>((value >> (8 * i)) & 0xFF);
}
void PutDouble(std::string& bytes, std::size_t at, double value) {
  PutLe(bytes, at, std::bit_cast<std::uint64_t>(value), 8);
}

void WriteBytes(const std::filesystem::path& path, const std::string& bytes) {
  std::ofstream out(path, std::ios::binary);
  out.write(bytes.data(), static_cast<std::streamsize>(bytes.size()));
}

LasCloud ReadBytes(const std::string& bytes, const std::string& name = "mem.las") {
  std::istringstream in(bytes);
  return ReadLas(in, name);
}

/// Expects ReadLas on `bytes` to throw PointCloudError naming "mem.las" and containing `reason`.
void ExpectRefused(const std::string& bytes, const std::string& reason) {
  try {
    ReadBytes(bytes);
    ADD_FAILURE() << "no error, expected: " << reason;
  } catch (const PointCloudError& e) {
    EXPECT_THAT(e.what(), HasSubstr("'mem.las'"));
    EXPECT_THAT(e.what(), HasSubstr(reason));
  }
}

/// A cloud on the 1 mm grid of `offset`, with intensity and classification: what a LAS file holds exactly.
LasCloud GridCloud(std::size_t count, const Eigen::Vector3d& offset, unsigned seed, int max_class = 31) {
  std::mt19937 rng(seed);
  std::uniform_int_distribution<std::int32_t> mm(-2'000'000, 2'000'000);
  std::uniform_int_distribution<int> intensity(0, 65535);
  std::uniform_int_distribution<int> klass(0, max_class);
  LasCloud cloud;
  for (std::size_t i = 0; i < count; ++i) {
    cloud.points_m.emplace_back(static_cast<double>(mm(rng)) * 0.001 + offset.x(),
                                static_cast<double>(mm(rng)) * 0.001 + offset.y(),
                                static_cast<double>(mm(rng) / 100) * 0.001 + offset.z());
    cloud.intensity.push_back(static_cast<std::uint16_t>(intensity(rng)));
    cloud.classification.push_back(static_cast<std::uint8_t>(klass(rng)));
  }
  return cloud;
}

/// A valid file of `count` points (LAS 1.`minor`, `format`) to patch.
std::string ValidFile(int minor = 2, int format = 0, std::size_t count = 3) {
  LasWriteOptions options;
  options.version_minor = minor;
  options.point_format = format;
  options.offset = Eigen::Vector3d(500000.0, 5000000.0, 0.0);
  return EncodeLas(GridCloud(count, *options.offset, 7), options);
}

// ---- Point record sizes and the round trip ----

TEST(LasPointFormatSize, MatchesTheSpecification) {
  const std::uint16_t expected[] = {20, 28, 26, 34, 57, 63, 30, 36, 38, 59, 67};
  for (int format = 0; format <= 10; ++format) EXPECT_EQ(LasPointFormatSize(format), expected[format]) << format;
  EXPECT_THROW(LasPointFormatSize(11), std::invalid_argument);
  EXPECT_THROW(LasPointFormatSize(-1), std::invalid_argument);
}

struct RoundTripCase {
  int minor;
  int format;
  std::uint16_t extra_bytes;
};

class LasRoundTrip : public ::testing::TestWithParam<RoundTripCase> {};

TEST_P(LasRoundTrip, WriteThenReadGivesTheSamePointsAndHeader) {
  const RoundTripCase c = GetParam();
  test::ScratchDir dir;
  const std::filesystem::path path = dir / "cloud.las";
  const Eigen::Vector3d offset(512000.0, 5012000.0, 240.0);
  const LasCloud cloud = GridCloud(301, offset, 42, c.format < 6 ? 31 : 255);
  LasWriteOptions options;
  options.version_minor = c.minor;
  options.point_format = c.format;
  options.offset = offset;
  options.extra_bytes = c.extra_bytes;
  WriteLasFile(cloud, path, options);

  const LasCloud read = ReadLasFile(path);
  const LasHeader& h = read.header;
  EXPECT_EQ(h.version_major, 1);
  EXPECT_EQ(h.version_minor, c.minor);
  EXPECT_EQ(h.point_format, c.format);
  EXPECT_EQ(h.point_record_length, LasPointFormatSize(c.format) + c.extra_bytes);
  EXPECT_EQ(h.extra_bytes(), c.extra_bytes);
  EXPECT_EQ(h.header_size, c.minor == 4 ? 375 : c.minor == 3 ? 235 : 227);
  EXPECT_EQ(h.offset_to_point_data, h.header_size);
  EXPECT_EQ(h.point_count, cloud.points_m.size());
  // LAS 1.4: the legacy count is 0 for formats 6-10 (the public header block's rule), else the count.
  EXPECT_EQ(h.legacy_point_count, c.minor == 4 && c.format >= 6 ? 0U : cloud.points_m.size());
  EXPECT_EQ((h.global_encoding & 0x10) != 0, c.format >= 6);  // WKT bit, required with formats 6-10
  EXPECT_EQ(h.system_identifier, "OTHER");
  EXPECT_EQ(h.generating_software, "rowloc");
  EXPECT_EQ(h.scale, Eigen::Vector3d::Constant(0.001));
  EXPECT_EQ(h.offset, offset);
  ASSERT_EQ(read.points_m.size(), cloud.points_m.size());
  Eigen::Vector3d lo = cloud.points_m.front();
  Eigen::Vector3d hi = lo;
  for (std::size_t i = 0; i < cloud.points_m.size(); ++i) {
    EXPECT_EQ(read.points_m[i], cloud.points_m[i]) << "point " << i;
    EXPECT_EQ(read.intensity[i], cloud.intensity[i]) << "point " << i;
    EXPECT_EQ(read.classification[i], cloud.classification[i]) << "point " << i;
    lo = lo.cwiseMin(cloud.points_m[i]);
    hi = hi.cwiseMax(cloud.points_m[i]);
  }
  EXPECT_EQ(h.min, lo);
  EXPECT_EQ(h.max, hi);
}

std::vector<RoundTripCase> AllCases() {
  std::vector<RoundTripCase> cases;
  for (const std::uint16_t extra : {0, 9}) {
    for (int format = 0; format <= 3; ++format) cases.push_back({2, format, extra});
    for (int format = 0; format <= 5; ++format) cases.push_back({3, format, extra});
    for (int format = 0; format <= 10; ++format) cases.push_back({4, format, extra});
  }
  return cases;
}

INSTANTIATE_TEST_SUITE_P(VersionsFormatsExtraBytes, LasRoundTrip, ::testing::ValuesIn(AllCases()),
                         [](const ::testing::TestParamInfo<RoundTripCase>& test_case) {
                           return "v1" + std::to_string(test_case.param.minor) + "_format" +
                                  std::to_string(test_case.param.format) + "_extra" +
                                  std::to_string(test_case.param.extra_bytes);
                         });

TEST(WriteLasFile, DefaultOffsetIsTheFloorOfTheMinimumAndRoundsToTheScale) {
  LasCloud cloud;
  cloud.points_m = {{500123.4564, 5000456.7891, 241.0004}, {500200.0, 5000500.0, 250.0}};
  std::istringstream in(EncodeLas(cloud, {}));  // LAS 1.4, format 6, 1 mm
  const LasCloud read = ReadLas(in, "mem.las");
  EXPECT_EQ(read.header.offset, Eigen::Vector3d(500123.0, 5000456.0, 241.0));
  EXPECT_NEAR(read.points_m[0].x(), 500123.456, 1e-9);
  EXPECT_NEAR(read.points_m[0].y(), 5000456.789, 1e-9);
  EXPECT_NEAR(read.points_m[0].z(), 241.000, 1e-9);
  EXPECT_TRUE(read.classification == std::vector<std::uint8_t>({0, 0}));  // none given: 0
}

// ---- A file assembled from the specification, not by the writer ----

TEST(ReadLas, ReadsAHandAssembledLas12File) {
  // LAS 1.2, point format 1 (28 bytes) with 4 extra bytes per record, one 60-byte VLR area
  // between the header and the points, and bytes after the points (ignored).
  constexpr std::size_t kHeader = 227;
  constexpr std::size_t kOffset = kHeader + 60;
  constexpr std::size_t kRecord = 32;
  std::string b(kOffset + 2 * kRecord + 5, '\0');
  b.replace(0, 4, "LASF");
  b[24] = 1;
  b[25] = 2;
  PutLe(b, 94, kHeader, 2);
  PutLe(b, 96, kOffset, 4);
  PutLe(b, 100, 1, 4);  // one VLR (not parsed)
  b[104] = 1;
  PutLe(b, 105, kRecord, 2);
  PutLe(b, 107, 2, 4);
  PutDouble(b, 131, 0.01);
  PutDouble(b, 139, 0.01);
  PutDouble(b, 147, 0.001);
  PutDouble(b, 155, 400000.0);
  PutDouble(b, 163, 4990000.0);
  PutDouble(b, 171, -10.0);
  const std::int32_t xyz[2][3] = {{123456, -7, 250000}, {-2147483647 - 1, 2147483647, 0}};
  for (std::size_t i = 0; i < 2; ++i) {
    const std::size_t at = kOffset + i * kRecord;
    for (std::size_t axis = 0; axis < 3; ++axis) PutLe(b, at + 4 * axis, static_cast<std::uint32_t>(xyz[i][axis]), 4);
    PutLe(b, at + 12, 1000 + i, 2);                   // intensity
    b[at + 15] = static_cast<char>(0xE0 | (2 + i));  // synthetic/key-point/withheld flags over class 2, 3
    for (std::size_t k = 28; k < kRecord; ++k) b[at + k] = static_cast<char>(0xFF);  // extra bytes
  }
  const LasCloud read = ReadBytes(b);
  ASSERT_EQ(read.points_m.size(), 2U);
  EXPECT_EQ(read.points_m[0], Eigen::Vector3d(123456 * 0.01 + 400000.0, -7 * 0.01 + 4990000.0, 250000 * 0.001 - 10.0));
  EXPECT_EQ(read.points_m[1],
            Eigen::Vector3d(-2147483648.0 * 0.01 + 400000.0, 2147483647.0 * 0.01 + 4990000.0, 0.0 * 0.001 - 10.0));
  EXPECT_EQ(read.intensity, std::vector<std::uint16_t>({1000, 1001}));
  EXPECT_EQ(read.classification, std::vector<std::uint8_t>({2, 3}));
  EXPECT_EQ(read.header.number_of_vlrs, 1U);
  EXPECT_EQ(read.header.extra_bytes(), 4);
}

TEST(ReadLas, AcceptsLas10And11) {
  for (const char minor : {0, 1}) {
    std::string b = ValidFile(2, 1);
    b[25] = minor;
    const LasCloud read = ReadBytes(b);
    EXPECT_EQ(read.header.version_minor, minor);
    EXPECT_EQ(read.points_m.size(), 3U);
  }
}

TEST(ReadLas, Las14TakesTheLegacyCountWhenThe64BitCountIsZero) {
  std::string b = ValidFile(4, 1);
  PutLe(b, 247, 0, 8);
  EXPECT_EQ(ReadBytes(b).points_m.size(), 3U);
}

TEST(ReadLas, AcceptsAFileWithZeroPoints) {
  LasCloud empty;
  const LasCloud read = ReadBytes(EncodeLas(empty, {}));
  EXPECT_EQ(read.header.point_count, 0U);
  EXPECT_TRUE(read.points_m.empty());
}

// ---- Precision at UTM magnitudes, through the point cloud loader ----

TEST(ReadPointCloud, KeepsMillimetresOfUtmCoordinatesAfterTheOriginIsSubtracted) {
  test::ScratchDir dir;
  // Eastings ~5e5 m and northings ~5e6 m at 1 mm, offset far from the points (the file's choice).
  LasCloud cloud;
  std::vector<Eigen::Vector3d> local_mm;
  for (int i = 0; i < 50; ++i) {
    const Eigen::Vector3d mm(1000.0 * i + 1.0 + (i % 7), 997.0 * i + 3.0 + (i % 5), 1000.0 + (i % 11));
    local_mm.push_back(mm);
    cloud.points_m.emplace_back(512345.0 + mm.x() / 1000.0, 5012345.0 + mm.y() / 1000.0, 240.0 + mm.z() / 1000.0);
  }
  for (const int minor : {2, 4}) {
    const std::filesystem::path path = dir / ("utm-1" + std::to_string(minor) + ".LAS");
    LasWriteOptions options;
    options.version_minor = minor;
    options.point_format = minor == 4 ? 6 : 1;
    options.offset = Eigen::Vector3d(400000.0, 4000000.0, 0.0);
    WriteLasFile(cloud, path, options);
    const PointCloud read = ReadPointCloud(path);
    ASSERT_EQ(read.points_m.size(), cloud.points_m.size());
    // The origin as map build subtracts it (the floor of the minimum x, y), in double.
    Eigen::Vector3d lo = read.points_m.front();
    for (const auto& p : read.points_m) lo = lo.cwiseMin(p);
    const Eigen::Vector3d origin(std::floor(lo.x()), std::floor(lo.y()), 0.0);
    EXPECT_EQ(origin, Eigen::Vector3d(512345.0, 5012345.0, 0.0));
    for (std::size_t i = 0; i < read.points_m.size(); ++i) {
      const Eigen::Vector3d local = read.points_m[i] - origin;
      EXPECT_NEAR(local.x(), local_mm[i].x() / 1000.0, 1e-6) << "point " << i;
      EXPECT_NEAR(local.y(), local_mm[i].y() / 1000.0, 1e-6) << "point " << i;
      EXPECT_NEAR(local.z(), 240.0 + local_mm[i].z() / 1000.0, 1e-6) << "point " << i;
    }
  }
  // What float32 would do to the same northing (its spacing at 5e6 is 0.5 m).
  const double northing = cloud.points_m[1].y();
  EXPECT_GT(std::abs(static_cast<double>(static_cast<float>(northing)) - northing), 0.001);
}

TEST(ReadPointCloud, RefusesLasEdgeCasesWithItsOwnMessages) {
  test::ScratchDir dir;
  test::ExpectReadError(dir / "absent.las", "no such file");
  std::filesystem::create_directory(dir / "folder.las");
  test::ExpectReadError(dir / "folder.las", "not a regular file");
  WriteBytes(dir / "empty.las", EncodeLas(LasCloud{}, {}));
  test::ExpectReadError(dir / "empty.las", "the file holds no points");
  WriteBytes(dir / "text.las", "1 2 3\n");
  test::ExpectReadError(dir / "text.las", "not a LAS file");
}

// ---- Refusals ----

TEST(ForEachPointChunk, StreamsALasFileInChunksEqualToTheWholeRead) {
  test::ScratchDir dir;
  const LasCloud cloud = GridCloud(10007, Eigen::Vector3d(512000.0, 5012000.0, 200.0), 11);
  const std::filesystem::path path = dir / "survey.las";
  WriteLasFile(cloud, path);
  const PointCloud whole = ReadPointCloud(path);
  for (std::size_t chunk : {std::size_t{1}, std::size_t{1000}, std::size_t{10007}, std::size_t{1} << 20}) {
    std::vector<Eigen::Vector3d> joined;
    std::size_t largest = 0;
    const std::size_t count = ForEachPointChunk(path, chunk, [&](const std::vector<Eigen::Vector3d>& points) {
      largest = std::max(largest, points.size());
      joined.insert(joined.end(), points.begin(), points.end());
    });
    EXPECT_EQ(count, 10007U);
    EXPECT_LE(largest, chunk);
    EXPECT_EQ(joined, whole.points_m) << "chunks of " << chunk;
  }
  EXPECT_THROW(ForEachPointChunk(path, 0, [](const std::vector<Eigen::Vector3d>&) {}), std::invalid_argument);
}

TEST(ForEachPointChunk, ReportsATruncatedLasFileAfterTheChunksBeforeIt) {
  test::ScratchDir dir;
  std::string bytes = ValidFile(2, 0, 100);
  bytes.resize(bytes.size() - 30);  // cuts into record 99 of 100 (20 bytes each)
  const std::filesystem::path path = dir / "cut.las";
  WriteBytes(path, bytes);
  // ReadLasHeader checks the count against the file's size first: nothing is streamed.
  std::size_t seen = 0;
  try {
    ForEachPointChunk(path, 10, [&](const std::vector<Eigen::Vector3d>& chunk) { seen += chunk.size(); });
    ADD_FAILURE() << "a truncated file was streamed";
  } catch (const PointCloudError& e) {
    EXPECT_EQ(e.path(), path);
    EXPECT_THAT(e.what(), HasSubstr("point count"));
  }
  EXPECT_EQ(seen, 0U);
}

TEST(ForEachPointChunk, RefusesAnEmptyLasFile) {
  test::ScratchDir dir;
  const std::filesystem::path path = dir / "empty.las";
  WriteBytes(path, ValidFile(2, 0, 0));
  try {
    ForEachPointChunk(path, 10, [](const std::vector<Eigen::Vector3d>&) {});
    ADD_FAILURE() << "an empty file was accepted";
  } catch (const PointCloudError& e) {
    EXPECT_EQ(e.path(), path);
    EXPECT_THAT(e.what(), HasSubstr("the file holds no points"));
  }
}

TEST(ReadLas, RefusesLazByExtensionWithTheConversion) {
  test::ScratchDir dir;
  const std::filesystem::path path = dir / "survey.laz";
  WriteBytes(path, ValidFile());
  for (const bool through_loader : {false, true}) {
    try {
      if (through_loader) {
        ReadPointCloud(path);
      } else {
        ReadLasFile(path);
      }
      ADD_FAILURE() << "no error";
    } catch (const PointCloudError& e) {
      const std::string las = (dir / "survey.las").string();
      EXPECT_THAT(e.what(), HasSubstr("LAZ (compressed LAS) is not read: convert it with `laszip -i " + path.string() +
                                      " -o " + las + "` or `pdal translate " + path.string() + " " + las + "`"));
      EXPECT_THAT(e.what(), HasSubstr("the extension is .laz"));
    }
  }
}

TEST(ReadLas, RefusesTheLaszipBitsOfThePointFormat) {
  std::string b = ValidFile(4, 6);
  b[104] = static_cast<char>(0x80 | 6);
  ExpectRefused(b, "LAZ (compressed LAS) is not read: convert it with `laszip -i mem.las -o mem-decompressed.las` or "
                   "`pdal translate mem.las mem-decompressed.las`");
  ExpectRefused(b, "byte 104 is 134: bit 7, LASzip compression, is set");
  b[104] = static_cast<char>(0x40 | 1);
  ExpectRefused(b, "byte 104 is 65: bit 6, LASzip compression, is set");
}

TEST(ReadLas, RefusesAWrongSignature) {
  std::string b = ValidFile();
  b[3] = 'G';
  ExpectRefused(b, "not a LAS file: the signature (bytes 0-3) is \"LASG\", expected \"LASF\"");
  ExpectRefused("", "the signature (bytes 0-3) is \"\"");
  ExpectRefused(std::string("PK\x03\x04 zip", 8), "the signature (bytes 0-3) is \"PK\\x03\\x04\"");
}

TEST(ReadLas, RefusesATruncatedHeader) {
  ExpectRefused(ValidFile().substr(0, 226), "truncated: the file ends at byte 226, inside the public header block");
  // A LAS 1.4 header cut after the 1.2 fields: the header size runs past the end.
  ExpectRefused(ValidFile(4, 6, 0).substr(0, 300), "truncated: the header size 375 (byte 94) runs past the end of the file (300 bytes)");
}

TEST(ReadLas, RefusesUnknownVersions) {
  std::string b = ValidFile();
  b[24] = 2;
  b[25] = 0;
  ExpectRefused(b, "LAS version 2.0 (bytes 24-25) is not read: LAS 1.0 to 1.4 are");
  b[24] = 1;
  b[25] = 5;
  ExpectRefused(b, "LAS version 1.5 (bytes 24-25) is not read");
}

TEST(ReadLas, RefusesAHeaderSizeBelowTheVersionsBlock) {
  std::string b = ValidFile(4, 6);
  PutLe(b, 94, 227, 2);
  ExpectRefused(b, "header size 227 (byte 94) is smaller than the 375-byte public header block of LAS 1.4");
  b = ValidFile(3, 1);
  PutLe(b, 94, 227, 2);
  ExpectRefused(b, "header size 227 (byte 94) is smaller than the 235-byte public header block of LAS 1.3");
}

TEST(ReadLas, RefusesAnOffsetToPointDataOutsideTheFile) {
  std::string b = ValidFile();
  PutLe(b, 96, 100, 4);
  ExpectRefused(b, "offset to point data 100 (byte 96) lies inside the 227-byte header");
  PutLe(b, 96, 1'000'000, 4);
  ExpectRefused(b, "truncated: the offset to point data 1000000 (byte 96) lies past the end of the file (287 bytes)");
}

TEST(ReadLas, RefusesPointFormatsAbove10) {
  std::string b = ValidFile(4, 6);
  b[104] = 11;
  ExpectRefused(b, "point data record format 11 (byte 104) is not a LAS format (0-10)");
  b[104] = 63;
  ExpectRefused(b, "point data record format 63 (byte 104)");
}

TEST(ReadLas, RefusesARecordLengthBelowTheFormatsSize) {
  std::string b = ValidFile(2, 1);
  PutLe(b, 105, 27, 2);
  ExpectRefused(b, "point data record length 27 (byte 105) is smaller than the 28 bytes of point format 1");
  b = ValidFile(4, 10);
  PutLe(b, 105, 0, 2);
  ExpectRefused(b, "point data record length 0 (byte 105) is smaller than the 67 bytes of point format 10");
}

TEST(ReadLas, RefusesAPointCountTheFileCannotHoldBeforeAllocating) {
  std::string b = ValidFile(2, 0, 3);  // 227 + 3 x 20 bytes
  PutLe(b, 107, 4'000'000'000U, 4);
  ExpectRefused(b, "the header announces 4000000000 points of 20 bytes from byte 227 (point count, byte 107), but the "
                   "file holds 60 bytes there: truncated, or a wrong count");
  b = ValidFile(4, 6, 3);
  PutLe(b, 247, std::uint64_t{1} << 62, 8);  // count x record length overflows 64 bits
  ExpectRefused(b, "the header announces 4611686018427387904 points of 30 bytes from byte 375 (point count, byte 247)");
  // A record length larger than the records written: 3 records of 20 bytes are not 3 of 21.
  b = ValidFile(2, 0, 3);
  PutLe(b, 105, 21, 2);
  ExpectRefused(b, "the header announces 3 points of 21 bytes");
}

TEST(ReadLas, RefusesTruncatedPointData) {
  const std::string b = ValidFile(2, 1, 10);
  ExpectRefused(b.substr(0, b.size() - 1), "the header announces 10 points of 28 bytes from byte 227 (point count, "
                                           "byte 107), but the file holds 279 bytes there");
}

/// A stream whose end lies beyond its data, as a file that shrinks while it is read.
class ShrinkingBuffer : public std::stringbuf {
 public:
  ShrinkingBuffer(const std::string& data, std::streamoff claimed) : std::stringbuf(data), claimed_(claimed) {}

 protected:
  pos_type seekoff(off_type off, std::ios_base::seekdir dir, std::ios_base::openmode which) override {
    if (dir == std::ios_base::end || (at_end_ && dir == std::ios_base::cur && off == 0)) {
      at_end_ = true;
      return pos_type(claimed_ + off);
    }
    at_end_ = false;
    return std::stringbuf::seekoff(off, dir, which);
  }

 private:
  std::streamoff claimed_;
  bool at_end_ = false;
};

TEST(ReadLas, RefusesAFileThatEndsInsideThePointRecords) {
  const std::string b = ValidFile(2, 0, 5);  // 227 + 5 x 20 = 327 bytes
  ShrinkingBuffer buffer(b.substr(0, 290), static_cast<std::streamoff>(b.size()));
  std::istream in(&buffer);
  try {
    ReadLas(in, "mem.las");
    ADD_FAILURE() << "no error";
  } catch (const PointCloudError& e) {
    EXPECT_THAT(e.what(), HasSubstr("truncated: the file ends at byte 290, inside point record 3 of 5"));
  }
}

TEST(ReadLas, RefusesBadScalesAndOffsets) {
  std::string b = ValidFile();
  PutDouble(b, 131, 0.0);
  ExpectRefused(b, "x scale factor 0 (byte 131) must be finite and non-zero");
  b = ValidFile();
  PutDouble(b, 139, std::numeric_limits<double>::quiet_NaN());
  ExpectRefused(b, "y scale factor nan (byte 139) must be finite and non-zero");
  b = ValidFile();
  PutDouble(b, 147, -std::numeric_limits<double>::infinity());
  ExpectRefused(b, "z scale factor -inf (byte 147) must be finite and non-zero");
  b = ValidFile();
  PutDouble(b, 163, std::numeric_limits<double>::infinity());
  ExpectRefused(b, "y offset inf (byte 163) must be finite");
  b = ValidFile();
  PutDouble(b, 131, 1e300);
  ExpectRefused(b, "x scale factor 1e+300 and offset 500000 (bytes 131, 155) overflow double");
}

TEST(ReadLas, RefusesALegacyCountThatContradictsThe64BitCount) {
  std::string b = ValidFile(4, 1, 3);
  PutLe(b, 107, 2, 4);
  ExpectRefused(b, "the legacy point count 2 (byte 107) contradicts the point count 3 (byte 247)");
}

// ---- The writer's refusals ----

TEST(EncodeLas, RefusesWhatLasCannotHold) {
  LasCloud cloud;
  cloud.points_m = {{0.0, 0.0, 0.0}};
  const auto refuses = [&cloud](LasWriteOptions options, const std::string& reason) {
    try {
      EncodeLas(cloud, options);
      ADD_FAILURE() << "no error, expected: " << reason;
    } catch (const std::invalid_argument& e) {
      EXPECT_THAT(e.what(), HasSubstr(reason));
    }
  };
  refuses({.version_minor = 2, .point_format = 6}, "point format 6 needs LAS 1.4");
  refuses({.version_minor = 2, .point_format = 4}, "point format 4 needs LAS 1.3 or later");
  refuses({.version_minor = 1, .point_format = 0}, "version 1.1 is not written");
  refuses({.point_format = 11}, "point format 11 does not exist");
  refuses({.scale = Eigen::Vector3d(0.001, 0.0, 0.001)}, "y scale 0 must be finite and positive");
  refuses({.extra_bytes = 65535}, "a record of 65565 bytes");
  LasWriteOptions far;
  far.offset = Eigen::Vector3d(-3e6, 0.0, 0.0);  // 3e9 mm from the offset
  refuses(far, "point 0: x = 0 is 3000000000 counts of 0.001 from the offset -3000000, outside int32");
  cloud.intensity = {1, 2};
  refuses({}, "intensity is not one per point");
  cloud.intensity.clear();
  cloud.classification = {32};
  refuses({.version_minor = 2, .point_format = 1}, "classification 32 needs point format 6-10");
  cloud.classification.clear();
  cloud.points_m[0].z() = std::numeric_limits<double>::quiet_NaN();
  refuses({}, "point 0 is not finite");
}

TEST(WriteLasFile, NamesThePathOnFailure) {
  test::ScratchDir dir;
  LasCloud cloud;
  cloud.points_m = {{1.0, 2.0, 3.0}};
  try {
    WriteLasFile(cloud, dir / "missing-dir" / "x.las");
    ADD_FAILURE() << "no error";
  } catch (const PointCloudError& e) {
    EXPECT_THAT(e.what(), HasSubstr("x.las"));
  }
  try {
    WriteLasFile(cloud, dir / "x.las", {.version_minor = 2, .point_format = 7});
    ADD_FAILURE() << "no error";
  } catch (const PointCloudError& e) {
    EXPECT_THAT(e.what(), HasSubstr("point format 7 needs LAS 1.4"));
  }
}

}  // namespace
}  // namespace rowloc::mapping
