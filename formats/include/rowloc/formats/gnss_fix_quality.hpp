// GNSS fix quality: the `fix` of a `gps` message (docs/protocol.md §1). One definition for the
// simulator's GNSS model and writer (sim) and the sensor-log reader and the filter (formats,
// localization).
#pragma once

#include <string_view>

namespace rowloc::formats {

/// kNone: the receiver has no position (a `gps` message without position keys).
enum class GnssFixQuality { kNone, kSbas, kRtkFloat, kRtkFixed };

/// The protocol's name: "none", "sbas", "rtk_float" or "rtk_fixed".
std::string_view GnssFixQualityName(GnssFixQuality fix);

}  // namespace rowloc::formats
