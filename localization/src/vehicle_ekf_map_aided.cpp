// VehicleEkf: the map-aided ultrasonic update (issue 5). MapAidedUpdater (map_aided_updater.hpp)
// makes the measurement from the pose block; here it is applied to the full state.
#include "rowloc/localization/vehicle_ekf.hpp"

#include <utility>

namespace rowloc::localization {
namespace {

/// States up to which the Jacobian of an echo lives on the stack (the shipped vehicles have <= 23).
constexpr int kStackStates = 64;

/// The echo's Jacobian over the whole state: m.jacobian in the pose columns, zero elsewhere.
template <typename Matrix>
Matrix StateJacobian(const MapAidedMeasurement& m, Eigen::Index states) {
  Matrix h = Matrix::Zero(m.jacobian.rows(), states);
  h.template leftCols<3>() = m.jacobian;
  return h;
}

}  // namespace

void VehicleEkf::AttachRowMap(const geometry::RowMap& map) { map_aided_.AttachRowMap(map); }

ProcessResult VehicleEkf::Apply(const formats::UltrasonicMessage& ping) {
  ProcessResult result;
  if (!map_aided_.has_row_map() || !initialised_ || !ping.range_m) return result;  // no echo: no measurement
  MapAidedEcho echo = map_aided_.Measure(ping, x_.head<3>(), p_.topLeftCorner<3, 3>());
  if (echo.agreement_checked) health_.ObserveDisagreement("map", echo.map_problem);
  EchoTrace& trace = result.echo.emplace(std::move(echo.trace));
  if (!echo.measurement) return result;
  const MapAidedMeasurement& m = *echo.measurement;
  using StackJacobian = Eigen::Matrix<double, Eigen::Dynamic, Eigen::Dynamic, 0, 2, kStackStates>;
  const UpdateRecord& record = result.updates.emplace_back(
      x_.size() <= kStackStates
          ? Update(ping.time_s, "ultrasonic", m.innovation, StateJacobian<StackJacobian>(m, x_.size()), m.noise, echo.gate)
          : Update(ping.time_s, "ultrasonic", m.innovation, StateJacobian<Eigen::MatrixXd>(m, x_.size()), m.noise,
                   echo.gate));
  trace.outcome = record.outcome.accepted ? "accepted" : "gated";
  trace.posterior_position_m = x_.head<2>();
  trace.posterior_covariance = p_.topLeftCorner<2, 2>();
  return result;
}

}  // namespace rowloc::localization
