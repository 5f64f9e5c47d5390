// DropCollinearVertices: dense straight runs collapse to their ends, every dropped vertex lies within
// the tolerance of the chord that replaced it, curves and turn-backs are kept.
#include "rowloc/geometry/collinear_vertices.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <numbers>
#include <random>

namespace rowloc::geometry {
namespace {

/// Distance from p to the segment [a, b].
double DistanceToSegment(const Eigen::Vector2d& p, const Eigen::Vector2d& a, const Eigen::Vector2d& b) {
  const Eigen::Vector2d ab = b - a;
  const double t = ab.squaredNorm() > 0.0 ? std::clamp((p - a).dot(ab) / ab.squaredNorm(), 0.0, 1.0) : 0.0;
  return (a + t * ab - p).norm();
}

/// Checks that kept is an ordered subsequence of points and that every dropped vertex lies within
/// tol of the kept chord spanning it.
void ExpectWithinTolerance(const std::vector<Eigen::Vector2d>& points, const std::vector<Eigen::Vector2d>& kept,
                           bool closed, double tol) {
  std::vector<Eigen::Vector2d> path = points, kept_path = kept;
  if (closed) {
    path.push_back(points.front());
    kept_path.push_back(kept.front());
  }
  std::size_t k = 0;  // kept_path[k] == path[i] for the last kept i
  ASSERT_EQ(kept_path.front(), path.front());
  for (std::size_t i = 1; i < path.size(); ++i) {
    if (k + 1 < kept_path.size() && path[i] == kept_path[k + 1]) {
      ++k;
      continue;
    }
    ASSERT_LT(k + 1, kept_path.size());
    EXPECT_LE(DistanceToSegment(path[i], kept_path[k], kept_path[k + 1]), tol * (1 + 1e-9)) << i;
  }
  EXPECT_EQ(k + 1, kept_path.size());
}

TEST(DropCollinearVertices, DenseStraightRowCollapsesToItsEnds) {
  std::vector<Eigen::Vector2d> line;
  for (int i = 0; i < 10000; ++i) line.emplace_back(0.005 * i, 0.0);
  const auto kept = DropCollinearVertices(line, false, 1e-6);
  ASSERT_EQ(kept.size(), 2u);
  EXPECT_EQ(kept.front(), line.front());
  EXPECT_EQ(kept.back(), line.back());
}

TEST(DropCollinearVertices, DenseRectangleKeepsItsCorners) {
  std::vector<Eigen::Vector2d> ring;
  for (int i = 0; i < 1000; ++i) ring.emplace_back(0.05 * i, 0.0);
  for (int i = 0; i < 10; ++i) ring.emplace_back(50.0, 0.05 * i);
  for (int i = 0; i < 1000; ++i) ring.emplace_back(50.0 - 0.05 * i, 0.5);
  for (int i = 0; i < 10; ++i) ring.emplace_back(0.0, 0.5 - 0.05 * i);
  const auto kept = DropCollinearVertices(ring, true, 1e-6);
  EXPECT_EQ(kept.size(), 4u);
  ExpectWithinTolerance(ring, kept, true, 1e-6);
}

TEST(DropCollinearVertices, CurvesAndTurnBacksAreKept) {
  std::vector<Eigen::Vector2d> arc;
  for (int i = 0; i < 100; ++i) arc.emplace_back(std::cos(0.01 * i), std::sin(0.01 * i));  // sag 1.25e-5 m
  EXPECT_EQ(DropCollinearVertices(arc, false, 1e-6).size(), arc.size());
  const std::vector<Eigen::Vector2d> zigzag{{0, 0}, {1, 0}, {0, 0}, {1, 0}, {0, 0}};
  EXPECT_EQ(DropCollinearVertices(zigzag, false, 1e-6).size(), zigzag.size());
  const std::vector<Eigen::Vector2d> triangle{{0, 0}, {1, 0}, {0, 1}};
  EXPECT_EQ(DropCollinearVertices(triangle, true, 1e-6), triangle);
}

TEST(DropCollinearVertices, EveryDroppedVertexIsWithinTheTolerance) {
  // Property over noisy straight and gently curved paths: the guarantee holds for any input.
  std::mt19937 rng(7);
  std::normal_distribution<double> noise(0.0, 1e-6);
  for (int trial = 0; trial < 50; ++trial) {
    const double curvature = 1e-4 * trial;
    std::vector<Eigen::Vector2d> path;
    for (int i = 0; i < 2000; ++i) {
      const double s = 0.01 * i;
      path.emplace_back(s + noise(rng), 0.5 * curvature * s * s + noise(rng));
    }
    for (const double tol : {1e-6, 1e-5, 1e-3}) {
      ExpectWithinTolerance(path, DropCollinearVertices(path, false, tol), false, tol);
    }
  }
}

}  // namespace
}  // namespace rowloc::geometry
