// Outline validity of a row (contract in row_outline_validity.hpp): Boost.Geometry is_valid for
// rings, a turn-back test for polylines.
#include "rowloc/geometry/row_outline_validity.hpp"

// Boost 1.74's Boost.Math (pulled in by Boost.Geometry) includes a header it itself deprecated
// (as in segment_index.cpp): without this the build prints a deprecation note.
#ifndef BOOST_ALLOW_DEPRECATED_HEADERS
#define BOOST_ALLOW_DEPRECATED_HEADERS
#endif
// is_valid instantiates Boost's rescale policy, in which GCC 12 at -O3 sees a member "may be used
// uninitialized" (a false positive inside Boost 1.74: the policy is default-constructed and not
// used by is_valid's no-rescaling strategy). Silenced for this file only.
#if defined(__GNUC__) && !defined(__clang__)
#pragma GCC diagnostic push
#pragma GCC diagnostic ignored "-Wmaybe-uninitialized"
#endif
#include <boost/geometry/algorithms/area.hpp>
#include <boost/geometry/algorithms/is_valid.hpp>
#include <boost/geometry/algorithms/perimeter.hpp>
#include <boost/geometry/geometries/point_xy.hpp>
#include <boost/geometry/geometries/ring.hpp>

#include <algorithm>
#include <cmath>
#include <string>

namespace rowloc::geometry {
namespace {

namespace bg = boost::geometry;
using Point = bg::model::d2::point_xy<double>;
using Ring = bg::model::ring<Point, /*ClockWise=*/false, /*Closed=*/false>;

std::optional<std::string> RingDefect(const Row& row) {
  Ring ring;
  ring.reserve(row.points_m.size());
  for (const Eigen::Vector2d& p : row.points_m) ring.emplace_back(p.x(), p.y());
  // Either vertex order is a valid row: test the counter-clockwise one.
  const double area_m2 = bg::area(ring);
  if (area_m2 < 0.0) std::reverse(ring.begin(), ring.end());
  std::string message;
  if (!bg::is_valid(ring, message)) {
    return "the Polygon outline is not a valid ring: " + message + " (Boost.Geometry is_valid; points in local metres)";
  }
  // A ring of (nearly) zero area escapes is_valid when rounding puts its vertices a few 1e-12 m
  // off their line: its mean thickness 2 A / P is the test.
  if (2.0 * std::abs(area_m2) < kMinOutlineThicknessM * static_cast<double>(bg::perimeter(ring))) {
    return std::string("the Polygon outline encloses no area (its vertices lie on one line, to 1e-6 m)");
  }
  return std::nullopt;
}

std::optional<std::string> TurnBack(const Row& row) {
  const double cos_limit = -std::cos(kTurnBackToleranceRad);
  for (std::size_t i = 1; i + 1 < row.points_m.size(); ++i) {
    const Eigen::Vector2d before = row.points_m[i] - row.points_m[i - 1];
    const Eigen::Vector2d after = row.points_m[i + 1] - row.points_m[i];
    if (before.dot(after) <= cos_limit * before.norm() * after.norm()) {
      return "the LineString turns back on itself at vertex " + std::to_string(i) +
             " (the segments before and after it overlap: the row retraces itself)";
    }
  }
  return std::nullopt;
}

}  // namespace

std::optional<std::string> RowOutlineDefect(const Row& row) { return row.closed ? RingDefect(row) : TurnBack(row); }

}  // namespace rowloc::geometry

#if defined(__GNUC__) && !defined(__clang__)
#pragma GCC diagnostic pop
#endif
