// VehicleEkf: the map-aided ultrasonic update (issue 5; map_aided_ranging.hpp states the models).
#include "rowloc/localization/vehicle_ekf.hpp"

#include <algorithm>
#include <cmath>
#include <limits>
#include <stdexcept>

namespace rowloc::localization {
namespace {

/// States up to which the Jacobian of an echo lives on the stack (the shipped vehicles have <= 23).
constexpr int kStackStates = 64;
/// Echoes between two evaluations of the map's agreement (map_agreement.hpp).
constexpr std::size_t kAgreementEveryEchoes = 20;

/// The echo's Jacobian over the whole state: m.jacobian in the pose columns, zero elsewhere.
template <typename Matrix>
Matrix StateJacobian(const MapAidedMeasurement& m, Eigen::Index states) {
  Matrix h = Matrix::Zero(m.jacobian.rows(), states);
  h.template leftCols<3>() = m.jacobian;
  return h;
}

}  // namespace

void VehicleEkf::AttachRowMap(const geometry::RowMap& map) {
  if (vehicle_.ultrasonic.empty()) {
    throw std::invalid_argument("row map: the vehicle '" + vehicle_.name + "' has no ultrasonic sensor to use it");
  }
  ranging_ = std::make_shared<const RowMapRanging>(map, frame_.origin(), config_.map_aided.row_smoothing_m);
}

std::optional<std::size_t> VehicleEkf::UltrasonicIndex(const std::string& name, std::size_t hint) const {
  if (hint < vehicle_.ultrasonic.size() && vehicle_.ultrasonic[hint].name == name) return hint;
  const auto it = std::find_if(vehicle_.ultrasonic.begin(), vehicle_.ultrasonic.end(),
                               [&](const mapio::SensorMount& m) { return m.name == name; });
  if (it == vehicle_.ultrasonic.end()) return std::nullopt;
  return static_cast<std::size_t>(it - vehicle_.ultrasonic.begin());
}

void VehicleEkf::CheckMapAgreement() {
  if (map_aided_stats_.echoes % kAgreementEveryEchoes != 0) return;
  health_.ObserveDisagreement("map", map_agreement_.MapProblem());
}

ProcessResult VehicleEkf::Apply(const formats::UltrasonicMessage& ping) {
  ProcessResult result;
  if (!ranging_ || !initialised_ || !ping.range_m) return result;  // no echo: no measurement
  MapAidedStats& stats = map_aided_stats_;
  ++stats.echoes;
  const RangeSensorMount& mount = ultrasonic_mounts_[*UltrasonicIndex(ping.sensor, ping.sensor_index)];  // checked by Validate
  const MapAidedConfig& config = config_.map_aided;
  const Eigen::Vector3d pose = x_.head<3>();
  const Eigen::Matrix3d pose_covariance = p_.topLeftCorner<3, 3>();
  EchoTrace& trace = result.echo.emplace();
  trace.sensor = ping.sensor;
  trace.measured_range_m = *ping.range_m;
  trace.prior_position_m = trace.posterior_position_m = pose.head<2>();
  trace.prior_covariance = trace.posterior_covariance = pose_covariance.topLeftCorner<2, 2>();
  // Association checks 1-3 of map_aided_ranging.hpp: the heading, the sensor inside a canopy, the lane.
  if (config.k_sigma * std::sqrt(pose_covariance(2, 2)) > mount.cone_half_angle_rad) {
    ++stats.heading_uncertain;
    trace.outcome = "heading_uncertain";
    return result;
  }
  // Candidates: every surface within k sigma (position and range) of the nearest predicted one.
  const double window_m =
      config.k_sigma * (std::sqrt(pose_covariance.topLeftCorner<2, 2>().trace()) + config.range_sigma_m +
                        ranging_->max_outline_sigma_m());
  const std::vector<EchoCandidate>& candidates =
      ranging_->Candidates(pose, mount, config.max_range_m, window_m, candidate_buffers_);
  map_agreement_.ObserveEcho(!candidate_buffers_.sensor_inside_outline && !candidates.empty());
  CheckMapAgreement();
  if (candidate_buffers_.sensor_inside_outline) {
    ++stats.inside_outline;
    trace.outcome = "inside_outline";
    return result;
  }
  if (candidates.empty()) {
    ++stats.no_segment;
    trace.outcome = "no_segment";
    return result;
  }
  if (candidates.size() > 1) ++stats.ambiguous;
  const EchoCandidate* best = nullptr;
  double best_nis = std::numeric_limits<double>::infinity();
  for (const EchoCandidate& c : candidates) {
    const double nis = RangeNis(c, mount, *ping.range_m, pose_covariance, config.range_sigma_m);
    if (nis < best_nis || best == nullptr) {
      best_nis = nis;
      best = &c;
    }
  }
  trace.segment = ranging_->index().entries()[best->entry].segment;
  trace.line = best->edge;
  const double range_variance = best->jacobian * pose_covariance * best->jacobian.transpose();
  if (config.k_sigma * std::sqrt(range_variance) > 0.5 * best->lane_clearance_m) {
    ++stats.lane_ambiguous;
    trace.outcome = "lane_ambiguous";
    return result;
  }
  const MapAidedMeasurement m = MakeMapAidedMeasurement(*best, mount, pose, pose_covariance, *ping.range_m, config);
  if (m.innovation.size() == 0) {
    switch (m.cut_status) {
      case geometry::CutStatus::kEmpty: ++stats.contradicting; trace.outcome = "contradicting"; break;
      case geometry::CutStatus::kUnchanged: ++stats.uninformative; trace.outcome = "uninformative"; break;
      default: ++stats.degenerate; trace.outcome = "degenerate"; break;
    }
    return result;
  }
  const double gate = m.innovation.size() == 1 ? gate_map_aided_1_ : gate_map_aided_2_;
  using StackJacobian = Eigen::Matrix<double, Eigen::Dynamic, Eigen::Dynamic, 0, 2, kStackStates>;
  const UpdateRecord& record = result.updates.emplace_back(
      x_.size() <= kStackStates
          ? Update(ping.time_s, "ultrasonic", m.innovation, StateJacobian<StackJacobian>(m, x_.size()), m.noise, gate)
          : Update(ping.time_s, "ultrasonic", m.innovation, StateJacobian<Eigen::MatrixXd>(m, x_.size()), m.noise, gate));
  trace.outcome = record.outcome.accepted ? "accepted" : "gated";
  trace.posterior_position_m = x_.head<2>();
  trace.posterior_covariance = p_.topLeftCorner<2, 2>();
  return result;
}

}  // namespace rowloc::localization
