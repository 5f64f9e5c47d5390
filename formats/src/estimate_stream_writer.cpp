// Estimate-stream writer of docs/protocol.md §3 (see estimate_stream_writer.hpp).
#include "rowloc/formats/estimate_stream_writer.hpp"

#include "rowloc/formats/ndjson_writing.hpp"

#include <Eigen/Eigenvalues>

#include <nlohmann/json.hpp>

#include <algorithm>
#include <stdexcept>

namespace rowloc::formats {
namespace {

using ndjson::CheckTimeOrder;
using ndjson::Finite;
using ndjson::MessageStart;
using ndjson::Refuse;
using ordered_json = nlohmann::ordered_json;

/// `wheel_calibration`: {wheel: {rolling_radius_m, rolling_radius_sigma_m, slip_compliance,
/// slip_compliance_sigma}}; unique non-empty names, each number finite and in its domain
/// (kWheelCalibrationFields: R_w > 0, kappa and sigmas >= 0).
ordered_json CalibrationJson(const char* type, const std::vector<WheelCalibrationRecord>& wheels) {
  ordered_json out = ordered_json::object();
  for (const WheelCalibrationRecord& w : wheels) {
    if (w.wheel.empty() || out.contains(w.wheel)) Refuse(type, "wheel_calibration names must be unique and non-empty");
    ordered_json numbers = ordered_json::object();
    for (const WheelCalibrationField& field : kWheelCalibrationFields) {
      const double value = Finite(type, field.key, w.*field.member);
      if (!field.InDomain(value)) {
        Refuse(type, "wheel_calibration of '" + w.wheel + "': " + field.key + " " + field.DomainText());
      }
      numbers[field.key] = value;
    }
    out[w.wheel] = std::move(numbers);
  }
  return out;
}

/// `sensor_health`: {sensor: {state, reason, accepted, gated, skipped, refused}}; unique non-empty
/// names, state one of "ok", "suspect", "excluded".
ordered_json HealthJson(const char* type, const std::vector<SensorHealthRecord>& sensors) {
  ordered_json out = ordered_json::object();
  for (const SensorHealthRecord& h : sensors) {
    if (h.sensor.empty() || out.contains(h.sensor)) Refuse(type, "sensor_health names must be unique and non-empty");
    if (h.state != "ok" && h.state != "suspect" && h.state != "excluded") {
      Refuse(type, "sensor_health of '" + h.sensor + "': state must be ok, suspect or excluded, got '" + h.state + "'");
    }
    ordered_json entry = ordered_json::object();
    entry["state"] = h.state;
    entry["reason"] = h.reason;
    entry["accepted"] = h.accepted;
    entry["gated"] = h.gated;
    entry["skipped"] = h.skipped;
    entry["refused"] = h.refused;
    out[h.sensor] = std::move(entry);
  }
  return out;
}

}  // namespace

EstimateLogWriter::EstimateLogWriter(std::ostream& out, const std::string& source, const std::string& vehicle,
                                     const geometry::GeoOrigin& origin)
    : out_(out) {
  ordered_json j;
  j["type"] = "estimate_header";
  j["protocol"] = "rowloc-estimate/1";
  j["source"] = source;
  j["vehicle"] = vehicle;
  j["origin"] = ndjson::OriginJson(origin);
  out_ << j.dump() << '\n';
  if (!out_) throw std::runtime_error("estimate log: write failed");
}

void EstimateLogWriter::Write(const EstimateRecord& r) {
  const char* type = "estimate";
  CheckTimeOrder(type, r.time_s, last_time_s_);
  ordered_json j = MessageStart(type, r.time_s);
  j["x_m"] = Finite(type, "x_m", r.position_m.x());
  j["y_m"] = Finite(type, "y_m", r.position_m.y());
  if (r.heading_rad) j["phi_rad"] = Finite(type, "phi_rad", *r.heading_rad);
  if (r.covariance) {
    const int n = r.heading_rad ? 3 : 2;
    const Eigen::MatrixXd c = r.covariance->topLeftCorner(n, n);
    if (!c.allFinite()) Refuse(type, "covariance is not finite");
    if (!c.isApprox(c.transpose(), 1e-12) && (c - c.transpose()).norm() > 1e-15) {
      Refuse(type, "covariance is not symmetric");
    }
    // Positive semi-definite up to round-off (an estimate's covariance; NEES needs it).
    const Eigen::SelfAdjointEigenSolver<Eigen::MatrixXd> eigen(0.5 * (c + c.transpose()), Eigen::EigenvaluesOnly);
    if (eigen.eigenvalues().minCoeff() < -1e-12 * std::max(1.0, eigen.eigenvalues().cwiseAbs().maxCoeff())) {
      Refuse(type, "covariance is not positive semi-definite");
    }
    ordered_json values = ordered_json::array();
    for (int row = 0; row < n; ++row)
      for (int col = 0; col < n; ++col) values.push_back(c(row, col));
    j["covariance_xy_phi"] = values;
  }
  if (!r.slip.empty()) {
    ordered_json slip = ordered_json::object();
    for (const auto& [wheel, value] : r.slip) {
      if (wheel.empty() || slip.contains(wheel)) Refuse(type, "slip wheel names must be unique and non-empty");
      slip[wheel] = Finite(type, "slip", value);
    }
    j["slip"] = slip;
  }
  if (!r.wheel_calibration.empty()) j["wheel_calibration"] = CalibrationJson(type, r.wheel_calibration);
  if (!r.sensor_health.empty()) j["sensor_health"] = HealthJson(type, r.sensor_health);
  out_ << j.dump() << '\n';
  if (!out_) throw std::runtime_error("estimate log: write failed");
  last_time_s_ = r.time_s;
}

void EstimateLogWriter::WriteUpdate(const UpdateLogRecord& r) {
  const char* type = "update";
  CheckTimeOrder(type, r.time_s, last_time_s_);
  const Eigen::Index m = r.innovation.size();
  if (r.sensor.empty()) Refuse(type, "sensor name is empty");
  if (m == 0 || r.innovation_covariance.rows() != m || r.innovation_covariance.cols() != m) {
    Refuse(type, "innovation and innovation_covariance sizes do not match");
  }
  if (!r.innovation.allFinite() || !r.innovation_covariance.allFinite()) Refuse(type, "innovation is not finite");
  ordered_json j = MessageStart(type, r.time_s);
  j["sensor"] = r.sensor;
  j["innovation"] = std::vector<double>(r.innovation.data(), r.innovation.data() + m);
  ordered_json s = ordered_json::array();
  for (Eigen::Index row = 0; row < m; ++row)
    for (Eigen::Index col = 0; col < m; ++col) s.push_back(r.innovation_covariance(row, col));
  j["innovation_covariance"] = s;
  j["nis"] = Finite(type, "nis", r.nis);
  j["accepted"] = r.accepted;
  out_ << j.dump() << '\n';
  if (!out_) throw std::runtime_error("estimate log: write failed");
  last_time_s_ = r.time_s;
}

}  // namespace rowloc::formats
