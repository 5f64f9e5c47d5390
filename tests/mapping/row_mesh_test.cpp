// LoftRings and TriangulatePolygon: a lofted frustum is closed, outward, of the right volume, and
// CGAL's slicer cuts it on the interpolated ring; polygon triangulations cover the polygon; bad
// input is refused.
#include "rowloc/mapping/row_mesh.hpp"

#include "rowloc/mapping/mesh_slicer.hpp"
#include "rowloc/mapping/polyline_simplification.hpp"

#include <gtest/gtest.h>

#include <Eigen/Geometry>

#include <cmath>
#include <map>
#include <stdexcept>
#include <utility>

namespace rowloc::mapping {
namespace {

std::vector<Eigen::Vector2d> Square(double half, bool clockwise = false) {
  std::vector<Eigen::Vector2d> ring = {{-half, -half}, {half, -half}, {half, half}, {-half, half}};
  if (clockwise) std::reverse(ring.begin(), ring.end());
  return ring;
}

/// Volume by the divergence theorem (sum of signed tetrahedra from the origin).
double Volume(const TriangleMesh& mesh) {
  double v = 0.0;
  for (const auto& t : mesh.triangles) {
    v += mesh.vertices_m[static_cast<std::size_t>(t[0])].dot(
             mesh.vertices_m[static_cast<std::size_t>(t[1])].cross(mesh.vertices_m[static_cast<std::size_t>(t[2])])) /
         6.0;
  }
  return v;
}

TEST(LoftRings, AFrustumIsClosedOutwardAndOfItsVolume) {
  // Squares of side 2 at h = 0, 1.5 at h = 0.5 and 1 at h = 1 (the middle one given clockwise):
  // a frustum of volume h/3 (A1 + A2 + sqrt(A1 A2)) = 7/3.
  const std::optional<TriangleMesh> mesh =
      LoftRings({{0.0, Square(1.0)}, {0.5, Square(0.75, true)}, {1.0, Square(0.5)}}, 0.5);
  ASSERT_TRUE(mesh.has_value());
  EXPECT_FALSE(ValidateTriangleMesh(*mesh).has_value());
  EXPECT_EQ(mesh->vertices_m.size(), 3U * 16U);       // M = perimeter 8 / 0.5 m
  EXPECT_EQ(mesh->triangles.size(), 2U * 16U * 2U + 2U * 14U);
  EXPECT_NEAR(Volume(*mesh), 7.0 / 3.0, 1e-12);
  // Closed and consistently oriented: every directed edge appears once, its reverse once.
  std::map<std::pair<int, int>, int> edges;
  for (const auto& t : mesh->triangles) {
    for (int k = 0; k < 3; ++k) ++edges[{t[static_cast<std::size_t>(k)], t[static_cast<std::size_t>((k + 1) % 3)]}];
  }
  for (const auto& [edge, count] : edges) {
    EXPECT_EQ(count, 1);
    EXPECT_EQ(edges.count({edge.second, edge.first}), 1U);
  }
}

TEST(LoftRings, TheSlicerCutsTheInterpolatedRing) {
  const std::optional<TriangleMesh> mesh = LoftRings({{0.6, Square(1.0)}, {1.6, Square(0.5)}}, 0.25);
  ASSERT_TRUE(mesh.has_value());
  for (const double h : {0.6 + 1e-9, 0.85, 1.1, 1.6 - 1e-9}) {
    const std::vector<Polyline3> slices = SliceMesh(*mesh, Eigen::Vector3d::UnitZ(), h);
    ASSERT_EQ(slices.size(), 1U) << h;
    ASSERT_TRUE(slices.front().closed);
    const double half = 1.0 - 0.5 * (h - 0.6);  // linear between the rings
    for (const auto& p : slices.front().points_m) {
      EXPECT_NEAR(std::max(std::abs(p.x()), std::abs(p.y())), half, 1e-9) << h;
      EXPECT_NEAR(p.z(), h, 1e-12);
    }
  }
  EXPECT_TRUE(SliceMesh(*mesh, Eigen::Vector3d::UnitZ(), 1.7).empty());  // above the top ring
}

TEST(LoftRings, RingsStartWhereThePreviousOneStartsSoTheSidesDoNotTwist) {
  // The same square given from different starting corners: every side triangle stays vertical-ish,
  // i.e. matching vertices lie above each other.
  std::vector<Eigen::Vector2d> rotated = Square(1.0);
  std::rotate(rotated.begin(), rotated.begin() + 2, rotated.end());
  const std::optional<TriangleMesh> mesh = LoftRings({{0.0, Square(1.0)}, {1.0, rotated}}, 0.5);
  ASSERT_TRUE(mesh.has_value());
  const std::size_t m = mesh->vertices_m.size() / 2;
  for (std::size_t i = 0; i < m; ++i) {
    EXPECT_NEAR((mesh->vertices_m[i].head<2>() - mesh->vertices_m[m + i].head<2>()).norm(), 0.0, 1e-12);
  }
}

TEST(LoftRings, RefusesBadInputAndAnUntriangulableCap) {
  EXPECT_THROW(LoftRings({{0.0, Square(1.0)}}, 0.5), std::invalid_argument);
  EXPECT_THROW(LoftRings({{1.0, Square(1.0)}, {0.5, Square(1.0)}}, 0.5), std::invalid_argument);
  EXPECT_THROW(LoftRings({{0.0, Square(1.0)}, {1.0, {{0, 0}, {1, 0}}}}, 0.5), std::invalid_argument);
  EXPECT_THROW(LoftRings({{0.0, Square(1.0)}, {1.0, Square(1.0)}}, 0.0), std::invalid_argument);
  EXPECT_THROW(LoftRings({{0.0, Square(1.0)}, {std::nan(""), Square(1.0)}}, 0.5), std::invalid_argument);
  const std::vector<Eigen::Vector2d> bow_tie = {{0, 0}, {2, 2}, {2, 0}, {0, 2}};
  EXPECT_FALSE(LoftRings({{0.0, bow_tie}, {1.0, Square(1.0)}}, 0.5).has_value());
}

/// An outline as TraceOutline makes it: the right edge forward (y = -half), then the left edge back.
std::vector<Eigen::Vector2d> TracedBox(double length, double half, int per_edge) {
  std::vector<Eigen::Vector2d> ring;
  for (int i = 0; i < per_edge; ++i) ring.emplace_back(length * i / (per_edge - 1), -half);
  for (int i = per_edge; i-- > 0;) ring.emplace_back(length * i / (per_edge - 1), half);
  return ring;
}

TEST(LoftRings, TwoEdgeSamplingKeepsTheCornersAndUnswapsAReversedOutline) {
  // Boxes 10 m long, 0.5 then 0.3 m half-width, with different vertex counts; the upper one traced
  // from the other end (its halves swapped, as when the centre line points the other way).
  std::vector<Eigen::Vector2d> upper = TracedBox(10.0, 0.3, 7);
  std::rotate(upper.begin(), upper.begin() + 7, upper.end());
  const std::optional<TriangleMesh> mesh =
      LoftRings({{0.0, TracedBox(10.0, 0.5, 40)}, {1.0, upper}}, 2.0, RingSampling::kTwoEdges);
  ASSERT_TRUE(mesh.has_value());
  EXPECT_FALSE(ValidateTriangleMesh(*mesh).has_value());
  EXPECT_EQ(mesh->vertices_m.size(), 2U * 2U * 6U);  // two rings of two edges of 10 m / 2 m + 1
  // Every cross-section along x is a trapezoid (1.0 m wide at h = 0, 0.6 m at h = 1): volume
  // 10 x (1.0 + 0.6) / 2 x 1 = 8.
  EXPECT_NEAR(Volume(*mesh), 8.0, 1e-9);
  const std::vector<Polyline3> cut = SliceMesh(*mesh, Eigen::Vector3d::UnitZ(), 0.5);
  ASSERT_EQ(cut.size(), 1U);
  for (const auto& p : cut.front().points_m) {
    // Halfway up: the half-width 0.4 m on the long sides, the ends at x = 0 and 10.
    const bool on_side = std::abs(std::abs(p.y()) - 0.4) < 1e-9;
    const bool on_end = std::abs(p.x()) < 1e-9 || std::abs(p.x() - 10.0) < 1e-9;
    EXPECT_TRUE(on_side || on_end) << p.transpose();
  }
  // A clockwise or odd outline is not made like a traced one.
  std::vector<Eigen::Vector2d> clockwise = TracedBox(10.0, 0.5, 4);
  std::reverse(clockwise.begin(), clockwise.end());
  EXPECT_FALSE(LoftRings({{0.0, clockwise}, {1.0, TracedBox(10.0, 0.3, 4)}}, 2.0, RingSampling::kTwoEdges));
  std::vector<Eigen::Vector2d> odd = TracedBox(10.0, 0.5, 4);
  odd.pop_back();
  EXPECT_FALSE(LoftRings({{0.0, odd}, {1.0, TracedBox(10.0, 0.3, 4)}}, 2.0, RingSampling::kTwoEdges));
}

TEST(ResampleRing, PointsAreEquallySpacedOnTheRing) {
  const std::vector<Eigen::Vector2d> ring = ResampleRing(Square(1.0), 1, 10);  // from (1, -1)
  ASSERT_EQ(ring.size(), 10U);
  EXPECT_NEAR((ring.front() - Eigen::Vector2d(1.0, -1.0)).norm(), 0.0, 1e-12);
  for (std::size_t i = 0; i < ring.size(); ++i) {
    // Every point on the square's boundary, 0.8 m of arc after the previous one.
    EXPECT_NEAR(std::max(std::abs(ring[i].x()), std::abs(ring[i].y())), 1.0, 1e-12);
  }
  EXPECT_NEAR((ring[1] - Eigen::Vector2d(1.0, -0.2)).norm(), 0.0, 1e-12);
  EXPECT_THROW(ResampleRing(Square(1.0), 4, 10), std::invalid_argument);
  EXPECT_THROW(ResampleRing({{0, 0}, {0, 0}, {0, 0}}, 0, 10), std::invalid_argument);
}

TEST(TriangulatePolygon, CoversAnLShapeWithCounterClockwiseTriangles) {
  const std::vector<Eigen::Vector2d> l_shape = {{0, 0}, {2, 0}, {2, 1}, {1, 1}, {1, 2}, {0, 2}};
  const std::vector<std::array<int, 3>> triangles = TriangulatePolygon(l_shape);
  ASSERT_EQ(triangles.size(), l_shape.size() - 2);
  double area = 0.0;
  for (const auto& t : triangles) {
    const Eigen::Vector2d a = l_shape[static_cast<std::size_t>(t[0])];
    const Eigen::Vector2d b = l_shape[static_cast<std::size_t>(t[1])];
    const Eigen::Vector2d c = l_shape[static_cast<std::size_t>(t[2])];
    const double signed_area = 0.5 * ((b - a).x() * (c - a).y() - (b - a).y() * (c - a).x());
    EXPECT_GT(signed_area, 0.0);
    area += signed_area;
  }
  EXPECT_NEAR(area, 3.0, 1e-12);  // no triangle in the notch
  EXPECT_TRUE(TriangulatePolygon({{0, 0}, {2, 2}, {2, 0}, {0, 2}}).empty());  // not simple
  EXPECT_TRUE(TriangulatePolygon({{0, 0}, {1, 0}}).empty());
  EXPECT_THROW(TriangulatePolygon({{0, 0}, {1, std::nan("")}, {0, 1}}), std::invalid_argument);
}

}  // namespace
}  // namespace rowloc::mapping
