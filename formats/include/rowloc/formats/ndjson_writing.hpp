// The little helpers every NDJSON writer of docs/protocol.md shares: the estimate-stream writer
// (estimate_stream_writer.hpp) and the simulator's sensor-log and truth writers (sim/log_writers.hpp).
// Lines are built as nlohmann::ordered_json (keys in the documented order), so this header needs
// nlohmann-json: it is for the writers' .cpp files, each of which links nlohmann-json itself, and
// never appears in a public API.
//
// A refusal is a std::invalid_argument "<type> message refused: <reason>" (`type` is the line's
// `type`, e.g. "gps" or "estimate"); a writer calls these before it writes anything of the line.
#pragma once

#include "rowloc/geometry/row_map.hpp"

#include <nlohmann/json.hpp>

#include <string>

namespace rowloc::formats::ndjson {

/// Throws std::invalid_argument("<type> message refused: <reason>").
[[noreturn]] void Refuse(const char* type, const std::string& reason);

/// `value` if it is finite; else refuses the message: "<key> is not finite".
double Finite(const char* type, const char* key, double value);

/// Refuses a non-finite `time_s`, or one before `last_time_s` (time never decreases in a stream).
void CheckTimeOrder(const char* type, double time_s, double last_time_s);

/// A message object with its first two keys, "type" and "t" (docs/protocol.md key order).
nlohmann::ordered_json MessageStart(const char* type, double time_s);

/// A header's `origin` object {latitude_deg, longitude_deg, altitude_m}. Throws
/// std::invalid_argument("log header: origin: <problem>") for an invalid WGS84 position.
nlohmann::ordered_json OriginJson(const geometry::GeoOrigin& origin);

}  // namespace rowloc::formats::ndjson
