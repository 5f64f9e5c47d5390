// Tests of ReadPointCloud / WritePointCloud (mapping/point_cloud.hpp): exact round trips through
// binary PLY and PCD, hand-written ASCII fixtures, and every rejected input.
#include "rowloc/mapping/point_cloud.hpp"

#include "point_cloud_errors.hpp"
#include "test_support.hpp"

#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include <array>
#include <cmath>
#include <fstream>
#include <iterator>
#include <limits>
#include <random>
#include <string>

namespace rowloc::mapping {
namespace {

using ::testing::HasSubstr;

void WriteText(const std::filesystem::path& path, const std::string& text) {
  std::ofstream out(path, std::ios::binary);
  out << text;
}

PointCloud RandomCloud(std::size_t count, unsigned seed) {
  std::mt19937 rng(seed);
  std::uniform_real_distribution<double> coordinate(-150.0, 150.0);
  PointCloud cloud;
  for (std::size_t i = 0; i < count; ++i) {
    // Doubles that float cannot represent, so a float round trip would be caught.
    cloud.points_m.emplace_back(coordinate(rng), coordinate(rng), coordinate(rng) / 7.0);
  }
  return cloud;
}

class PointCloudRoundTrip : public ::testing::TestWithParam<std::string> {};

TEST_P(PointCloudRoundTrip, WriteThenReadGivesTheSamePointsBitForBit) {
  test::ScratchDir dir;
  const std::filesystem::path path = dir / ("cloud" + GetParam());
  const PointCloud cloud = RandomCloud(257, 42);
  WritePointCloud(cloud, path);
  const PointCloud read = ReadPointCloud(path);
  ASSERT_EQ(read.points_m.size(), cloud.points_m.size());
  for (std::size_t i = 0; i < cloud.points_m.size(); ++i) {
    EXPECT_EQ(read.points_m[i], cloud.points_m[i]) << "point " << i;
  }
}

INSTANTIATE_TEST_SUITE_P(Formats, PointCloudRoundTrip,
                         ::testing::Values(".ply", ".pcd", ".PLY", ".Pcd"));

TEST(ReadPointCloud, ReadsAsciiPlyWithExtraPropertiesAndFaces) {
  test::ScratchDir dir;
  const std::filesystem::path path = dir / "fixture.ply";
  WriteText(path,
            "ply\n"
            "format ascii 1.0\n"
            "comment hand-written fixture\n"
            "element vertex 3\n"
            "property float x\n"
            "property float y\n"
            "property float z\n"
            "property uchar intensity\n"
            "element face 1\n"
            "property list uchar int vertex_indices\n"
            "end_header\n"
            "1.5 2.25 -3 10\n"
            "0 0 0 20\n"
            "-0.125 100 7.75 30\n"
            "3 0 1 2\n");
  const PointCloud cloud = ReadPointCloud(path);
  ASSERT_EQ(cloud.points_m.size(), 3U);
  EXPECT_EQ(cloud.points_m[0], Eigen::Vector3d(1.5, 2.25, -3.0));
  EXPECT_EQ(cloud.points_m[1], Eigen::Vector3d(0.0, 0.0, 0.0));
  EXPECT_EQ(cloud.points_m[2], Eigen::Vector3d(-0.125, 100.0, 7.75));
}

TEST(ReadPointCloud, ReadsDoublePrecisionAsciiPlyExactly) {
  test::ScratchDir dir;
  const std::filesystem::path path = dir / "double.ply";
  WriteText(path,
            "ply\nformat ascii 1.0\nelement vertex 2\n"
            "property double x\nproperty double y\nproperty double z\nend_header\n"
            "0.1 0.2 0.3\n"
            "123456.789 -0.7 1e-3\n");
  const PointCloud cloud = ReadPointCloud(path);
  ASSERT_EQ(cloud.points_m.size(), 2U);
  EXPECT_EQ(cloud.points_m[0], Eigen::Vector3d(0.1, 0.2, 0.3));
  EXPECT_EQ(cloud.points_m[1], Eigen::Vector3d(123456.789, -0.7, 1e-3));
}

TEST(ReadPointCloud, ReadsAsciiPcdWithExtraField) {
  test::ScratchDir dir;
  const std::filesystem::path path = dir / "fixture.pcd";
  WriteText(path,
            "# .PCD v0.7 - Point Cloud Data file format\n"
            "VERSION 0.7\n"
            "FIELDS x y z intensity\n"
            "SIZE 4 4 4 4\n"
            "TYPE F F F F\n"
            "COUNT 1 1 1 1\n"
            "WIDTH 4\n"
            "HEIGHT 1\n"
            "VIEWPOINT 0 0 0 1 0 0 0\n"
            "POINTS 4\n"
            "DATA ascii\n"
            "1 2 3 0.5\n"
            "-1.5 0.25 8 0.5\n"
            "0 0 -0.75 1\n"
            "1024 -2048 0.0625 0\n");
  const PointCloud cloud = ReadPointCloud(path);
  ASSERT_EQ(cloud.points_m.size(), 4U);
  EXPECT_EQ(cloud.points_m[0], Eigen::Vector3d(1.0, 2.0, 3.0));
  EXPECT_EQ(cloud.points_m[1], Eigen::Vector3d(-1.5, 0.25, 8.0));
  EXPECT_EQ(cloud.points_m[2], Eigen::Vector3d(0.0, 0.0, -0.75));
  EXPECT_EQ(cloud.points_m[3], Eigen::Vector3d(1024.0, -2048.0, 0.0625));
}

TEST(ReadPointCloud, RejectsMissingFile) {
  test::ScratchDir dir;
  test::ExpectReadError(dir / "absent.ply", "no such file");
  test::ExpectReadError(dir / "absent.pcd", "no such file");
}

TEST(ReadPointCloud, RejectsADirectory) {
  test::ScratchDir dir;
  std::filesystem::create_directory(dir / "folder.ply");
  test::ExpectReadError(dir / "folder.ply", "not a regular file");
}

TEST(ReadPointCloud, RejectsUnknownExtension) {
  test::ScratchDir dir;
  for (const std::string name : {"cloud.xyz", "cloud.txt", "cloud"}) {  // .las: las_file_test.cpp
    WriteText(dir / name, "1 2 3\n");
    test::ExpectReadError(dir / name, "unknown extension");
  }
}

TEST(ReadPointCloud, RejectsGarbageContent) {
  test::ScratchDir dir;
  const std::string garbage = "this is not a point cloud\n\x01\x02\x03 binary junk \xff\xfe\n";
  WriteText(dir / "garbage.ply", garbage);
  WriteText(dir / "garbage.pcd", garbage);
  test::ExpectReadError(dir / "garbage.ply", "not a PLY file (the first line is not 'ply')");
  test::ExpectReadError(dir / "garbage.pcd", "line 1: unknown PCD header key 'this'");  // PCL's parser accepts anything
}

TEST(ReadPointCloud, RejectsEmptyFiles) {
  test::ScratchDir dir;
  WriteText(dir / "empty.ply", "");
  WriteText(dir / "empty.pcd", "");
  test::ExpectReadError(dir / "empty.ply", "not a PLY file");
  test::ExpectReadError(dir / "empty.pcd", "no DATA line");
}

TEST(ReadPointCloud, RejectsHeaderOnlyPly) {
  test::ScratchDir dir;
  WriteText(dir / "header_only.ply",
            "ply\nformat ascii 1.0\nelement vertex 0\n"
            "property float x\nproperty float y\nproperty float z\nend_header\n");
  test::ExpectReadError(dir / "header_only.ply", "holds no points");
}

TEST(ReadPointCloud, RejectsHeaderOnlyPcd) {
  test::ScratchDir dir;
  WriteText(dir / "header_only.pcd",
            "VERSION 0.7\nFIELDS x y z\nSIZE 4 4 4\nTYPE F F F\nCOUNT 1 1 1\n"
            "WIDTH 0\nHEIGHT 1\nVIEWPOINT 0 0 0 1 0 0 0\nPOINTS 0\nDATA ascii\n");
  test::ExpectReadError(dir / "header_only.pcd", "holds no points");
}

TEST(ReadPointCloud, RejectsPcdWithoutDataLine) {
  test::ScratchDir dir;
  WriteText(dir / "no_data.pcd",
            "VERSION 0.7\nFIELDS x y z\nSIZE 4 4 4\nTYPE F F F\nCOUNT 1 1 1\n"
            "WIDTH 1\nHEIGHT 1\nVIEWPOINT 0 0 0 1 0 0 0\nPOINTS 1\n1 2 3\n");
  test::ExpectReadError(dir / "no_data.pcd", "line 10: a number where a header key is expected: the PCD header has no DATA line");
}

class TruncatedCloud : public ::testing::TestWithParam<std::string> {};

TEST_P(TruncatedCloud, IsRejectedNotMisread) {
  test::ScratchDir dir;
  const std::filesystem::path path = dir / ("cloud" + GetParam());
  WritePointCloud(RandomCloud(100, 5), path);
  // Cut the binary body in half (PCL pads binary PCD files, so cut relative to the header end).
  std::ifstream in(path, std::ios::binary);
  const std::string text((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
  const std::string header_end = GetParam() == ".ply" ? "end_header\n" : "DATA binary\n";
  const std::size_t body = text.find(header_end);
  ASSERT_NE(body, std::string::npos);
  std::filesystem::resize_file(path, body + header_end.size() + 100 * 24 / 2);
  EXPECT_THROW(ReadPointCloud(path), PointCloudError);
}

INSTANTIATE_TEST_SUITE_P(Formats, TruncatedCloud, ::testing::Values(".ply", ".pcd"));

TEST(ReadPointCloud, RejectsCloudWithoutZ) {
  test::ScratchDir dir;
  WriteText(dir / "flat.pcd",
            "VERSION 0.7\nFIELDS x y\nSIZE 4 4\nTYPE F F\nCOUNT 1 1\n"
            "WIDTH 2\nHEIGHT 1\nVIEWPOINT 0 0 0 1 0 0 0\nPOINTS 2\nDATA ascii\n1 2\n3 4\n");
  test::ExpectReadError(dir / "flat.pcd", "no 'z' field");
}

TEST(ReadPointCloud, RejectsNonFinitePointsAndCountsThem) {
  test::ScratchDir dir;
  WriteText(dir / "nan.pcd",
            "VERSION 0.7\nFIELDS x y z\nSIZE 4 4 4\nTYPE F F F\nCOUNT 1 1 1\n"
            "WIDTH 5\nHEIGHT 1\nVIEWPOINT 0 0 0 1 0 0 0\nPOINTS 5\nDATA ascii\n"
            "1 2 3\nnan 0 0\n4 5 6\n0 0 nan\n7 8 9\n");
  test::ExpectReadError(dir / "nan.pcd", "2 of 5 points have non-finite");
}

TEST(ReadPointCloud, RejectsNonFinitePointsInBinaryPly) {
  test::ScratchDir dir;
  const std::filesystem::path path = dir / "nan.ply";
  const double values[2][3] = {{1.0, 2.0, 3.0}, {std::numeric_limits<double>::infinity(), 0.0, 0.0}};
  {
    std::ofstream out(path, std::ios::binary);
    out << "ply\nformat binary_little_endian 1.0\nelement vertex 2\n"
           "property double x\nproperty double y\nproperty double z\nend_header\n";
    out.write(reinterpret_cast<const char*>(values), sizeof values);
  }
  test::ExpectReadError(path, "1 of 2 points have non-finite");
}

TEST(WritePointCloud, RejectsBadInput) {
  test::ScratchDir dir;
  const PointCloud good = RandomCloud(3, 1);
  EXPECT_THROW(WritePointCloud(PointCloud{}, dir / "empty.ply"), PointCloudError);
  EXPECT_THROW(WritePointCloud(good, dir / "cloud.xyz"), PointCloudError);
  EXPECT_THROW(WritePointCloud(good, dir / "missing" / "cloud.ply"), PointCloudError);
  EXPECT_THROW(WritePointCloud(good, dir / "missing" / "cloud.pcd"), PointCloudError);
  PointCloud with_nan = good;
  with_nan.points_m[1].y() = std::nan("");
  try {
    WritePointCloud(with_nan, dir / "nan.pcd");
    ADD_FAILURE() << "no error for a NaN point";
  } catch (const PointCloudError& e) {
    EXPECT_THAT(e.what(), HasSubstr("1 of 3 points have non-finite"));
  }
  EXPECT_FALSE(std::filesystem::exists(dir / "nan.pcd"));
}

TEST(WriteTriangleMeshPly, WritesAMeshThatReadsBackAndRefusesBadMeshes) {
  test::ScratchDir dir;
  const std::vector<Eigen::Vector3d> vertices = {{0, 0, 0}, {1, 0, 0}, {0, 1, 0}, {0, 0, 1}};
  const std::vector<std::array<int, 3>> triangles = {{0, 2, 1}, {0, 1, 3}, {1, 2, 3}, {0, 3, 2}};
  WriteTriangleMeshPly(vertices, triangles, dir / "tetra.ply");
  EXPECT_EQ(ReadPointCloud(dir / "tetra.ply").points_m, vertices);  // exact: small coordinates in float
  const auto refused = [&](const std::vector<Eigen::Vector3d>& v, const std::vector<std::array<int, 3>>& t,
                           const std::string& name, const std::string& reason) {
    try {
      WriteTriangleMeshPly(v, t, dir / name);
      ADD_FAILURE() << "accepted: " << reason;
    } catch (const PointCloudError& e) {
      EXPECT_THAT(e.what(), HasSubstr(reason));
      EXPECT_FALSE(std::filesystem::exists(dir / name)) << name;
    }
  };
  refused(vertices, triangles, "tetra.pcd", "a mesh is written as .ply only");
  refused({}, triangles, "empty.ply", "refusing to write an empty mesh");
  refused(vertices, {}, "empty.ply", "refusing to write an empty mesh");
  refused(vertices, {{0, 1, 4}}, "bad.ply", "a triangle refers to vertex 4 of 4");
  refused(vertices, {{0, -1, 2}}, "bad.ply", "a triangle refers to vertex -1 of 4");
  refused({{0, 0, 0}, {1, 0, std::nan("")}, {0, 1, 0}}, {{0, 1, 2}}, "nan.ply", "non-finite");
}

}  // namespace
}  // namespace rowloc::mapping
