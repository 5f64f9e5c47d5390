// RowMap: ValidateRowMap (each rejected case and the accepted edge cases) and the synthetic
// sample map (geometry of rows checked against MakeSampleRowMap's stated construction).
#include "rowloc/geometry/row_map.hpp"

#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <limits>
#include <stdexcept>

namespace rowloc::geometry {
namespace {

using ::testing::HasSubstr;

constexpr double kNaN = std::numeric_limits<double>::quiet_NaN();
constexpr double kInf = std::numeric_limits<double>::infinity();

RowMap ValidMap() {
  RowMap map;
  map.origin = GeoOrigin{45.0, 7.0, 200.0};
  map.rows.push_back(Row{"open", {{0.0, 0.0}, {10.0, 0.0}}, false, 0.0});
  map.rows.push_back(Row{"triangle", {{0.0, 2.0}, {1.0, 2.0}, {0.0, 3.0}}, true, 0.0});
  return map;
}

/// The problem ValidateRowMap reports (the test fails if there is none).
std::string ProblemOf(const RowMap& map) {
  const std::optional<std::string> problem = ValidateRowMap(map);
  EXPECT_TRUE(problem.has_value());
  return problem.value_or("");
}

TEST(ValidateRowMap, AcceptsMinimalRows) {
  EXPECT_EQ(ValidateRowMap(ValidMap()), std::nullopt);
}

TEST(ValidateRowMap, RejectsInvalidOrigin) {
  for (const GeoOrigin& bad : {GeoOrigin{90.5, 7.0, 0.0}, GeoOrigin{-91.0, 7.0, 0.0}, GeoOrigin{45.0, 180.1, 0.0},
                               GeoOrigin{45.0, -181.0, 0.0}, GeoOrigin{kNaN, 7.0, 0.0}, GeoOrigin{45.0, kNaN, 0.0},
                               GeoOrigin{45.0, 7.0, kInf}, GeoOrigin{45.0, 7.0, kNaN}}) {
    RowMap map = ValidMap();
    map.origin = bad;
    EXPECT_THAT(ProblemOf(map), HasSubstr("origin is not a valid WGS84 position"));
  }
}

TEST(ValidateRowMap, AcceptsBoundaryOrigin) {
  RowMap map = ValidMap();
  map.origin = GeoOrigin{-90.0, 180.0, -400.0};
  EXPECT_EQ(ValidateRowMap(map), std::nullopt);
}

TEST(ValidateRowMap, RejectsMapWithoutRows) {
  RowMap map = ValidMap();
  map.rows.clear();
  EXPECT_THAT(ProblemOf(map), HasSubstr("no rows"));
}

TEST(ValidateRowMap, RejectsEmptyId) {
  RowMap map = ValidMap();
  map.rows[1].id.clear();
  EXPECT_THAT(ProblemOf(map), HasSubstr("row 1 has an empty id"));
}

TEST(ValidateRowMap, RejectsDuplicateId) {
  RowMap map = ValidMap();
  map.rows[1].id = "open";
  EXPECT_THAT(ProblemOf(map), HasSubstr("row 1 ('open'): duplicate id"));
}

TEST(ValidateRowMap, RejectsOpenRowWithOneVertex) {
  RowMap map = ValidMap();
  map.rows[0].points_m.pop_back();
  EXPECT_THAT(ProblemOf(map), HasSubstr("row 0 ('open'): needs at least 2 vertices, has 1"));
  map.rows[0].points_m.clear();
  EXPECT_THAT(ProblemOf(map), HasSubstr("has 0"));
}

TEST(ValidateRowMap, RejectsClosedRowWithTwoVertices) {
  RowMap map = ValidMap();
  map.rows[1].points_m.pop_back();
  EXPECT_THAT(ProblemOf(map), HasSubstr("row 1 ('triangle'): needs at least 3 vertices, has 2"));
}

TEST(ValidateRowMap, RejectsNonFiniteVertex) {
  for (const Eigen::Vector2d& bad : {Eigen::Vector2d(kNaN, 0.0), Eigen::Vector2d(5.0, kInf), Eigen::Vector2d(-kInf, 1.0)}) {
    RowMap map = ValidMap();
    map.rows[0].points_m.push_back(bad);
    EXPECT_THAT(ProblemOf(map), HasSubstr("row 0 ('open'): vertex 2 is not finite"));
  }
}

TEST(ValidateRowMap, RejectsZeroLengthSegment) {
  RowMap map = ValidMap();
  map.rows[0].points_m.insert(map.rows[0].points_m.begin() + 1, map.rows[0].points_m[0]);
  EXPECT_THAT(ProblemOf(map), HasSubstr("row 0 ('open'): segment 0 has zero length"));
}

TEST(ValidateRowMap, RejectsClosedRowThatRepeatsItsFirstVertex) {
  // A closed row is stored without the repeated vertex; repeating it makes the closing segment empty.
  RowMap map = ValidMap();
  map.rows[1].points_m.push_back(map.rows[1].points_m.front());
  EXPECT_THAT(ProblemOf(map), HasSubstr("row 1 ('triangle'): segment 3 has zero length"));
}

TEST(RowSegments, CountAndEndpoints) {
  const RowMap map = ValidMap();
  EXPECT_EQ(map.rows[0].SegmentCount(), 1u);
  EXPECT_EQ(map.rows[1].SegmentCount(), 3u);  // the closing segment counts
  EXPECT_EQ(map.SegmentCount(), 4u);
  const auto [a, b] = map.rows[1].Segment(2);
  EXPECT_EQ(a, Eigen::Vector2d(0.0, 3.0));
  EXPECT_EQ(b, Eigen::Vector2d(0.0, 2.0));
  EXPECT_EQ(Row{}.SegmentCount(), 0u);
}

// --- InsideOutline -----------------------------------------------------------------------------

/// An L-shaped (concave) outline: the square [0, 2]^2 without its quadrant [1, 2] x [1, 2].
Row LShape(bool counter_clockwise) {
  Row row{"L", {{0.0, 0.0}, {2.0, 0.0}, {2.0, 1.0}, {1.0, 1.0}, {1.0, 2.0}, {0.0, 2.0}}, true};
  if (!counter_clockwise) std::reverse(row.points_m.begin(), row.points_m.end());
  return row;
}

TEST(InsideOutline, ConcaveOutlineInEitherVertexOrder) {
  for (const bool ccw : {true, false}) {
    const Row row = LShape(ccw);
    EXPECT_TRUE(InsideOutline(row, {0.5, 0.5})) << ccw;
    EXPECT_TRUE(InsideOutline(row, {1.5, 0.5})) << ccw;
    EXPECT_TRUE(InsideOutline(row, {0.5, 1.5})) << ccw;
    EXPECT_FALSE(InsideOutline(row, {1.5, 1.5})) << ccw;  // the notch
    EXPECT_FALSE(InsideOutline(row, {3.0, 0.5})) << ccw;
    EXPECT_FALSE(InsideOutline(row, {-0.1, 1.0})) << ccw;
    EXPECT_FALSE(InsideOutline(row, {1.0, 0.0})) << ccw;  // on the outline: not strictly inside
  }
}

TEST(OutlineSignedArea, PositiveCounterClockwiseNegativeClockwiseZeroOpen) {
  EXPECT_DOUBLE_EQ(OutlineSignedArea(LShape(true)), 3.0);
  EXPECT_DOUBLE_EQ(OutlineSignedArea(LShape(false)), -3.0);
  EXPECT_EQ(OutlineSignedArea(ValidMap().rows[0]), 0.0);              // an open row
  EXPECT_DOUBLE_EQ(OutlineSignedArea(ValidMap().rows[1]), 0.5);       // the triangle, counter-clockwise
}

TEST(InsideOutline, AgreesWithTheSquareOnRandomPoints) {
  const Row square{"square", {{-1.0, -1.0}, {1.0, -1.0}, {1.0, 1.0}, {-1.0, 1.0}}, true};
  std::uint32_t state = 12345u;
  const auto uniform = [&state] {  // a small LCG: deterministic and independent of the library
    state = state * 1664525u + 1013904223u;
    return -2.0 + 4.0 * (state >> 8) / double(1u << 24);
  };
  for (int i = 0; i < 2000; ++i) {
    const Eigen::Vector2d p(uniform(), uniform());
    if (std::abs(std::abs(p.x()) - 1.0) < 1e-9 || std::abs(std::abs(p.y()) - 1.0) < 1e-9) continue;
    EXPECT_EQ(InsideOutline(square, p), p.cwiseAbs().maxCoeff() < 1.0) << p.transpose();
  }
}

TEST(InsideOutline, OpenRowsHaveNoInsideAndBadPointsThrow) {
  const RowMap map = ValidMap();
  EXPECT_FALSE(InsideOutline(map.rows[0], {5.0, 0.0}));   // on the open row
  EXPECT_FALSE(InsideOutline(map.rows[0], {5.0, -1.0}));
  EXPECT_TRUE(InsideOutline(map.rows[1], {0.2, 2.2}));    // the triangle
  EXPECT_THROW(InsideOutline(map.rows[1], {kNaN, 2.2}), std::invalid_argument);
  EXPECT_THROW(InsideOutline(map.rows[1], {0.2, kInf}), std::invalid_argument);
}

// --- MakeSampleRowMap --------------------------------------------------------------------------
// Every row outline is right[0..S] followed by left[S..0] (S segments per side), so vertex i and
// vertex 2S+1-i are the two sides of the canopy at the same station along the row.

struct Sides {
  std::vector<Eigen::Vector2d> right, left;
};

Sides SidesOf(const Row& row) {
  const std::size_t per_side = row.points_m.size() / 2;
  Sides s;
  for (std::size_t i = 0; i < per_side; ++i) {
    s.right.push_back(row.points_m[i]);
    s.left.push_back(row.points_m[row.points_m.size() - 1 - i]);
  }
  return s;
}

Eigen::Vector2d Centre(const Sides& s, std::size_t i) { return 0.5 * (s.right[i] + s.left[i]); }

double SignedArea(const std::vector<Eigen::Vector2d>& ring) {
  double twice = 0.0;
  for (std::size_t i = 0; i < ring.size(); ++i) {
    const Eigen::Vector2d& p = ring[i];
    const Eigen::Vector2d& q = ring[(i + 1) % ring.size()];
    twice += p.x() * q.y() - q.x() * p.y();
  }
  return 0.5 * twice;
}

TEST(MakeSampleRowMap, DefaultMapIsValidWithClosedOutlines) {
  const SampleRowMapParams params;
  const RowMap map = MakeSampleRowMap(params);
  EXPECT_EQ(ValidateRowMap(map), std::nullopt);
  ASSERT_EQ(map.rows.size(), 10u);
  EXPECT_EQ(map.rows.front().id, "row-1");
  EXPECT_EQ(map.rows.back().id, "row-10");
  EXPECT_EQ(map.origin.latitude_deg, params.origin.latitude_deg);
  EXPECT_EQ(map.origin.longitude_deg, params.origin.longitude_deg);
  EXPECT_EQ(map.origin.altitude_m, params.origin.altitude_m);
  for (const Row& row : map.rows) {
    EXPECT_TRUE(row.closed) << row.id;
    EXPECT_EQ(row.points_m.size(), 2u * (25u + 1u)) << row.id;  // ceil(50 m / 2 m) = 25 segments per side
    // Counter-clockwise, and the area of a 0.5 m wide strip along a ~50 m (slightly bowed) row.
    EXPECT_NEAR(SignedArea(row.points_m), params.canopy_width_m * params.row_length_m, 0.01 * 25.0) << row.id;
  }
}

TEST(MakeSampleRowMap, NeighbouringCentreLinesAreRowSpacingApartAtTheEnds) {
  const SampleRowMapParams params;
  const RowMap map = MakeSampleRowMap(params);
  for (std::size_t r = 0; r + 1 < map.rows.size(); ++r) {
    const Sides a = SidesOf(map.rows[r]), b = SidesOf(map.rows[r + 1]);
    EXPECT_NEAR((Centre(b, 0) - Centre(a, 0)).norm(), params.row_spacing_m, 1e-9);
    EXPECT_NEAR((Centre(b, 25) - Centre(a, 25)).norm(), params.row_spacing_m, 1e-9);
  }
}

TEST(MakeSampleRowMap, RowsHaveTheChordLengthAndHeading) {
  const SampleRowMapParams params;
  const Eigen::Vector2d along(std::cos(params.heading_rad), std::sin(params.heading_rad));
  for (const Row& row : MakeSampleRowMap(params).rows) {
    const Sides s = SidesOf(row);
    const Eigen::Vector2d chord = Centre(s, s.right.size() - 1) - Centre(s, 0);
    EXPECT_NEAR(chord.norm(), params.row_length_m, 1e-9) << row.id;
    EXPECT_NEAR(chord.normalized().dot(along), 1.0, 1e-12) << row.id;
  }
}

TEST(MakeSampleRowMap, CanopyHasConstantWidth) {
  SampleRowMapParams params;
  params.canopy_width_m = 0.8;
  params.bow_m = 1.5;
  for (const Row& row : MakeSampleRowMap(params).rows) {
    const Sides s = SidesOf(row);
    for (std::size_t i = 0; i < s.right.size(); ++i) {
      EXPECT_NEAR((s.left[i] - s.right[i]).norm(), 0.8, 1e-12) << row.id << " station " << i;
    }
  }
}

TEST(MakeSampleRowMap, BowIsTheSagAtMidLength) {
  SampleRowMapParams params;
  params.row_length_m = 40.0;
  params.vertex_spacing_m = 2.0;  // 20 segments: station 10 is mid-length
  params.bow_m = 0.75;
  params.heading_rad = -1.2;
  const Eigen::Vector2d along(std::cos(params.heading_rad), std::sin(params.heading_rad));
  const Eigen::Vector2d across(-along.y(), along.x());
  const RowMap map = MakeSampleRowMap(params);
  for (std::size_t r = 0; r < map.rows.size(); ++r) {
    const Sides s = SidesOf(map.rows[r]);
    ASSERT_EQ(s.right.size(), 21u);
    const Eigen::Vector2d mid = Centre(s, 10);
    EXPECT_NEAR(mid.dot(along), 20.0, 1e-9);
    EXPECT_NEAR(mid.dot(across) - static_cast<double>(r) * params.row_spacing_m, 0.75, 1e-9);
  }
}

TEST(MakeSampleRowMap, StraightRowsWithoutBow) {
  SampleRowMapParams params;
  params.bow_m = 0.0;
  params.heading_rad = 0.5 * 3.14159265358979323846;  // rows along +North (the y axis)
  for (const Row& row : MakeSampleRowMap(params).rows) {
    const Sides s = SidesOf(row);
    for (std::size_t i = 0; i < s.right.size(); ++i) EXPECT_NEAR(Centre(s, i).x(), Centre(s, 0).x(), 1e-9);
  }
}

TEST(MakeSampleRowMap, RejectsInvalidParameters) {
  const auto with = [](auto change) {
    SampleRowMapParams p;
    change(p);
    return p;
  };
  const SampleRowMapParams bad[] = {
      with([](SampleRowMapParams& p) { p.row_count = 0; }),
      with([](SampleRowMapParams& p) { p.row_count = -3; }),
      with([](SampleRowMapParams& p) { p.row_spacing_m = 0.0; }),
      with([](SampleRowMapParams& p) { p.row_spacing_m = kNaN; }),
      with([](SampleRowMapParams& p) { p.row_length_m = -1.0; }),
      with([](SampleRowMapParams& p) { p.row_length_m = kInf; }),
      with([](SampleRowMapParams& p) { p.canopy_width_m = 0.0; }),
      with([](SampleRowMapParams& p) { p.canopy_width_m = 2.5; }),  // == spacing: rows would touch
      with([](SampleRowMapParams& p) { p.bow_m = kNaN; }),
      with([](SampleRowMapParams& p) { p.heading_rad = kInf; }),
      with([](SampleRowMapParams& p) { p.vertex_spacing_m = 0.0; }),
      with([](SampleRowMapParams& p) { p.vertex_spacing_m = 60.0; }),  // longer than a row
      with([](SampleRowMapParams& p) { p.origin.latitude_deg = 100.0; }),
      with([](SampleRowMapParams& p) { p.origin.longitude_deg = kNaN; }),
      with([](SampleRowMapParams& p) { p.row_count = 1'000'000; }),
      with([](SampleRowMapParams& p) {  // 10^15 segments: must not overflow int or allocate
        p.row_length_m = 1e6;
        p.vertex_spacing_m = 1e-9;
      }),
      with([](SampleRowMapParams& p) { p.bow_m = 1e4; }),  // outline folds over itself
  };
  for (std::size_t i = 0; i < std::size(bad); ++i) {
    EXPECT_THROW(MakeSampleRowMap(bad[i]), std::invalid_argument) << "case " << i;
  }
}

}  // namespace
}  // namespace rowloc::geometry
