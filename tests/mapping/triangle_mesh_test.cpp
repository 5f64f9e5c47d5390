// Tests of the test meshes and of ValidateTriangleMesh (mapping/triangle_mesh.hpp): the box and
// the prism are closed 2-manifolds, outward oriented, with the right volume; each invalid mesh is
// reported.
#include "rowloc/mapping/triangle_mesh.hpp"

#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include <Eigen/Geometry>

#include <cmath>
#include <limits>
#include <map>
#include <numbers>
#include <utility>

namespace rowloc::mapping {
namespace {

using ::testing::HasSubstr;
using ::testing::Optional;

/// Closed, consistently oriented 2-manifold: every directed edge appears exactly once and its
/// reverse exactly once.
void ExpectClosedAndConsistentlyOriented(const TriangleMesh& mesh) {
  std::map<std::pair<int, int>, int> directed;
  for (const auto& t : mesh.triangles) {
    for (int k = 0; k < 3; ++k) ++directed[{t[static_cast<std::size_t>(k)], t[static_cast<std::size_t>((k + 1) % 3)]}];
  }
  for (const auto& [edge, count] : directed) {
    EXPECT_EQ(count, 1) << "edge " << edge.first << "->" << edge.second;
    const auto reverse = directed.find({edge.second, edge.first});
    EXPECT_TRUE(reverse != directed.end()) << "edge " << edge.first << "->" << edge.second
                                           << " has no opposite (hole)";
  }
}

/// Enclosed volume by the divergence theorem: sum over triangles of a . (b x c) / 6.
double SignedVolume(const TriangleMesh& mesh) {
  double six_volume = 0.0;
  for (const auto& t : mesh.triangles) {
    const Eigen::Vector3d& a = mesh.vertices_m[static_cast<std::size_t>(t[0])];
    const Eigen::Vector3d& b = mesh.vertices_m[static_cast<std::size_t>(t[1])];
    const Eigen::Vector3d& c = mesh.vertices_m[static_cast<std::size_t>(t[2])];
    six_volume += a.dot(b.cross(c));
  }
  return six_volume / 6.0;
}

/// For a convex mesh: every face normal points away from an interior point.
void ExpectOutwardNormals(const TriangleMesh& mesh, const Eigen::Vector3d& interior) {
  for (const auto& t : mesh.triangles) {
    const Eigen::Vector3d& a = mesh.vertices_m[static_cast<std::size_t>(t[0])];
    const Eigen::Vector3d& b = mesh.vertices_m[static_cast<std::size_t>(t[1])];
    const Eigen::Vector3d& c = mesh.vertices_m[static_cast<std::size_t>(t[2])];
    EXPECT_GT((b - a).cross(c - a).dot((a + b + c) / 3.0 - interior), 0.0);
  }
}

TEST(MakeBoxMesh, IsAClosedOutwardBoxWithTheRightVolume) {
  const Eigen::Vector3d lo(-1.0, 2.0, 0.5);
  const Eigen::Vector3d hi(3.0, 2.5, 4.0);
  const TriangleMesh box = MakeBoxMesh(lo, hi);
  EXPECT_EQ(box.vertices_m.size(), 8U);
  EXPECT_EQ(box.triangles.size(), 12U);
  EXPECT_EQ(ValidateTriangleMesh(box), std::nullopt);
  ExpectClosedAndConsistentlyOriented(box);
  ExpectOutwardNormals(box, (lo + hi) / 2.0);
  EXPECT_NEAR(SignedVolume(box), 4.0 * 0.5 * 3.5, 1e-12);
  for (const Eigen::Vector3d& v : box.vertices_m) {
    for (int axis = 0; axis < 3; ++axis) EXPECT_TRUE(v[axis] == lo[axis] || v[axis] == hi[axis]);
  }
}

TEST(MakeBoxMesh, RejectsEmptyOrNonFiniteBoxes) {
  EXPECT_THROW(MakeBoxMesh(Eigen::Vector3d::Zero(), Eigen::Vector3d(1.0, 0.0, 1.0)), std::invalid_argument);
  EXPECT_THROW(MakeBoxMesh(Eigen::Vector3d::Ones(), Eigen::Vector3d::Zero()), std::invalid_argument);
  EXPECT_THROW(MakeBoxMesh(Eigen::Vector3d::Zero(),
                           Eigen::Vector3d(1.0, 1.0, std::numeric_limits<double>::infinity())),
               std::invalid_argument);
  EXPECT_THROW(MakeBoxMesh(Eigen::Vector3d(std::nan(""), 0.0, 0.0), Eigen::Vector3d::Ones()),
               std::invalid_argument);
}

class CylinderMesh : public ::testing::TestWithParam<int> {};

TEST_P(CylinderMesh, IsAClosedOutwardPrismWithTheInscribedPolygonVolume) {
  const int sides = GetParam();
  const Eigen::Vector3d base(10.0, -5.0, 0.25);
  const double radius_m = 0.4;
  const double height_m = 1.7;
  const TriangleMesh mesh = MakeCylinderMesh(base, radius_m, height_m, sides);
  EXPECT_EQ(mesh.vertices_m.size(), static_cast<std::size_t>(2 * sides + 2));
  EXPECT_EQ(mesh.triangles.size(), static_cast<std::size_t>(4 * sides));
  EXPECT_EQ(ValidateTriangleMesh(mesh), std::nullopt);
  ExpectClosedAndConsistentlyOriented(mesh);
  ExpectOutwardNormals(mesh, base + Eigen::Vector3d(0.0, 0.0, height_m / 2.0));
  const double polygon_area = 0.5 * sides * radius_m * radius_m * std::sin(2.0 * std::numbers::pi / sides);
  EXPECT_NEAR(SignedVolume(mesh), polygon_area * height_m, 1e-12);
  for (const Eigen::Vector3d& v : mesh.vertices_m) {
    const double r = (v - base).head<2>().norm();
    EXPECT_TRUE(std::abs(r - radius_m) < 1e-12 || r < 1e-12);  // ring vertex or cap centre
    EXPECT_TRUE(v.z() == base.z() || std::abs(v.z() - (base.z() + height_m)) < 1e-12);
  }
}

INSTANTIATE_TEST_SUITE_P(Sides, CylinderMesh, ::testing::Values(3, 4, 7, 32, 100));

TEST(MakeCylinderMesh, RejectsBadParameters) {
  const Eigen::Vector3d c = Eigen::Vector3d::Zero();
  EXPECT_THROW(MakeCylinderMesh(c, 0.0, 1.0, 8), std::invalid_argument);
  EXPECT_THROW(MakeCylinderMesh(c, -1.0, 1.0, 8), std::invalid_argument);
  EXPECT_THROW(MakeCylinderMesh(c, 1.0, 0.0, 8), std::invalid_argument);
  EXPECT_THROW(MakeCylinderMesh(c, 1.0, 1.0, 2), std::invalid_argument);
  EXPECT_THROW(MakeCylinderMesh(c, std::nan(""), 1.0, 8), std::invalid_argument);
  EXPECT_THROW(MakeCylinderMesh(c, 1.0, std::numeric_limits<double>::infinity(), 8),
               std::invalid_argument);
  EXPECT_THROW(MakeCylinderMesh(Eigen::Vector3d(0.0, std::nan(""), 0.0), 1.0, 1.0, 8),
               std::invalid_argument);
}

TriangleMesh OneTriangle() {
  return TriangleMesh{{Eigen::Vector3d(0, 0, 0), Eigen::Vector3d(1, 0, 0), Eigen::Vector3d(0, 1, 0)},
                      {{0, 1, 2}}};
}

TEST(ValidateTriangleMesh, AcceptsAnOpenSingleTriangle) {
  EXPECT_EQ(ValidateTriangleMesh(OneTriangle()), std::nullopt);
}

TEST(ValidateTriangleMesh, ReportsEachProblem) {
  TriangleMesh mesh = OneTriangle();
  mesh.triangles.clear();
  EXPECT_THAT(ValidateTriangleMesh(mesh), Optional(HasSubstr("no triangles")));

  mesh = OneTriangle();
  mesh.triangles[0][2] = 3;
  EXPECT_THAT(ValidateTriangleMesh(mesh), Optional(HasSubstr("out of range")));
  mesh.triangles[0][2] = -1;
  EXPECT_THAT(ValidateTriangleMesh(mesh), Optional(HasSubstr("out of range")));

  mesh = OneTriangle();
  mesh.triangles[0] = {0, 1, 0};
  EXPECT_THAT(ValidateTriangleMesh(mesh), Optional(HasSubstr("repeats a vertex")));

  mesh = OneTriangle();
  mesh.vertices_m[2] = Eigen::Vector3d(2.0, 0.0, 0.0);  // collinear
  EXPECT_THAT(ValidateTriangleMesh(mesh), Optional(HasSubstr("degenerate")));
  mesh.vertices_m[2] = mesh.vertices_m[1];  // coincident
  EXPECT_THAT(ValidateTriangleMesh(mesh), Optional(HasSubstr("degenerate")));

  mesh = OneTriangle();
  mesh.vertices_m[1].x() = std::numeric_limits<double>::infinity();
  EXPECT_THAT(ValidateTriangleMesh(mesh), Optional(HasSubstr("vertex 1 is not finite")));
  mesh.vertices_m.push_back(Eigen::Vector3d(std::nan(""), 0.0, 0.0));  // unused, still reported
  mesh.vertices_m[1].x() = 1.0;
  EXPECT_THAT(ValidateTriangleMesh(mesh), Optional(HasSubstr("vertex 3 is not finite")));
}

TEST(ValidateTriangleMesh, DegeneracyIsScaleInvariant) {
  // A small but well-shaped triangle (1 mm) is valid; a needle 1e-13 wide is not, at any scale.
  for (const double scale : {1e-3, 1.0, 1e4}) {
    TriangleMesh mesh = OneTriangle();
    for (auto& v : mesh.vertices_m) v *= scale;
    EXPECT_EQ(ValidateTriangleMesh(mesh), std::nullopt) << scale;
    mesh.vertices_m[2] = Eigen::Vector3d(0.5, 1e-13, 0.0) * scale;
    EXPECT_NE(ValidateTriangleMesh(mesh), std::nullopt) << scale;
  }
}

}  // namespace
}  // namespace rowloc::mapping
