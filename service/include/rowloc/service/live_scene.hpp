// The `scene` message of the live view (docs/live-view.md §4): what does not change during a session
// and the page draws under the moving parts: the rows of the session's map (local ENU metres, the
// frame of the states) and the vehicle's geometry (wheels, ultrasonic rangers, GNSS antenna, in the
// body frame: x forward, y left, origin the reference point), from which the page draws its outline.
#pragma once

#include "rowloc/geometry/row_map.hpp"
#include "rowloc/service/service_session.hpp"

#include <string>

namespace rowloc::service {

/// One-line JSON: {"type":"scene","session","vehicle":{...},"map":NAME|null,"rows":[...],
/// "map_error":TEXT|null}. `map` may be null (a session without a map: no rows).
std::string LiveSceneLine(const ServiceSession& session, const geometry::RowMap* map, const std::string& map_error);

}  // namespace rowloc::service
