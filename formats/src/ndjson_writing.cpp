// Helpers shared by the NDJSON writers (see ndjson_writing.hpp).
#include "rowloc/formats/ndjson_writing.hpp"

#include "rowloc/mapio/local_frame.hpp"

#include <cmath>
#include <stdexcept>

namespace rowloc::formats::ndjson {

void Refuse(const char* type, const std::string& reason) {
  throw std::invalid_argument(std::string(type) + " message refused: " + reason);
}

double Finite(const char* type, const char* key, double value) {
  if (!std::isfinite(value)) Refuse(type, std::string(key) + " is not finite");
  return value;
}

void CheckTimeOrder(const char* type, double time_s, double last_time_s) {
  Finite(type, "t", time_s);
  if (time_s < last_time_s) {
    Refuse(type, "time goes backwards (" + std::to_string(time_s) + " s after " + std::to_string(last_time_s) + " s)");
  }
}

nlohmann::ordered_json MessageStart(const char* type, double time_s) {
  nlohmann::ordered_json j;
  j["type"] = type;
  j["t"] = time_s;
  return j;
}

nlohmann::ordered_json OriginJson(const geometry::GeoOrigin& origin) {
  const std::string problem =
      mapio::GeodeticPositionProblem(origin.latitude_deg, origin.longitude_deg, origin.altitude_m);
  if (!problem.empty()) throw std::invalid_argument("log header: origin: " + problem);
  nlohmann::ordered_json o;
  o["latitude_deg"] = origin.latitude_deg;
  o["longitude_deg"] = origin.longitude_deg;
  o["altitude_m"] = origin.altitude_m;
  return o;
}

}  // namespace rowloc::formats::ndjson
