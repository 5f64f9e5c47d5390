// Local East-North-Up (ENU) tangent frame at a WGS84 origin (the design: "World frame: local
// East-North-Up tangent plane with a georeferenced origin ... Convert with GeographicLib
// (LocalCartesian), never by hand").
//
// Math (GeographicLib::LocalCartesian, C. F. F. Karney): a geodetic position (lat, lon, h) is
// converted to Earth-centred Earth-fixed coordinates X on the WGS84 ellipsoid, then
//   enu = R(lat0, lon0) (X - X0),
// where X0 is the origin in ECEF and the rows of R are the unit East, North and Up vectors at
// the origin. The frame is a plane tangent to the ellipsoid at the origin: a point on the
// ellipsoid d metres away lies about d^2 / (2 R_earth) below it (8 mm at 10 km). The inverse
// is exact up to floating point (no small-distance approximation).
#pragma once

#include "rowloc/geometry/row_map.hpp"

#include <Eigen/Core>

#include <memory>
#include <string>

namespace rowloc::mapio {

/// Immutable ENU frame; cheap to copy (the GeographicLib state is shared, read-only) and safe
/// to use from several threads at once.
class LocalFrame {
 public:
  /// Throws std::invalid_argument if the latitude is not in [-90, 90] deg, the longitude not in
  /// [-180, 180] deg, or any value is not finite.
  explicit LocalFrame(const geometry::GeoOrigin& origin);

  /// Geodetic WGS84 position (degrees, metres above the ellipsoid) -> ENU metres.
  /// Throws std::invalid_argument on the same conditions as the constructor.
  Eigen::Vector3d ToEnu(double latitude_deg, double longitude_deg, double altitude_m) const;

  /// ENU metres -> geodetic WGS84 position (longitude in [-180, 180] deg).
  /// Throws std::invalid_argument if enu_m is not finite.
  geometry::GeoOrigin ToGeodetic(const Eigen::Vector3d& enu_m) const;

  const geometry::GeoOrigin& origin() const { return origin_; }

 private:
  struct Impl;
  geometry::GeoOrigin origin_;
  std::shared_ptr<const Impl> impl_;
};

/// Why (latitude, longitude, altitude) is not a valid WGS84 position; empty if it is.
/// Shared by LocalFrame and the map reader so that both word the problem the same way.
std::string GeodeticPositionProblem(double latitude_deg, double longitude_deg, double altitude_m);

}  // namespace rowloc::mapio
