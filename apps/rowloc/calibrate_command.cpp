// `rowloc calibrate LOG --vehicle V --map MAP -o REPORT [--filter F] [--config C] [--write-vehicle OUT]`:
// estimates where each ultrasonic ranger sits on the vehicle from a recorded drive along rows of a
// known map (rowloc/calibration/ranger_calibration.hpp; localization/ranger_mount_fit.hpp states the
// least-squares problem; the reference trajectory is the filter without the rangers, smoothed).
// The report (JSON) gives per ranger the configured and estimated lever arm, the correction along
// and across its beam with 1-sigma, the echoes used and the residual RMS before and after; the
// console prints the same as a table. --write-vehicle writes the vehicle file with the calibrated
// mounts (every other key as read; a relative recommended_filter re-pointed from the new file's
// directory). Without --filter the vehicle's recommended filter is used (as `rowloc replay` does).
// What is calibrated today: the rangers' body (x, y). Not yet: their yaw, the wheel radii (the filter
// estimates them online; `rowloc replay --calibration` carries them to the next drive), sensor biases.
#include "commands.hpp"
#include "option_checks.hpp"

#include "rowloc/calibration/drive_record.hpp"
#include "rowloc/calibration/ranger_calibration.hpp"
#include "rowloc/localization/filter_choice.hpp"
#include "rowloc/mapio/input_file.hpp"
#include "rowloc/mapio/output_file.hpp"
#include "rowloc/mapio/row_map_geojson.hpp"
#include "rowloc/mapio/vehicle_config.hpp"

#include <nlohmann/json.hpp>
#include <spdlog/spdlog.h>

#include <cerrno>
#include <cmath>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <memory>
#include <string>

