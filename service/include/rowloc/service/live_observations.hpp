// What the live stream (docs/live-view.md §4, `subscribe` with `stream: "live"`) says about one
// processed sensor message besides the state: a GNSS fix in the session's local frame with its
// claimed sigma and whether the filter used it, and an ultrasonic echo as a ray from the ranger's
// mount at the filter's pose to the range measured, with the row segment the map-aided update
// matched it to (localization/vehicle_ekf.hpp EchoTrace) and the update's outcome.
//
// The ray is drawn from the pose after the message was processed (the posterior), so an accepted
// echo's ray ends on its row up to the remaining error; the mount is the vehicle file's
// (position_m, yaw_rad): origin = p + R(phi) m_xy, direction phi + yaw.
#pragma once

#include "rowloc/formats/sensor_messages.hpp"
#include "rowloc/localization/localization_session.hpp"
#include "rowloc/mapio/local_frame.hpp"

#include <string>
#include <vector>

namespace rowloc::service {

/// The `gnss` and `echo` lines (one-line JSON objects, `session` last) of one processed message;
/// empty for other messages, a GNSS message without a position, or an ultrasonic message without an
/// echo trace (no map, no echo, or a filter not yet initialised). session_json: the session's name
/// as a JSON string.
std::vector<std::string> LiveObservationLines(const formats::SensorMessage& message,
                                              const localization::SessionStep& step,
                                              const localization::VehicleEkf& filter,
                                              const mapio::LocalFrame& frame, const std::string& session_json);

}  // namespace rowloc::service
