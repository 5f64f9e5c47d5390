#include "rowloc/mapio/local_frame.hpp"

#include <GeographicLib/LocalCartesian.hpp>

#include <cmath>
#include <sstream>
#include <stdexcept>

namespace rowloc::mapio {

struct LocalFrame::Impl {
  GeographicLib::LocalCartesian projection;
};

std::string GeodeticPositionProblem(double latitude_deg, double longitude_deg, double altitude_m) {
  // The valid case (every GNSS fix) returns before building a stream: an ostringstream costs a
  // locale set-up, 3.5 % of the instructions of a swerve EKF cycle
  // (docs/notes/2026-12-benchmarks-history.md, "2026-12-02 (3)").
  if (std::abs(latitude_deg) <= 90.0 && std::abs(longitude_deg) <= 180.0 && std::isfinite(altitude_m)) return {};
  std::ostringstream out;
  out.precision(17);
  if (!std::isfinite(latitude_deg) || std::abs(latitude_deg) > 90.0) {
    out << "latitude " << latitude_deg << " deg is not in [-90, 90]";
  } else if (!std::isfinite(longitude_deg) || std::abs(longitude_deg) > 180.0) {
    out << "longitude " << longitude_deg << " deg is not in [-180, 180]";
  } else if (!std::isfinite(altitude_m)) {
    out << "altitude " << altitude_m << " m is not finite";
  }
  return out.str();
}

LocalFrame::LocalFrame(const geometry::GeoOrigin& origin) : origin_(origin) {
  const std::string problem =
      GeodeticPositionProblem(origin.latitude_deg, origin.longitude_deg, origin.altitude_m);
  if (!problem.empty()) throw std::invalid_argument("LocalFrame origin: " + problem);
  impl_ = std::make_shared<const Impl>(Impl{GeographicLib::LocalCartesian(
      origin.latitude_deg, origin.longitude_deg, origin.altitude_m, GeographicLib::Geocentric::WGS84())});
}

Eigen::Vector3d LocalFrame::ToEnu(double latitude_deg, double longitude_deg, double altitude_m) const {
  const std::string problem = GeodeticPositionProblem(latitude_deg, longitude_deg, altitude_m);
  if (!problem.empty()) throw std::invalid_argument("LocalFrame::ToEnu: " + problem);
  Eigen::Vector3d enu;
  impl_->projection.Forward(latitude_deg, longitude_deg, altitude_m, enu.x(), enu.y(), enu.z());
  return enu;
}

geometry::GeoOrigin LocalFrame::ToGeodetic(const Eigen::Vector3d& enu_m) const {
  if (!enu_m.allFinite()) throw std::invalid_argument("LocalFrame::ToGeodetic: ENU position is not finite");
  geometry::GeoOrigin out;
  impl_->projection.Reverse(enu_m.x(), enu_m.y(), enu_m.z(), out.latitude_deg, out.longitude_deg,
                            out.altitude_m);
  return out;
}

}  // namespace rowloc::mapio
