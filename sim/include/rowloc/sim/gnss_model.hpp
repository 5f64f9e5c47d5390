// GNSS receiver error model: truth in, fix out (the design's "GPS noise, dropouts under canopy and
// multipath jumps"; issue 3, Sensors). The caller passes the true antenna position (world ENU, m),
// the epoch time (s) and the canopy-cover factor c in [0, 1] above the antenna at that epoch.
//
// Math (docs/simulation-sensors.md):
//  - Noise: x_meas = x_true + m + n, n ~ N(0, diag(s_h^2, s_h^2, s_v^2)) i.i.d. per epoch, with the
//    canopy law s_h(c) = s_h0 (1 + g c), s_v(c) = s_v0 (1 + g c) (g = canopy_sigma_gain).
//  - Dropouts: a two-state continuous-time Markov chain (fix <-> no fix), onset rate
//    a(c) = a_open + (a_canopy - a_open) c, recovery rate b = 1 / mean_outage_s. Between two epochs
//    dt apart the chain is advanced by its exact transition matrix
//      P(fix -> none) = a/(a+b) (1 - exp(-(a+b) dt)),  P(none -> fix) = b/(a+b) (1 - exp(-(a+b) dt)),
//    so the stationary outage occupancy is a/(a+b) and the outage durations are exponential with
//    mean 1/b (seen at the epochs as geometric runs of mean 1 / P(none -> fix) epochs).
//  - Multipath: a second chain of the same form (onset m(c) = m_open + (m_canopy - m_open) c,
//    mean duration T_mp). At onset it draws a constant horizontal offset m of magnitude
//    U[min, max] m in a uniformly random direction, held until the chain recovers.
// Each sample carries the true fault state (for the validation suite) next to the measurement.
#pragma once

#include "rowloc/formats/gnss_fix_quality.hpp"

#include <Eigen/Core>

#include <cstdint>
#include <random>

namespace rowloc::sim {

/// Two-state Markov fault process parameters (rates in 1/s, durations in s).
struct GnssMarkovFaultConfig {
  double onset_rate_open_per_s = 0.0;    ///< onset rate with no canopy (c = 0)
  double onset_rate_canopy_per_s = 0.0;  ///< onset rate under full canopy (c = 1)
  double mean_duration_s = 1.0;          ///< mean duration of one fault episode (> 0)
  bool operator==(const GnssMarkovFaultConfig&) const = default;
};

struct GnssConfig {
  double rate_hz = 10.0;                 ///< nominal output rate (epochs per second)
  double sigma_horizontal_m = 0.01;      ///< per-axis (east, north) 1-sigma noise in the open
  double sigma_vertical_m = 0.0;         ///< up-axis 1-sigma noise in the open (0: exact)
  double canopy_sigma_gain = 0.0;        ///< g in s(c) = s0 (1 + g c), >= 0
  formats::GnssFixQuality nominal_fix = formats::GnssFixQuality::kRtkFixed;  ///< reported when a fix exists
  GnssMarkovFaultConfig dropout;         ///< outages (no fix)
  GnssMarkovFaultConfig multipath;       ///< constant-offset jumps
  double multipath_offset_min_m = 0.0;   ///< smallest jump magnitude
  double multipath_offset_max_m = 0.0;   ///< largest jump magnitude (>= min)
  bool operator==(const GnssConfig&) const = default;

  /// Throws std::invalid_argument naming the offending field if any parameter is out of range.
  void Validate() const;
  double period_s() const { return 1.0 / rate_hz; }
};

/// Ground truth of the faults active at one epoch.
struct GnssFaultState {
  bool dropout = false;
  bool multipath = false;
  Eigen::Vector2d multipath_offset_m = Eigen::Vector2d::Zero();  ///< east, north
  double canopy_cover = 0.0;
};

struct GnssSample {
  double time_s = 0.0;
  bool has_fix = false;                               ///< false during a dropout
  formats::GnssFixQuality fix = formats::GnssFixQuality::kNone;
  Eigen::Vector3d position_m = Eigen::Vector3d::Zero();  ///< ENU; undefined (zero) without fix
  double sigma_horizontal_m = 0.0;                    ///< noise sigma actually used (canopy law)
  double sigma_vertical_m = 0.0;
  GnssFaultState faults;                              ///< truth, not seen by a real receiver
};

/// Transition probabilities of a two-state chain with onset rate a and recovery rate b over dt.
struct MarkovStep {
  double p_onset = 0.0;     ///< P(ok -> fault)
  double p_recovery = 0.0;  ///< P(fault -> ok)
};
MarkovStep ExactMarkovStep(double onset_rate_per_s, double recovery_rate_per_s, double dt_s);

class GnssModel {
 public:
  /// Throws std::invalid_argument if the configuration is invalid.
  GnssModel(const GnssConfig& config, std::uint64_t seed);

  /// One epoch. time_s must be finite and strictly greater than the previous call's; the
  /// position finite; canopy_cover in [0, 1]. Otherwise std::invalid_argument.
  GnssSample Measure(double time_s, const Eigen::Vector3d& true_position_m, double canopy_cover);

  const GnssConfig& config() const { return config_; }

 private:
  void AdvanceFaults(double dt_s, double canopy_cover);

  GnssConfig config_;
  std::mt19937_64 rng_;
  bool has_previous_time_ = false;
  double previous_time_s_ = 0.0;
  bool dropout_ = false;
  bool multipath_ = false;
  Eigen::Vector2d multipath_offset_m_ = Eigen::Vector2d::Zero();
};

}  // namespace rowloc::sim
