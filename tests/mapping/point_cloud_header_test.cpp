// Tests of CheckPcdFile / CheckPlyFile (mapping/point_cloud_header.hpp) and of ReadPointCloud
// behind them: every header claim is bounded by what the file holds, before PCL allocates; a short
// or long ASCII line is an error with its line number; a written cloud passes.
#include "rowloc/mapping/point_cloud_header.hpp"

#include "rowloc/mapping/point_cloud.hpp"

#include "test_support.hpp"

#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include <fstream>
#include <sstream>
#include <string>

namespace rowloc::mapping {
namespace {

using ::testing::HasSubstr;

std::string PcdHeader(const std::string& count, std::uint64_t points, const std::string& data) {
  return "# .PCD v0.7\nVERSION 0.7\nFIELDS x y z\nSIZE 4 4 4\nTYPE F F F\nCOUNT " + count + "\nWIDTH " +
         std::to_string(points) + "\nHEIGHT 1\nVIEWPOINT 0 0 0 1 0 0 0\nPOINTS " + std::to_string(points) +
         "\nDATA " + data + "\n";
}

std::string PlyHeader(const std::string& format, std::uint64_t vertices, const std::string& extra = "") {
  return "ply\nformat " + format + " 1.0\nelement vertex " + std::to_string(vertices) +
         "\nproperty float x\nproperty float y\nproperty float z\n" + extra + "end_header\n";
}

std::string PcdError(const std::string& text) {
  std::istringstream in(text);
  try {
    CheckPcdFile(in, "t.pcd");
  } catch (const PointCloudError& e) {
    return e.what();
  }
  return "accepted";
}

std::string PlyError(const std::string& text) {
  std::istringstream in(text);
  try {
    CheckPlyFile(in, "t.ply");
  } catch (const PointCloudError& e) {
    return e.what();
  }
  return "accepted";
}

TEST(CheckPcdFile, AcceptsAConsistentAsciiFile) {
  std::istringstream in(PcdHeader("1 1 1", 2, "ascii") + "1 2 3\n4 5 6\n");
  const PointCloudFileSummary s = CheckPcdFile(in, "t.pcd");
  EXPECT_EQ(s.points, 2U);
  EXPECT_EQ(s.point_bytes, 12U);
  EXPECT_EQ(s.encoding, PointCloudEncoding::kAscii);
}

TEST(CheckPcdFile, RefusesAHugeCount) {
  // The issue's 200-byte file: COUNT 1000000000 made PCL reach 7.6 GB.
  EXPECT_THAT(PcdError(PcdHeader("1000000000 1 1", 1, "ascii") + "1 2 3\n"), HasSubstr("COUNT"));
  EXPECT_THAT(PcdError(PcdHeader("4000 4000 1", 1, "ascii") + "1 2 3\n"), HasSubstr("values per point"));
}

TEST(CheckPcdFile, RefusesPointsTheFileDoesNotHold) {
  // 50 million points and no data: PCL allocated 1.2 GB.
  EXPECT_THAT(PcdError(PcdHeader("1 1 1", 50000000, "binary")), HasSubstr("only 0 follow the header"));
  EXPECT_THAT(PcdError(PcdHeader("1 1 1", 50000000, "ascii") + "1 2 3\n"),
              HasSubstr("holds 1 point lines"));
  EXPECT_THAT(PcdError(PcdHeader("1 1 1", 2, "binary") + std::string(23, '\0')), HasSubstr("but only 23 follow"));
}

TEST(CheckPcdFile, RefusesACompressedBlockThatClaimsMoreThanLzfCanHold) {
  // 4 GB claimed by an 8-byte block header: PCL reached 4.2 GB.
  std::string block = {'\x0c', 0, 0, 0, '\x00', '\x00', '\x00', '\xff'};
  EXPECT_THAT(PcdError(PcdHeader("1 1 1", 1, "binary_compressed") + block + std::string(12, 'a')),
              HasSubstr("uncompressed bytes, but POINTS x point size is 12"));
  // A consistent size the compressed bytes cannot expand to.
  std::string points = PcdHeader("1 1 1", 1000, "binary_compressed");
  points += std::string{'\x02', 0, 0, 0, '\xe0', '\x2e', 0, 0} + "ab";  // 12000 from 2 bytes
  EXPECT_THAT(PcdError(points), HasSubstr("LZF expands at most 88 times"));
  EXPECT_THAT(PcdError(PcdHeader("1 1 1", 1, "binary_compressed") + std::string{'\x40', 0, 0, 0, '\x0c', 0, 0, 0}),
              HasSubstr("claims 64 compressed bytes, but 0 follow"));
}

TEST(CheckPcdFile, AShortOrLongAsciiLineIsAnErrorWithItsLineNumber) {
  // 4 fields, 3 values per line: PCL read every point as (0, 0, 0).
  const std::string four = "VERSION 0.7\nFIELDS x y z intensity\nSIZE 4 4 4 4\nTYPE F F F F\nCOUNT 1 1 1 1\n"
                           "WIDTH 2\nHEIGHT 1\nPOINTS 2\nDATA ascii\n";
  EXPECT_THAT(PcdError(four + "1 2 3 4\n1 2 3\n"), HasSubstr("line 11: 3 values, but FIELDS and COUNT announce 4"));
  EXPECT_THAT(PcdError(four + "1 2 3 4 5\n1 2 3 4\n"), HasSubstr("line 10: 5 values"));
  EXPECT_THAT(PcdError(four + "1 2 3 4\n\n1 2 3 4\n1 2 3 4\n"), HasSubstr("line 13: more points than POINTS 2"));
  EXPECT_EQ(PcdError(four + "1 2 3 4\r\n\n  1 2 3 4\n"), "accepted");  // blank lines and CRLF are fine
}

TEST(CheckPcdFile, ALineOfWhiteSpaceIsRefusedNotReadAsAPointOfZeros) {
  // PCL skips only empty lines: "  " or "\r" became a point (0, 0, 0) and the last point was lost.
  EXPECT_EQ(PcdError(PcdHeader("1 1 1", 2, "ascii") + "  \n1 2 3\n4 5 6\n"),
            "point cloud 't.pcd': line 12: white space only (PCL would read it as a point of zeros; remove the line)");
  EXPECT_THAT(PcdError(PcdHeader("1 1 1", 2, "ascii") + "1 2 3\r\n\r\n4 5 6\r\n"), HasSubstr("line 13: white space only"));
  EXPECT_EQ(PcdError(PcdHeader("1 1 1", 2, "ascii") + "1 2 3\n\n4 5 6\n"), "accepted");  // an empty line is skipped
}

TEST(CheckPointCloudFiles, AnAsciiLineIsRefusedAfter1MiBNotReadWhole) {
  // Issue 26 sibling: PCL reads an ASCII line whole; a 1 GiB line of spaces took 2.2 GB and read
  // as a point of zeros. Here 2 MiB of spaces before the values of a point.
  const std::string spaces(std::size_t{2} << 20, ' ');
  EXPECT_EQ(PcdError(PcdHeader("1 1 1", 1, "ascii") + spaces + "1 2 3\n"),
            "point cloud 't.pcd': line 12 is longer than 1048576 bytes");
  EXPECT_EQ(PlyError(PlyHeader("ascii", 1) + spaces + "1 2 3\n"), "point cloud 't.ply': line 8 is longer than 1048576 bytes");
  const std::string at_limit = std::string(kMaxAsciiLineBytes - 5, ' ') + "1 2 3";
  EXPECT_EQ(PcdError(PcdHeader("1 1 1", 1, "ascii") + at_limit + "\n"), "accepted");
}

TEST(CheckPcdFile, RefusesMalformedHeaders) {
  EXPECT_THAT(PcdError("FIELDS x y z\nSIZE 4 4\nTYPE F F F\nWIDTH 1\nHEIGHT 1\nDATA ascii\n1 2 3\n"),
              HasSubstr("SIZE gives 2 sizes for 3 FIELDS"));
  EXPECT_THAT(PcdError("FIELDS x y z\nSIZE 4 4 3\n"), HasSubstr("line 2: SIZE: 3 is not 1, 2, 4 or 8"));
  EXPECT_THAT(PcdError(PcdHeader("1 1 1", 2, "ascii").replace(0, 0, "BOGUS 1\n")), HasSubstr("line 1: unknown PCD"));
  EXPECT_THAT(PcdError("FIELDS x y z\nSIZE 4 4 4\nTYPE F F F\nWIDTH 2\nHEIGHT 2\nPOINTS 3\nDATA ascii\n"),
              HasSubstr("POINTS 3 is not WIDTH x HEIGHT = 4"));
  EXPECT_THAT(PcdError("FIELDS x y z\nSIZE 4 4 4\nTYPE F F F\nWIDTH 1\nHEIGHT 1\n"), HasSubstr("no DATA line"));
  EXPECT_THAT(PcdError(std::string(kMaxHeaderLineBytes + 10, 'F')), HasSubstr("header line 1 is longer"));
}

TEST(CheckPlyFile, RefusesVerticesTheFileDoesNotHold) {
  // 50 million vertices and no data: PCL allocated 0.6 GB.
  EXPECT_THAT(PlyError(PlyHeader("binary_little_endian", 50000000)), HasSubstr("only 0 follow the header"));
  EXPECT_THAT(PlyError(PlyHeader("ascii", 50000000) + "1 2 3\n"), HasSubstr("announce 50000000 records"));
  // Faces: each needs at least its list count.
  EXPECT_THAT(PlyError(PlyHeader("binary_little_endian", 1, "element face 1000000\nproperty list uchar int vi\n") +
                       std::string(12, '\0')),
              HasSubstr("only 12 follow"));
}

TEST(CheckPlyFile, AShortAsciiVertexLineIsAnErrorWithItsLineNumber) {
  EXPECT_THAT(PlyError(PlyHeader("ascii", 2) + "1 2 3\n1 2\n"), HasSubstr("line 9: 2 values, but element 'vertex' has 3"));
  EXPECT_THAT(PlyError(PlyHeader("ascii", 1) + "1 2 3\n4 5 6\n"), HasSubstr("line 9: more records"));
}

TEST(CheckPlyFile, AcceptsFacesAndBinaryOfTheRightSize) {
  std::istringstream ascii(PlyHeader("ascii", 3, "element face 1\nproperty list uchar int vertex_indices\n") +
                           "0 0 0\n1 0 0\n0 1 0\n3 0 1 2\n");
  EXPECT_EQ(CheckPlyFile(ascii, "t.ply").points, 3U);
  std::istringstream binary(PlyHeader("binary_little_endian", 2) + std::string(24, '\0'));
  EXPECT_EQ(CheckPlyFile(binary, "t.ply").point_bytes, 12U);
  EXPECT_THAT(PlyError(PlyHeader("binary_little_endian", 2) + std::string(25, '\0')),
              HasSubstr("does not describe the data"));
}

TEST(CheckPlyFile, RefusesMalformedHeaders) {
  EXPECT_THAT(PlyError("plx\n"), HasSubstr("not a PLY file"));
  EXPECT_THAT(PlyError("ply\nformat ascii 1.0\nelement vertex 1\nproperty quad x\nend_header\n"),
              HasSubstr("line 4: unknown PLY property type 'quad'"));
  EXPECT_THAT(PlyError("ply\nformat ascii 1.0\nelement vertex 1\n"), HasSubstr("no end_header"));
  EXPECT_THAT(PlyError("ply\nformat ascii 1.0\nelement vertex 99999999999\n"), HasSubstr("element vertex"));
  EXPECT_THAT(PlyError("ply\nformat ascii 1.0\nelement thing 4000000000\nend_header\n"),
              HasSubstr("has records but no properties"));
}

TEST(ReadPointCloud, RefusesTheIssuesFilesWithTheReasonNotBadAlloc) {
  test::ScratchDir dir;
  const auto write = [&](const std::string& name, const std::string& text) {
    std::ofstream(dir / name, std::ios::binary) << text;
    return dir / name;
  };
  for (const auto& [path, reason] :
       {std::pair{write("count.pcd", PcdHeader("1000000000 1 1", 1, "ascii") + "1 2 3\n"), std::string("COUNT")},
        std::pair{write("points.pcd", PcdHeader("1 1 1", 50000000, "binary")), std::string("only 0 follow")},
        std::pair{write("points.ply", PlyHeader("binary_little_endian", 50000000)), std::string("only 0 follow")},
        std::pair{write("short.pcd", "FIELDS x y z w\nSIZE 4 4 4 4\nTYPE F F F F\nWIDTH 1\nHEIGHT 1\nDATA ascii\n1 2 3\n"),
                  std::string("line 7: 3 values")}}) {
    try {
      ReadPointCloud(path);
      ADD_FAILURE() << "read " << path;
    } catch (const PointCloudError& e) {
      EXPECT_THAT(e.what(), HasSubstr(path.string()));
      EXPECT_THAT(e.what(), HasSubstr(reason));
    }
  }
}

TEST(ReadPointCloud, AWrittenCloudPassesTheChecks) {
  test::ScratchDir dir;
  const PointCloud cloud{{{1.0, 2.0, 3.0}, {4.0, 5.0, 6.5}}};
  for (const char* name : {"c.ply", "c.pcd"}) {
    WritePointCloud(cloud, dir / name);
    std::ifstream in(dir / name, std::ios::binary);
    const PointCloudFileSummary s = std::string(name) == "c.ply" ? CheckPlyFile(in, name) : CheckPcdFile(in, name);
    EXPECT_EQ(s.points, 2U);
    EXPECT_EQ(s.point_bytes, 24U);
    EXPECT_EQ(ReadPointCloud(dir / name).points_m, cloud.points_m);
  }
}

TEST(WritePointCloud, NeverReplacesADirectoryAndLeavesNoTemporary) {
  test::ScratchDir dir;
  std::filesystem::create_directory(dir / "d.ply");
  EXPECT_THROW(WritePointCloud(PointCloud{{{1.0, 2.0, 3.0}}}, dir / "d.ply"), std::runtime_error);
  EXPECT_TRUE(std::filesystem::is_directory(dir / "d.ply"));
  EXPECT_EQ(std::distance(std::filesystem::directory_iterator(dir.path()), std::filesystem::directory_iterator()), 1);
}

}  // namespace
}  // namespace rowloc::mapping
