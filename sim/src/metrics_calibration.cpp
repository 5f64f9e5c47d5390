// The slip-aware odometry's rolling radius against the truth (see metrics.hpp, "Rolling radius").
#include "rowloc/sim/metrics.hpp"

namespace rowloc::sim {

std::vector<RollingRadiusError> CompareRollingRadius(const formats::TruthStream& truth,
                                                     const formats::EstimateStream& estimates, double probability) {
  struct Samples {
    std::vector<double> errors_m;
    std::vector<double> nees;
    RollingRadiusError result;
  };
  std::map<std::string, Samples> wheels;
  for (const formats::EstimateSample& est : estimates.estimates) {
    if (est.wheel_calibration.empty()) continue;
    const TruthState state = InterpolateTruth(truth, est.t_s);
    for (const formats::WheelCalibrationRecord& c : est.wheel_calibration) {
      const auto it = state.wheel_rolling_radius_m.find(c.wheel);
      if (it == state.wheel_rolling_radius_m.end()) continue;
      Samples& w = wheels[c.wheel];
      const double error_m = c.rolling_radius_m - it->second;
      w.errors_m.push_back(error_m);
      if (c.rolling_radius_sigma_m > 0.0) {
        w.nees.push_back(error_m * error_m / (c.rolling_radius_sigma_m * c.rolling_radius_sigma_m));
      } else {
        ++w.result.zero_sigma_count;
      }
      w.result.final_estimate_m = c.rolling_radius_m;
      w.result.final_sigma_m = c.rolling_radius_sigma_m;
      w.result.final_truth_m = it->second;
    }
  }
  std::vector<RollingRadiusError> out;
  for (auto& [wheel, w] : wheels) {
    w.result.wheel = wheel;
    w.result.error_m = Summarize(w.errors_m);
    w.result.nees = SummarizeConsistency(w.nees, std::vector<int>(w.nees.size(), 1), probability);
    out.push_back(std::move(w.result));
  }
  return out;
}

}  // namespace rowloc::sim