namespace rowloc::apps {
namespace {

struct CalibrateOptions {
  std::string log_path, vehicle_path, filter_path, map_path, config_path, output_path, vehicle_out_path;
};

nlohmann::json Number(double v) { return std::isfinite(v) ? nlohmann::json(v) : nlohmann::json(nullptr); }

nlohmann::ordered_json ReportJson(const calibration::RangerMountFit& c, const CalibrateOptions& o) {
  nlohmann::ordered_json rangers = nlohmann::ordered_json::array();
  for (const calibration::RangerMountEstimate& r : c.rangers) {
    rangers.push_back({{"name", r.name},
                       {"calibrated", r.calibrated},
                       {"configured_position_m", {r.configured_lever_arm_m.x(), r.configured_lever_arm_m.y()}},
                       {"estimated_position_m", {r.lever_arm_m.x(), r.lever_arm_m.y()}},
                       {"along_beam_m", r.along_beam_m},
                       {"along_beam_sigma_m", Number(r.along_beam_sigma_m)},
                       {"across_beam_m", r.across_beam_m},
                       {"across_beam_sigma_m", Number(r.across_beam_sigma_m)},
                       {"echoes", r.echoes},
                       {"echoes_used", r.echoes_used},
                       {"rms_before_m", Number(r.rms_before_m)},
                       {"rms_after_m", Number(r.rms_after_m)}});
  }
  return {{"type", "ranger_calibration"},
          {"log", o.log_path},
          {"vehicle", o.vehicle_path},
          {"map", o.map_path},
          {"rangers", rangers},
          {"common_along_beam_m", c.common_along_beam_m},
          {"knots", c.knots},
          {"echoes_used", c.echoes_used},
          {"echoes_unassociated", c.echoes_unassociated},
          {"echoes_outside_reference", c.echoes_outside_reference},
          {"position_correction_rms_m", c.position_correction_rms_m},
          {"solver_iterations", c.solver_iterations},
          {"solver", c.solver_report}};
}

void LogTable(const calibration::RangerMountFit& c) {
  spdlog::info("{:<20} {:>9} {:>14} {:>14} {:>12} {:>10} {:>10}", "ranger", "used", "along beam mm",
               "across beam mm", "sigma mm", "rms before", "rms after");
  for (const calibration::RangerMountEstimate& r : c.rangers) {
    spdlog::info("{:<20} {:>9} {:>14.1f} {:>14.1f} {:>5.1f} / {:<5.1f} {:>8.1f}mm {:>8.1f}mm{}", r.name, r.echoes_used,
                 1e3 * r.along_beam_m, 1e3 * r.across_beam_m, 1e3 * r.along_beam_sigma_m, 1e3 * r.across_beam_sigma_m,
                 1e3 * r.rms_before_m, 1e3 * r.rms_after_m, r.calibrated ? "" : "  (too few echoes: not calibrated)");
  }
  spdlog::info("common along-beam offset {:.1f} mm (also: the map's lanes narrower (+) or wider than the canopy "
               "heard); {} echoes used, {} without a row within the gate, {} outside the reference; reference "
               "corrected by {:.1f} cm rms",
               1e3 * c.common_along_beam_m, c.echoes_used, c.echoes_unassociated, c.echoes_outside_reference,
               1e2 * c.position_correction_rms_m);
}

/// The vehicle file as read, with the calibrated mounts; a relative recommended_filter re-pointed.
std::string CalibratedVehicleJson(const CalibrateOptions& o, const calibration::RangerMountFit& c) {
  nlohmann::ordered_json document = nlohmann::ordered_json::parse(mapio::ReadInputFile(o.vehicle_path, mapio::kMaxConfigFileBytes, "vehicle file"));
  for (auto& sensor : document.at("ultrasonic")) {
    for (const calibration::RangerMountEstimate& r : c.rangers) {
      if (!r.calibrated || sensor.at("name") != r.name) continue;
      sensor["position_m"][0] = r.lever_arm_m.x();
      sensor["position_m"][1] = r.lever_arm_m.y();
    }
  }
  if (document.contains("recommended_filter") && document["recommended_filter"].is_string()) {
    const std::filesystem::path filter = document["recommended_filter"].get<std::string>();
    if (filter.is_relative()) {
      const auto from = std::filesystem::absolute(o.vehicle_path).parent_path() / filter;
      const auto to_dir = std::filesystem::absolute(o.vehicle_out_path).parent_path();
      document["recommended_filter"] = std::filesystem::relative(from, to_dir).generic_string();
    }
  }
  return document.dump(2) + "\n";
}

void RunCalibrate(const CalibrateOptions& o) {
  CheckCommandFiles({{"log", o.log_path}, {"--vehicle", o.vehicle_path}, {"--filter", o.filter_path},
                     {"--map", o.map_path}, {"--config", o.config_path}},
                    {{"--output", o.output_path}, {"--write-vehicle", o.vehicle_out_path}});
  const mapio::VehicleFile vehicle_file = mapio::LoadVehicleFile(o.vehicle_path);
  const localization::FilterChoice filter = localization::ChooseFilter(o.filter_path, vehicle_file, o.vehicle_path);
  const calibration::RangerCalibrationConfig config =
      o.config_path.empty() ? calibration::RangerCalibrationConfig{}
                            : calibration::ParseRangerCalibrationConfig(
                                  mapio::ReadInputFile(o.config_path, mapio::kMaxConfigFileBytes, "calibration settings file"),
                                  o.config_path);
  geometry::RowMap map;
  try {
    map = mapio::ReadRowMapGeoJson(o.map_path);
  } catch (const std::invalid_argument& e) {
    throw std::runtime_error(o.map_path + ": " + e.what());
  }
  std::ifstream log(o.log_path, std::ios::binary);
  if (!log) throw std::runtime_error(o.log_path + ": cannot open sensor log: " + std::strerror(errno));
  spdlog::info("calibrate the rangers of {} from {} with {}", vehicle_file.vehicle.name, o.log_path,
               localization::DescribeFilterChoice(filter, o.vehicle_path));
  const calibration::DriveRecord drive =
      calibration::ReadDriveRecord(log, o.log_path, vehicle_file.vehicle, filter.config, config.knot_interval_s);
  spdlog::info("reference: {} smoothed poses from {:.1f} to {:.1f} s; {} echoes", drive.knots.size(),
               drive.knots.front().time_s, drive.knots.back().time_s, drive.echoes.size());
  const calibration::RangerMountFit result =
      calibration::CalibrateRangers(drive, map, vehicle_file.vehicle, filter.config, config);
  LogTable(result);
  std::unique_ptr<mapio::OutputFile> vehicle_out;
  if (!o.vehicle_out_path.empty()) {
    vehicle_out = std::make_unique<mapio::OutputFile>(o.vehicle_out_path);
    vehicle_out->stream() << CalibratedVehicleJson(o, result);
  }
  mapio::OutputFile report(o.output_path);
  report.stream() << ReportJson(result, o).dump(2) << '\n';
  report.Commit();
  spdlog::info("wrote {}", o.output_path);
  if (vehicle_out) {
    vehicle_out->Commit();
    spdlog::info("wrote {} (the calibrated mounts)", o.vehicle_out_path);
  }
}

}  // namespace

void RegisterCalibrateCommand(CLI::App& app) {
  auto o = std::make_shared<CalibrateOptions>();
  CLI::App* cmd = app.add_subcommand(
      "calibrate", "Estimate the ultrasonic rangers' mounts from a recorded drive along a known row map");
  cmd->add_option("log", o->log_path, "Sensor log of the drive (docs/protocol.md §1) or a service journal")->required();
  cmd->add_option("--vehicle", o->vehicle_path, "Vehicle file with the configured mounts")->required();
  cmd->add_option("--map", o->map_path, "Row map (GeoJSON) of the rows driven along")->required();
  cmd->add_option("--filter", o->filter_path,
                  "Filter file for the reference trajectory and the sound cone; default: the vehicle's "
                  "recommended filter, else the built-in defaults");
  cmd->add_option("--config", o->config_path,
                  "Calibration settings (JSON object, any of the keys of docs/calibration.md; the rest default)");
  cmd->add_option("-o,--output", o->output_path, "Report to write (JSON)")->required();
  cmd->add_option("--write-vehicle", o->vehicle_out_path, "Also write the vehicle file with the calibrated mounts");
  cmd->callback([o] { RunReportingInputErrors("calibrate", [&o] { RunCalibrate(*o); }); });
}

}  // namespace rowloc::apps
