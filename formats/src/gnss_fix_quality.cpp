// GNSS fix quality names (see gnss_fix_quality.hpp).
#include "rowloc/formats/gnss_fix_quality.hpp"

namespace rowloc::formats {

std::string_view GnssFixQualityName(GnssFixQuality fix) {
  switch (fix) {
    case GnssFixQuality::kNone: return "none";
    case GnssFixQuality::kSbas: return "sbas";
    case GnssFixQuality::kRtkFloat: return "rtk_float";
    case GnssFixQuality::kRtkFixed: return "rtk_fixed";
  }
  return "none";
}

}  // namespace rowloc::formats
