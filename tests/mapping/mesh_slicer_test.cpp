// Tests of SliceMesh (mapping/mesh_slicer.hpp) on the box and prism test meshes: the slice lies on
// the plane and on the surface, with the right perimeter and area; misses, tilted planes, open
// meshes and invalid input.
#include "rowloc/mapping/mesh_slicer.hpp"

#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include <Eigen/Geometry>

#include <cmath>
#include <limits>
#include <numbers>

namespace rowloc::mapping {
namespace {

using ::testing::HasSubstr;

double Perimeter(const Polyline3& polygon) {
  double length = 0.0;
  const std::size_t n = polygon.points_m.size();
  for (std::size_t i = 0; i < n; ++i) length += (polygon.points_m[(i + 1) % n] - polygon.points_m[i]).norm();
  return length;
}

/// Area of a closed planar polygon, signed: positive when counter-clockwise seen from the tip of
/// unit_normal (vector area 1/2 sum p_i x p_{i+1}, projected on the normal).
double SignedArea(const Polyline3& polygon, const Eigen::Vector3d& unit_normal) {
  Eigen::Vector3d twice_area = Eigen::Vector3d::Zero();
  const std::size_t n = polygon.points_m.size();
  for (std::size_t i = 0; i < n; ++i) twice_area += polygon.points_m[i].cross(polygon.points_m[(i + 1) % n]);
  return 0.5 * twice_area.dot(unit_normal);
}

bool Contains(const Polyline3& polygon, const Eigen::Vector3d& point, double tol) {
  for (const Eigen::Vector3d& p : polygon.points_m) {
    if ((p - point).norm() < tol) return true;
  }
  return false;
}

const Eigen::Vector3d kBoxMin(0.0, 0.0, 0.0);
const Eigen::Vector3d kBoxMax(2.0, 1.0, 3.0);

TEST(SliceMesh, BoxAtMidHeightIsItsRectangle) {
  const std::vector<Polyline3> slices = SliceMesh(MakeBoxMesh(kBoxMin, kBoxMax), Eigen::Vector3d::UnitZ(), 1.5);
  ASSERT_EQ(slices.size(), 1U);
  const Polyline3& rect = slices[0];
  EXPECT_TRUE(rect.closed);
  ASSERT_GE(rect.points_m.size(), 4U);
  EXPECT_NE(rect.points_m.front(), rect.points_m.back());  // closing point not repeated
  for (const Eigen::Vector3d& p : rect.points_m) {
    EXPECT_NEAR(p.z(), 1.5, 1e-12);
    const bool on_x_side = std::abs(p.x()) < 1e-12 || std::abs(p.x() - 2.0) < 1e-12;
    const bool on_y_side = std::abs(p.y()) < 1e-12 || std::abs(p.y() - 1.0) < 1e-12;
    EXPECT_TRUE(on_x_side || on_y_side) << p.transpose();
    EXPECT_TRUE((p.array() >= kBoxMin.array() - 1e-12).all() && (p.array() <= kBoxMax.array() + 1e-12).all());
  }
  for (const Eigen::Vector3d& corner : {Eigen::Vector3d(0, 0, 1.5), Eigen::Vector3d(2, 0, 1.5),
                                       Eigen::Vector3d(2, 1, 1.5), Eigen::Vector3d(0, 1, 1.5)}) {
    EXPECT_TRUE(Contains(rect, corner, 1e-12)) << corner.transpose();
  }
  EXPECT_NEAR(Perimeter(rect), 6.0, 1e-12);
  // An outward-oriented closed surface slices into a counter-clockwise polygon about the normal.
  EXPECT_NEAR(SignedArea(rect, Eigen::Vector3d::UnitZ()), 2.0, 1e-12);
}

TEST(SliceMesh, VerticalPlaneThroughBox) {
  const std::vector<Polyline3> slices = SliceMesh(MakeBoxMesh(kBoxMin, kBoxMax), Eigen::Vector3d::UnitX(), 0.7);
  ASSERT_EQ(slices.size(), 1U);
  EXPECT_TRUE(slices[0].closed);
  EXPECT_NEAR(Perimeter(slices[0]), 8.0, 1e-12);
  EXPECT_NEAR(SignedArea(slices[0], Eigen::Vector3d::UnitX()), 3.0, 1e-12);
  for (const Eigen::Vector3d& p : slices[0].points_m) EXPECT_NEAR(p.x(), 0.7, 1e-12);
}

TEST(SliceMesh, PlaneMissingTheMeshGivesNothing) {
  const TriangleMesh box = MakeBoxMesh(kBoxMin, kBoxMax);
  EXPECT_TRUE(SliceMesh(box, Eigen::Vector3d::UnitZ(), 3.5).empty());
  EXPECT_TRUE(SliceMesh(box, Eigen::Vector3d::UnitZ(), -0.01).empty());
  EXPECT_TRUE(SliceMesh(box, Eigen::Vector3d(1.0, 1.0, 1.0).normalized(), 10.0).empty());
}

TEST(SliceMesh, TiltedPlaneCutsAnEnlargedSectionOnThePlane) {
  // Through the box centre, tilted little enough to cross only the four side walls: the section
  // is the 2 x 1 rectangle seen through the tilt, area 2 / |n_z|.
  const TriangleMesh box = MakeBoxMesh(kBoxMin, kBoxMax);
  const Eigen::Vector3d n = Eigen::Vector3d(0.2, -0.1, 1.0).normalized();
  const double offset = n.dot((kBoxMin + kBoxMax) / 2.0);
  const std::vector<Polyline3> slices = SliceMesh(box, n, offset);
  ASSERT_EQ(slices.size(), 1U);
  EXPECT_TRUE(slices[0].closed);
  for (const Eigen::Vector3d& p : slices[0].points_m) {
    EXPECT_NEAR(n.dot(p), offset, 1e-12);
    EXPECT_TRUE((p.array() >= kBoxMin.array() - 1e-12).all() && (p.array() <= kBoxMax.array() + 1e-12).all());
  }
  EXPECT_NEAR(SignedArea(slices[0], n), 2.0 / n.z(), 1e-12);

  // Scaling the plane equation does not change the slice.
  const std::vector<Polyline3> scaled = SliceMesh(box, 3.0 * n, 3.0 * offset);
  ASSERT_EQ(scaled.size(), 1U);
  ASSERT_EQ(scaled[0].points_m.size(), slices[0].points_m.size());
  for (const Eigen::Vector3d& p : slices[0].points_m) EXPECT_TRUE(Contains(scaled[0], p, 1e-12));
}

TEST(SliceMesh, PlaneThroughAFaceGivesItsBoundary) {
  // CGAL reports the boundary of a face lying in the plane (Polygon_mesh_slicer documentation).
  const std::vector<Polyline3> slices = SliceMesh(MakeBoxMesh(kBoxMin, kBoxMax), Eigen::Vector3d::UnitZ(), 0.0);
  ASSERT_EQ(slices.size(), 1U);
  EXPECT_TRUE(slices[0].closed);
  EXPECT_NEAR(Perimeter(slices[0]), 6.0, 1e-12);
  EXPECT_NEAR(std::abs(SignedArea(slices[0], Eigen::Vector3d::UnitZ())), 2.0, 1e-12);
}

class CylinderSlice : public ::testing::TestWithParam<int> {};

TEST_P(CylinderSlice, SectionIsTheInscribedPolygon) {
  const int sides = GetParam();
  const Eigen::Vector3d base(3.0, -1.0, 0.2);
  const double radius_m = 0.35;
  const TriangleMesh mesh = MakeCylinderMesh(base, radius_m, 1.8, sides);
  const double h = 1.3;
  const std::vector<Polyline3> slices = SliceMesh(mesh, Eigen::Vector3d::UnitZ(), h);
  ASSERT_EQ(slices.size(), 1U);
  const Polyline3& polygon = slices[0];
  EXPECT_TRUE(polygon.closed);
  const double inscribed_area = 0.5 * sides * radius_m * radius_m * std::sin(2.0 * std::numbers::pi / sides);
  const double inscribed_perimeter = 2.0 * sides * radius_m * std::sin(std::numbers::pi / sides);
  EXPECT_NEAR(SignedArea(polygon, Eigen::Vector3d::UnitZ()), inscribed_area, 1e-12);
  EXPECT_NEAR(Perimeter(polygon), inscribed_perimeter, 1e-12);
  const double apothem = radius_m * std::cos(std::numbers::pi / sides);
  for (const Eigen::Vector3d& p : polygon.points_m) {
    EXPECT_NEAR(p.z(), h, 1e-12);
    const double r = (p - base).head<2>().norm();
    EXPECT_LE(r, radius_m + 1e-12);
    EXPECT_GE(r, apothem - 1e-12);
  }
}

INSTANTIATE_TEST_SUITE_P(Sides, CylinderSlice, ::testing::Values(3, 5, 12, 64));

TEST(SliceMesh, OpenMeshGivesOpenPolyline) {
  const TriangleMesh triangle{{Eigen::Vector3d(0, 0, 0), Eigen::Vector3d(2, 0, 0), Eigen::Vector3d(0, 0, 2)},
                              {{0, 1, 2}}};
  const std::vector<Polyline3> slices = SliceMesh(triangle, Eigen::Vector3d::UnitZ(), 1.0);
  ASSERT_EQ(slices.size(), 1U);
  EXPECT_FALSE(slices[0].closed);
  ASSERT_EQ(slices[0].points_m.size(), 2U);
  EXPECT_NEAR(Perimeter(slices[0]) / 2.0, 1.0, 1e-12);  // closed-form length 1, walked twice
}

TEST(SliceMesh, TwoBoxesGiveTwoPolygons) {
  TriangleMesh both = MakeBoxMesh(kBoxMin, kBoxMax);
  const TriangleMesh other = MakeBoxMesh(Eigen::Vector3d(5, 0, 0), Eigen::Vector3d(6, 1, 1));
  const int offset = static_cast<int>(both.vertices_m.size());
  both.vertices_m.insert(both.vertices_m.end(), other.vertices_m.begin(), other.vertices_m.end());
  for (auto t : other.triangles) both.triangles.push_back({t[0] + offset, t[1] + offset, t[2] + offset});
  const std::vector<Polyline3> slices = SliceMesh(both, Eigen::Vector3d::UnitZ(), 0.5);
  ASSERT_EQ(slices.size(), 2U);
  double total_area = 0.0;
  for (const Polyline3& s : slices) {
    EXPECT_TRUE(s.closed);
    total_area += SignedArea(s, Eigen::Vector3d::UnitZ());
  }
  EXPECT_NEAR(total_area, 2.0 + 1.0, 1e-12);
}

TEST(SliceMesh, RejectsInvalidMeshes) {
  TriangleMesh bad = MakeBoxMesh(kBoxMin, kBoxMax);
  bad.triangles[3][1] = 99;
  EXPECT_THROW(SliceMesh(bad, Eigen::Vector3d::UnitZ(), 1.0), InvalidMeshError);
  bad = MakeBoxMesh(kBoxMin, kBoxMax);
  bad.vertices_m[2].z() = std::nan("");
  EXPECT_THROW(SliceMesh(bad, Eigen::Vector3d::UnitZ(), 1.0), InvalidMeshError);
  EXPECT_THROW(SliceMesh(TriangleMesh{}, Eigen::Vector3d::UnitZ(), 1.0), InvalidMeshError);
  bad = MakeBoxMesh(kBoxMin, kBoxMax);
  bad.triangles[5] = {1, 1, 2};
  EXPECT_THROW(SliceMesh(bad, Eigen::Vector3d::UnitZ(), 1.0), InvalidMeshError);
}

TEST(SliceMesh, RejectsNonManifoldAndInconsistentlyOrientedSurfaces) {
  // Three triangles on one edge (0-1): not a 2-manifold.
  const TriangleMesh fin{{Eigen::Vector3d(0, 0, 0), Eigen::Vector3d(1, 0, 0), Eigen::Vector3d(0, 1, 0),
                          Eigen::Vector3d(0, -1, 0), Eigen::Vector3d(0, 0, 1)},
                         {{0, 1, 2}, {1, 0, 3}, {0, 1, 4}}};
  try {
    SliceMesh(fin, Eigen::Vector3d::UnitZ(), 0.5);
    ADD_FAILURE() << "no error for a non-manifold edge";
  } catch (const InvalidMeshError& e) {
    EXPECT_THAT(e.what(), HasSubstr("triangle 2"));
  }
  // Two triangles using edge 0->1 in the same direction: flipped neighbour.
  const TriangleMesh flipped{{Eigen::Vector3d(0, 0, 0), Eigen::Vector3d(1, 0, 0), Eigen::Vector3d(0, 1, 1),
                              Eigen::Vector3d(0, -1, 1)},
                             {{0, 1, 2}, {0, 1, 3}}};
  EXPECT_THROW(SliceMesh(flipped, Eigen::Vector3d::UnitZ(), 0.5), InvalidMeshError);
}

TEST(SliceMesh, RejectsBadPlanes) {
  const TriangleMesh box = MakeBoxMesh(kBoxMin, kBoxMax);
  const double nan = std::numeric_limits<double>::quiet_NaN();
  const double inf = std::numeric_limits<double>::infinity();
  EXPECT_THROW(SliceMesh(box, Eigen::Vector3d::Zero(), 1.0), std::invalid_argument);
  EXPECT_THROW(SliceMesh(box, Eigen::Vector3d(0.0, nan, 1.0), 1.0), std::invalid_argument);
  EXPECT_THROW(SliceMesh(box, Eigen::Vector3d(0.0, inf, 1.0), 1.0), std::invalid_argument);
  EXPECT_THROW(SliceMesh(box, Eigen::Vector3d::UnitZ(), nan), std::invalid_argument);
  EXPECT_THROW(SliceMesh(box, Eigen::Vector3d::UnitZ(), -inf), std::invalid_argument);
}

}  // namespace
}  // namespace rowloc::mapping
