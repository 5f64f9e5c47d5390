// Validity of a row's geometry beyond ValidateRowMap (which accepts any finite vertices without
// zero-length segments): the defects that make a row unusable as a canopy outline, found by
// Boost.Geometry's OGC validity test (`is_valid`, Simple Feature Access 1.2.1, Herring 2011) and
// by a turn-back test for open rows.
//
// - A closed row (polygon ring) must be a valid OGC ring: no self-intersection (a "bow-tie",
//   whose inside is undefined: the map-aided update then associates echoes with the wrong side
//   of the canopy; issue 26 measured a NEES of 8.9e5), no spike (an edge that goes out and comes
//   straight back), at least 3 distinct points, and an area: a mean thickness 2 A / P of at least
//   kMinOutlineThicknessM (Boost finds exactly collinear rings only). Either vertex order is valid.
// - An open row (polyline) must not turn back on itself: two consecutive segments anti-parallel
//   within kTurnBackToleranceRad retrace each other (10^6 vertices alternating between two points
//   are a single segment drawn 10^6 times).
// The reason names the defect and where it is (Boost's text with the point in local metres, or
// the vertex index).
#pragma once

#include "rowloc/geometry/row_map.hpp"

#include <optional>
#include <string>

namespace rowloc::geometry {

/// Mean thickness (2 area / perimeter, metres) under which a closed row encloses no area.
inline constexpr double kMinOutlineThicknessM = 1e-6;

/// Angle (radians) from a full turn-back under which an open row is said to retrace itself.
inline constexpr double kTurnBackToleranceRad = 1e-6;

/// Why the row's outline is not valid (see above), or nullopt. Expects a row that passes
/// ValidateRowMap (finite vertices, no zero-length segment).
std::optional<std::string> RowOutlineDefect(const Row& row);

}  // namespace rowloc::geometry
