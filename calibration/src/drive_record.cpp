// A recorded drive for the ranger calibration: echoes and the smoothed reference (drive_record.hpp).
#include "rowloc/calibration/drive_record.hpp"

#include "rowloc/formats/sensor_log_reader.hpp"
#include "rowloc/localization/localization_session.hpp"
#include "rowloc/localization/reorder_buffer.hpp"

#include <spdlog/spdlog.h>

#include <algorithm>
#include <cmath>
#include <optional>
#include <string>
#include <variant>

namespace rowloc::calibration {
namespace {

/// The ranger index of each name in the log header (vehicle order), or a DriveRecordError.
std::vector<std::size_t> RangerIndices(const formats::LogHeader& header, const mapio::VehicleConfig& vehicle,
                                       const std::string& source) {
  std::vector<std::size_t> indices;
  for (const std::string& name : header.ultrasonic) {
    const auto it = std::find_if(vehicle.ultrasonic.begin(), vehicle.ultrasonic.end(),
                                 [&](const mapio::SensorMount& m) { return m.name == name; });
    if (it == vehicle.ultrasonic.end()) {
      throw DriveRecordError(source + ": the log's ultrasonic sensor '" + name + "' is not in the vehicle file of '" +
                             vehicle.name + "'");
    }
    indices.push_back(static_cast<std::size_t>(it - vehicle.ultrasonic.begin()));
  }
  return indices;
}

ReferenceKnot KnotOf(const formats::EstimateRecord& estimate) {
  ReferenceKnot knot;
  knot.time_s = estimate.time_s;
  knot.pose << estimate.position_m, *estimate.heading_rad;
  return knot;
}

}  // namespace

DriveRecord ReadDriveRecord(std::istream& log, const std::string& source, const mapio::VehicleConfig& vehicle,
                            const localization::FilterConfig& filter, double knot_interval_s) {
  if (vehicle.ultrasonic.empty()) {
    throw DriveRecordError("the vehicle '" + vehicle.name + "' has no ultrasonic sensor to calibrate");
  }
  if (!(knot_interval_s > 0.0) || !std::isfinite(knot_interval_s)) {
    throw DriveRecordError("knot_interval_s must be positive and finite");
  }
  formats::SensorLogReader reader(log, source);
  const std::vector<std::size_t> ranger_of = RangerIndices(reader.header(), vehicle, source);
  localization::LocalizationSession session(
      vehicle, filter, reader.header(),
      {.estimate_period_s = knot_interval_s, .record_updates = false, .skip_types = {"ultrasonic"}});
  session.EnableSmoothing();
  DriveRecord record;
  record.origin = reader.header().origin;

  const auto process = [&](const formats::SensorMessage& message) {
    if (const auto* ping = std::get_if<formats::UltrasonicMessage>(&message)) {
      if (!ping->range_m) {
        ++record.pings_without_echo;
      } else {
        record.echoes.push_back({ping->time_s, ranger_of.at(ping->sensor_index), *ping->range_m});
      }
    }
    const localization::SessionStep step = session.Process(message);
    if (step.error) {
      spdlog::warn("{}:{}: rejected: {}", source, reader.line_number(), *step.error);
      ++record.refused_messages;
    }
  };
  localization::ReorderBuffer reorder(reader.header().reorder_window_s);
  for (;;) {
    std::optional<formats::SensorMessage> message;
    try {
      message = reader.Next();
    } catch (const formats::SensorLogError& e) {
      if (!reader.readable()) throw;
      spdlog::warn("{}:{}: rejected: {}: {}", source, e.line(), e.subject(), e.reason());
      ++record.refused_messages;
      continue;
    }
    if (!message) break;
    if (reorder.Add(std::move(*message)) == localization::ReorderBuffer::Admission::kTooOld) {
      spdlog::warn("{}:{}: rejected: older than the journal's reorder window", source, reader.line_number());
      ++record.refused_messages;
      continue;
    }
    while (auto ready = reorder.PopReady()) process(*ready);
  }
  while (auto held = reorder.PopAny()) process(*held);

  if (!session.filter().initialised() && session.estimates() == 0) {
    throw DriveRecordError(source + ": the filter never initialised (no GNSS baseline): no reference trajectory");
  }
  for (const formats::EstimateRecord& estimate : session.FinishSmoothing()) {
    if (estimate.heading_rad) record.knots.push_back(KnotOf(estimate));
  }
  if (record.knots.size() < 2) {
    throw DriveRecordError(source + ": fewer than two reference poses: the drive is too short to calibrate");
  }
  if (record.echoes.empty()) throw DriveRecordError(source + ": the log has no ultrasonic echo");
  // A journal's pings are in time order once reordered; a log's are already.
  std::stable_sort(record.echoes.begin(), record.echoes.end(),
                   [](const EchoRecord& a, const EchoRecord& b) { return a.time_s < b.time_s; });
  return record;
}

}  // namespace rowloc::calibration
