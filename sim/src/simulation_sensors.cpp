// Sensor sampling of a simulation run (the model is stated in simulation.hpp).
#include "simulation_run.hpp"

#include <Eigen/Geometry>

#include <algorithm>
#include <cmath>

namespace rowloc::sim::detail {

const VehicleTruth& SimulationRun::TruthAt(double time_s) {
  // Several clocks tick at the same instants (e.g. every 20 ms: imu, steering, wheels, truth).
  if (!cached_truth_ || cached_truth_time_s_ != time_s) {
    cached_truth_ = truth_.At(time_s);
    cached_truth_time_s_ = time_s;
  }
  return *cached_truth_;
}

void SimulationRun::SampleGnss(double time_s) {
  const auto& off_after = scenario_.gnss->off_after_s;
  if ((off_after && time_s > *off_after) || scenario_.faults.GnssOut(time_s)) {  // no message at all
    gnss_fix_ = false;
    return;
  }
  const VehicleTruth& truth = TruthAt(time_s);
  const SensorMount& antenna = scenario_.vehicle.gnss_antenna;
  const Eigen::Vector3d position = truth_.WorldPoint(truth, antenna.position_m);
  const double cover = cover_ ? cover_->At(position.head<2>(), antenna.position_m.z(), truth.route.heading_rad) : 0.0;
  GnssSample sample = gnss_->Measure(time_s, position, cover);
  const auto& outliers = scenario_.faults.gnss_outliers;
  std::optional<double> outlier_altitude_m;  // an outlier keeps the fix's altitude (a receiver's fault)
  if (sample.has_fix && next_gnss_outlier_ < outliers.size() && time_s >= outliers[next_gnss_outlier_].time_s) {
    outlier_altitude_m = frame_.ToGeodetic(sample.position_m).altitude_m;
    sample.position_m.head<2>() += outliers[next_gnss_outlier_++].offset_m;  // injected fault
  }
  gnss_faults_ = sample.faults;
  gnss_fix_ = sample.has_fix;
  GpsMessage message;
  message.time_s = scenario_.faults.Stamp(time_s);
  message.sensor = antenna.name;
  message.fix = sample.has_fix ? sample.fix : formats::GnssFixQuality::kNone;
  if (sample.has_fix) {
    const geometry::GeoOrigin geodetic = frame_.ToGeodetic(sample.position_m);
    message.latitude_deg = geodetic.latitude_deg;
    message.longitude_deg = geodetic.longitude_deg;
    message.altitude_m = outlier_altitude_m.value_or(geodetic.altitude_m);
    message.sigma_horizontal_m = sample.sigma_horizontal_m;
    message.sigma_vertical_m = sample.sigma_vertical_m;
    ++summary_.gps_fixes;
    if (sample.faults.multipath) ++summary_.gps_multipath;
  } else {
    ++summary_.gps_no_fix;
  }
  sensor_log_->Write(message);
  if (gnss_baseline_ && sample.has_fix) {
    const double variance = sample.sigma_horizontal_m * sample.sigma_horizontal_m;
    // The antenna lever arm is removed with the dead-reckoning heading (sensor data only, no truth).
    const double heading = dead_reckoning_ ? dead_reckoning_->pose().heading_rad : 0.0;
    const Eigen::Vector2d lever = dead_reckoning_ ? Eigen::Rotation2Dd(heading) * antenna.position_m.head<2>()
                                                  : Eigen::Vector2d::Zero();
    const Eigen::Matrix3d covariance = Eigen::Vector3d(variance, variance, 0.0).asDiagonal().toDenseMatrix();
    gnss_baseline_->Write(
        formats::EstimateRecord{time_s, sample.position_m.head<2>() - lever, std::nullopt, covariance, {}, {}, {}});
  }
}

void SimulationRun::SampleImu(double time_s) {
  const VehicleTruth& truth = TruthAt(time_s);
  const Eigen::Vector2d force = truth_.SpecificForce(truth, scenario_.vehicle.imu.position_m.head<2>());
  ImuSample sample = imu_->Measure(time_s, ImuTruth{force.x(), force.y(), truth.motion.yaw_rate_radps});
  imu_bias_ = sample.bias;
  if (scenario_.faults.imu_dead_after_s && time_s >= *scenario_.faults.imu_dead_after_s) {
    sample.accel_x_mps2 = sample.accel_y_mps2 = sample.gyro_z_radps = 0.0;  // injected fault: a dead IMU
  }
  sensor_log_->Write(ImuMessage{scenario_.faults.Stamp(time_s), scenario_.vehicle.imu.name, sample.accel_x_mps2, sample.accel_y_mps2,
                                sample.gyro_z_radps});
  ++summary_.imu;
  if (dead_reckoning_) dead_reckoning_->SetYawRate(time_s, sample.gyro_z_radps);
}

void SimulationRun::SampleSteering(double time_s) {
  const VehicleTruth& truth = TruthAt(time_s);
  SteeringMessage message{scenario_.faults.Stamp(time_s), {}};
  for (std::size_t i = 0; i < steering_encoders_.size(); ++i) {
    if (!steering_encoders_[i]) continue;
    const double angle = steering_encoders_[i]->Measure(time_s, truth.wheels[i].steering_angle_rad).angle_rad;
    steering_readings_rad_[i] = angle;
    message.angle_rad.emplace_back(scenario_.vehicle.wheels[i].name, angle);
  }
  sensor_log_->Write(message);
  ++summary_.steering;
  if (dead_reckoning_) dead_reckoning_->SetSteering(time_s, steering_readings_rad_);
}

void SimulationRun::SampleWheels(double time_s) {
  const std::size_t n = scenario_.vehicle.wheels.size();
  std::vector<double> mean_rate(n);
  if (previous_wheel_time_s_) {  // Simpson's rule on the exact rate over (t_prev, t]
    const VehicleTruth& middle = TruthAt(0.5 * (*previous_wheel_time_s_ + time_s));
    for (std::size_t i = 0; i < n; ++i) {
      mean_rate[i] = previous_wheel_rate_radps_[i] + 4.0 * middle.wheels[i].wheel_angular_speed_radps;
    }
  }
  const VehicleTruth& truth = TruthAt(time_s);  // after the middle: TruthAt keeps one time
  if (previous_wheel_time_s_) {
    for (std::size_t i = 0; i < n; ++i) mean_rate[i] = (mean_rate[i] + truth.wheels[i].wheel_angular_speed_radps) / 6.0;
  }
  WheelsMessage message{scenario_.faults.Stamp(time_s), {}, {}, {}};
  dead_wheel_angle_.resize(n);
  std::vector<double> readings(n);
  const double torque_sigma = scenario_.torque ? scenario_.torque->noise_sigma_nm : 0.0;
  std::normal_distribution<double> unit_normal;  // std::normal_distribution needs sigma > 0: scaled here
  for (std::size_t i = 0; i < n; ++i) {
    const std::string& name = scenario_.vehicle.wheels[i].name;
    WheelEncoderSample sample = wheel_encoders_[i].Measure(time_s, mean_rate[i]);
    for (const WheelEncoderDeadFault& dead : scenario_.faults.wheel_encoders_dead) {
      if (dead.wheel != name || time_s < dead.after_s) continue;  // injected fault: a dead encoder
      if (!dead_wheel_angle_[i]) dead_wheel_angle_[i] = sample.cumulative_angle_rad;
      sample.speed_radps = 0.0;
      sample.cumulative_angle_rad = *dead_wheel_angle_[i];
    }
    readings[i] = sample.speed_radps;
    message.speed_radps.emplace_back(name, readings[i]);
    message.angle_rad.emplace_back(name, sample.cumulative_angle_rad);
    if (scenario_.torque) message.torque_nm.emplace_back(name, truth.wheels[i].torque_nm + torque_sigma * unit_normal(torque_rng_));
  }
  previous_wheel_time_s_ = time_s;
  previous_wheel_rate_radps_.resize(n);
  std::transform(truth.wheels.begin(), truth.wheels.end(), previous_wheel_rate_radps_.begin(),
                 [](const WheelTruth& w) { return w.wheel_angular_speed_radps; });
  sensor_log_->Write(message);
  ++summary_.wheels;
  if (dead_reckoning_) {
    const PlanarPose pose = dead_reckoning_->AddWheelSpeeds(time_s, readings);
    odometry_baseline_->Write(
        formats::EstimateRecord{time_s, pose.position_m, pose.heading_rad, std::nullopt, {}, {}, {}});
  }
}

void SimulationRun::SampleVio(double time_s) {
  const VehicleTruth& truth = TruthAt(time_s);
  const Eigen::Vector2d velocity = PointVelocity(truth.motion, scenario_.vio->position_m.head<2>());
  std::normal_distribution<double> unit_normal;
  const double vx = velocity.x() + scenario_.vio->sigma_mps * unit_normal(vio_rng_);
  const double vy = velocity.y() + scenario_.vio->sigma_mps * unit_normal(vio_rng_);
  sensor_log_->Write(VioMessage{scenario_.faults.Stamp(time_s), "camera", vx, vy, scenario_.vio->sigma_mps});
  ++summary_.vio;
}

void SimulationRun::SampleUltrasonic(std::size_t sensor, double time_s) {
  const VehicleTruth& truth = TruthAt(time_s);
  const SensorMount& mount = scenario_.ultrasonic->mounts[sensor];
  const Eigen::Vector3d apex = truth_.WorldPoint(truth, mount.position_m);
  const auto reading = ultrasonic_[sensor].Measure(*caster_, apex.head<2>(),
                                                   VehicleTruthSampler::WorldDirection(truth, mount.yaw_rad),
                                                   mount.position_m.z());
  UltrasonicMessage message{scenario_.faults.Stamp(time_s), mount.name, std::nullopt};
  stuck_range_m_.resize(scenario_.ultrasonic->mounts.size());
  const auto& stuck_after = scenario_.faults.ultrasonic_stuck_after_s;
  if (stuck_after && time_s >= *stuck_after && stuck_range_m_[sensor]) {
    message.range_m = stuck_range_m_[sensor];  // injected fault: the ranger repeats its last range
  } else if (reading) {
    message.range_m = reading->range_m;
    stuck_range_m_[sensor] = reading->range_m;
    ++summary_.ultrasonic_echoes;
  } else {
    ++summary_.ultrasonic_no_echo;
  }
  sensor_log_->Write(message);
}

void SimulationRun::WriteTruth(double time_s) {
  const VehicleTruth& truth = TruthAt(time_s);
  TruthRecord record;
  record.time_s = time_s;
  record.position_m = truth.position_m;
  record.heading_rad = truth.route.heading_rad;
  record.velocity_x_mps = truth.motion.v_x_mps;
  record.velocity_y_mps = truth.motion.v_y_mps;
  record.yaw_rate_radps = truth.motion.yaw_rate_radps;
  const Eigen::Vector2d force = truth_.SpecificForce(truth, Eigen::Vector2d::Zero());
  record.accel_x_mps2 = force.x();
  record.accel_y_mps2 = force.y();
  record.gnss_available = gnss_.has_value() && gnss_fix_;
  record.gnss_multipath = gnss_faults_.multipath;
  const SensorMount& antenna = scenario_.vehicle.gnss_antenna;
  record.canopy_cover =
      cover_ ? cover_->At(truth_.WorldPoint(truth, antenna.position_m).head<2>(), antenna.position_m.z(),
                          truth.route.heading_rad)
             : 0.0;
  record.imu_bias_accel_x_mps2 = imu_bias_.accel_x_mps2;
  record.imu_bias_accel_y_mps2 = imu_bias_.accel_y_mps2;
  record.imu_bias_gyro_z_radps = imu_bias_.gyro_z_radps;
  for (std::size_t i = 0; i < truth.wheels.size(); ++i) {
    const WheelTruth& w = truth.wheels[i];
    record.wheels.push_back({scenario_.vehicle.wheels[i].name, w.steering_angle_rad, w.wheel_angular_speed_radps,
                             w.slip, w.rolling_radius_m, w.torque_nm, std::string(TerrainClassName(w.terrain))});
    if (w.traction_limited) ++summary_.traction_limited_samples;
    summary_.max_abs_slip = std::max(summary_.max_abs_slip, std::abs(w.slip));
  }
  truth_log_->Write(record);
}

}  // namespace rowloc::sim::detail
