// VehicleEkf with fixed-interval smoothing (EnableSmoothing, fixed_interval_smoother.hpp): the
// recording changes nothing in the filter, records every transition the filter makes (checked:
// no negative implied process noise, in every filter mode), and the smoothed track beats the
// filtered one through a GNSS outage; chains at re-initialisation; misuse refused.
#include "vehicle_ekf_test_support.hpp"

namespace rowloc::localization {
namespace {

/// Removes the GNSS fixes in [from_s, to_s) (and their truth samples).
void DropFixes(Drive& d, double from_s, double to_s) {
  const auto in_outage = [&](double t) { return t >= from_s && t < to_s; };
  std::erase_if(d.messages, [&](const formats::SensorMessage& m) {
    return std::holds_alternative<formats::GpsMessage>(m) && in_outage(formats::TimeOf(m));
  });
  std::erase_if(d.truth, [&](const Sample& s) { return in_outage(s.t); });
}

/// Pose truth at every 0.01 s step of MakeDrive's segments (the fixes' truth only covers fixes).
struct TruthTrack {
  Pose start;
  std::vector<Segment> segments;
  Pose At(double t) const {
    Pose pose = start;
    for (const Segment& s : segments) {
      if (t <= s.duration_s) return Advance(pose, s, t);
      pose = Advance(pose, s, s.duration_s);
      t -= s.duration_s;
    }
    return pose;
  }
};

struct SmoothingRun {
  std::vector<SmoothedState> smoothed;
  std::vector<SmoothedState> filtered;  ///< the filter's state at each mark
  double min_relative_process_noise = 0.0;
  std::size_t nodes = 0;
};

/// Processes the drive with smoothing (transitions checked), marking after every message from
/// mark_from_s on at most every 0.1 s.
SmoothingRun Smooth(VehicleEkf& ekf, const Drive& d, double mark_from_s = 0.0) {
  ekf.EnableSmoothing(/*check_transitions=*/true);
  SmoothingRun run;
  double next_mark_s = mark_from_s;
  for (const formats::SensorMessage& m : d.messages) {
    ekf.Process(m);
    if (!ekf.initialised() || ekf.time_s() < next_mark_s) continue;
    EXPECT_EQ(ekf.MarkForSmoothing(), run.filtered.size());
    run.filtered.push_back({ekf.time_s(), ekf.state(), ekf.covariance()});
    next_mark_s = ekf.time_s() + 0.1;
  }
  if (ekf.initialised()) {  // after the last message: nothing follows this mark
    ekf.MarkForSmoothing();
    run.filtered.push_back({ekf.time_s(), ekf.state(), ekf.covariance()});
  }
  run.min_relative_process_noise = ekf.smoother()->min_relative_process_noise();
  run.nodes = ekf.smoother()->nodes();
  run.smoothed = ekf.FinishSmoothing();
  EXPECT_EQ(ekf.smoother(), nullptr);
  return run;
}

double RmsPositionError(const std::vector<SmoothedState>& states, const TruthTrack& truth, double from_s, double to_s) {
  double sum = 0.0;
  int count = 0;
  for (const SmoothedState& s : states) {
    if (s.time_s < from_s || s.time_s >= to_s) continue;
    sum += (s.state.head<2>() - truth.At(s.time_s).p).squaredNorm();
    ++count;
  }
  EXPECT_GT(count, 0);
  return std::sqrt(sum / std::max(count, 1));
}

void ExpectSmoothedBeatsFiltered(const VehicleConfig& v, const FilterConfig& config, bool torque, bool angles) {
  SCOPED_TRACE(v.name);
  const TruthTrack truth{{{-5.0, 2.0}, 0.4}, {{6.0, 1.0, 0.0, 0.0}, {12.0, 1.0, 0.0, 0.2}}};
  Drive d = MakeDrive(v, truth.start, truth.segments, 0.0, 5, torque);
  if (angles) AddWheelAngles(d);
  DropFixes(d, 9.0, 15.0);  // a 6 s GNSS outage
  VehicleEkf ekf(v, config, kOrigin, WheelNames(v));
  const SmoothingRun run = Smooth(ekf, d);
  ASSERT_EQ(run.smoothed.size(), run.filtered.size());
  EXPECT_GT(run.nodes, run.smoothed.size());
  // Every transition was recorded: P^- - Phi P Phi^T is positive semi-definite at every node.
  EXPECT_GT(run.min_relative_process_noise, -1e-9);
  const double filtered = RmsPositionError(run.filtered, truth, 9.0, 15.0);
  const double smoothed = RmsPositionError(run.smoothed, truth, 9.0, 15.0);
  EXPECT_LT(smoothed, 0.7 * filtered) << "filtered " << filtered << " m, smoothed " << smoothed << " m";
  for (std::size_t i = 0; i < run.smoothed.size(); ++i) {
    const Eigen::MatrixXd& p = run.smoothed[i].covariance;
    EXPECT_EQ(p, p.transpose());
    EXPECT_EQ(Eigen::LLT<Eigen::MatrixXd>(p).info(), Eigen::Success) << "mark " << i;
    EXPECT_EQ(run.smoothed[i].time_s, run.filtered[i].time_s);
    // Smoothing only adds information: the position variance does not grow.
    const double smoothed_variance = p.topLeftCorner(2, 2).trace();
    EXPECT_LE(smoothed_variance, run.filtered[i].covariance.topLeftCorner(2, 2).trace() * (1 + 1e-9));
  }
  // The last mark has nothing after it: smoothed = filtered. (A mark between messages of one time
  // stamp gets the smoothed state of that time, which includes the messages after the mark.)
  EXPECT_LT((run.smoothed.back().state - run.filtered.back().state).cwiseAbs().maxCoeff(), 1e-9);
}

TEST(VehicleEkfSmoothing, BeatsTheFilterThroughAGnssOutageEveryVehicle) {
  FilterConfig config;
  ExpectSmoothedBeatsFiltered(mapio::AgrimaroSwerveConfig(), config, false, false);
  ExpectSmoothedBeatsFiltered(mapio::VineyardUgv4wsConfig(), config, false, false);
  ExpectSmoothedBeatsFiltered(mapio::TrackedVehicleConfig(), config, false, false);
  config.slip_aware_odometry.enabled = true;
  ExpectSmoothedBeatsFiltered(mapio::DifferentialDriveConfig(), config, false, false);
}

TEST(VehicleEkfSmoothing, WheelAnglesAndTractionStatesAreRecorded) {
  // The modes with re-anchoring: the wheel angles (anchored at the first angles) and the traction
  // states; a torque step re-anchors mu.
  FilterConfig config;
  config.slip_aware_odometry.enabled = true;
  config.slip_aware_odometry.torque_sigma_nm = 0.05;
  config.wheels.angle_measurement = true;
  config.wheels.angle_rate_noise_radps_per_sqrt_hz = 1e-3;
  const VehicleConfig v = mapio::DifferentialDriveConfig();
  Drive d = MakeDrive(v, {{0.0, 0.0}, 0.0}, StraightThenCircle(), 0.0, 7, /*torque=*/true);
  AddWheelAngles(d);
  for (formats::SensorMessage& m : d.messages) {
    auto* wheels = std::get_if<formats::WheelsMessage>(&m);
    if (wheels && wheels->time_s >= 12.0) wheels->torque_nm = std::vector<double>(v.wheels.size(), 6.0);
  }
  VehicleEkf ekf(v, config, kOrigin, WheelNames(v));
  std::size_t reanchored = 0;
  ekf.EnableSmoothing(true);
  double next_mark_s = 0.0;
  for (const formats::SensorMessage& m : d.messages) {
    const ProcessResult r = ekf.Process(m);
    for (const UpdateRecord& u : r.updates) reanchored += u.sensor == "torque" && !u.outcome.accepted;
    if (ekf.initialised() && ekf.time_s() >= next_mark_s) {
      ekf.MarkForSmoothing();
      next_mark_s = ekf.time_s() + 0.1;
    }
  }
  EXPECT_GE(reanchored, 1u);  // the torque step was re-anchored
  EXPECT_GT(ekf.smoother()->min_relative_process_noise(), -1e-9);
  const std::vector<SmoothedState> smoothed = ekf.FinishSmoothing();
  EXPECT_GT(smoothed.size(), 300u);
  for (const SmoothedState& s : smoothed) EXPECT_TRUE(s.state.allFinite());
}

TEST(VehicleEkfSmoothing, RecordingChangesNothingInTheFilter) {
  const VehicleConfig v = mapio::AgrimaroSwerveConfig();
  const Drive d = MakeDrive(v, {{0.0, 0.0}, 0.3}, StraightThenCircle(), 0.0, 9);
  VehicleEkf plain = MakeEkf(v, true), recording = MakeEkf(v, true);
  recording.EnableSmoothing();
  for (const formats::SensorMessage& m : d.messages) {
    plain.Process(m);
    recording.Process(m);
    if (recording.initialised()) recording.MarkForSmoothing();
  }
  EXPECT_TRUE(BitIdentical(Snap(plain), Snap(recording)));
}

TEST(VehicleEkfSmoothing, SetPoseAndReinitialisationAreRecorded) {
  const VehicleConfig v = mapio::DifferentialDriveConfig();
  FilterConfig config;
  config.slip_aware_odometry.enabled = true;
  VehicleEkf ekf(v, config, kOrigin, WheelNames(v));
  ekf.EnableSmoothing(true);
  const Drive first = MakeDrive(v, {{0.0, 0.0}, 0.0}, {{8.0, 1.0, 0.0, 0.0}}, 0.0, 11);
  std::size_t marks = 0;
  const auto mark = [&] {
    EXPECT_EQ(ekf.MarkForSmoothing(), marks);
    ++marks;
  };
  for (const formats::SensorMessage& m : first.messages) {
    ekf.Process(m);
    if (ekf.initialised()) mark();
  }
  ekf.SetPose(8.0, {8.0, 0.0, 0.0}, Eigen::Matrix3d::Identity() * 1e-4);  // the pose set anew
  mark();
  // A gap longer than max_prediction_gap_s: the filter drops its state and re-initialises.
  const double restart_s = 8.0 + config.max_prediction_gap_s + 1.0;
  const Drive second = MakeDrive(v, {{20.0, 0.0}, 0.0}, {{8.0, 1.0, 0.0, 0.0}}, restart_s, 13);
  bool reinitialised = false;
  for (const formats::SensorMessage& m : second.messages) {
    const ProcessResult r = ekf.Process(m);
    reinitialised = reinitialised || (r.notice && r.notice->find("initialised") != std::string::npos);
    if (ekf.initialised()) mark();
  }
  EXPECT_TRUE(reinitialised);
  EXPECT_GT(ekf.smoother()->min_relative_process_noise(), -1e-9);
  const std::vector<SmoothedState> smoothed = ekf.FinishSmoothing();
  ASSERT_EQ(smoothed.size(), marks);
  EXPECT_LT((smoothed.back().state - ekf.state()).cwiseAbs().maxCoeff(), 1e-12);
  for (const SmoothedState& s : smoothed) {
    EXPECT_TRUE(s.state.allFinite());
    if (s.time_s >= restart_s) {
      EXPECT_GT(s.state(StateLayout::kX), 15.0);  // the second chain's own states
    }
  }
}

TEST(VehicleEkfSmoothing, MisuseIsRefused) {
  const VehicleConfig v = mapio::DifferentialDriveConfig();
  VehicleEkf ekf = MakeEkf(v);
  EXPECT_THROW(ekf.MarkForSmoothing(), std::logic_error);  // not enabled
  EXPECT_THROW(ekf.FinishSmoothing(), std::logic_error);
  ekf.EnableSmoothing();
  EXPECT_THROW(ekf.EnableSmoothing(), std::logic_error);
  EXPECT_THROW(ekf.MarkForSmoothing(), std::logic_error);  // not initialised
  EXPECT_TRUE(ekf.FinishSmoothing().empty());
  // Enabled after initialisation: the chain starts at the current state.
  ekf.SetPose(0.0, {0.0, 0.0, 0.0}, Eigen::Matrix3d::Identity() * 1e-4);
  ekf.EnableSmoothing();
  ekf.MarkForSmoothing();
  EXPECT_EQ(ekf.FinishSmoothing().size(), 1u);
}

}  // namespace
}  // namespace rowloc::localization
