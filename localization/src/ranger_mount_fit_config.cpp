// The ranger mount fit's configuration checks (ranger_mount_fit.hpp).
#include "rowloc/localization/ranger_mount_fit.hpp"

#include <cmath>
#include <string>

namespace rowloc::localization {

void ValidateRangerMountFitConfig(const RangerMountFitConfig& c) {
  const std::pair<const char*, double> positive[] = {
      {"association_gate_m", c.association_gate_m},
      {"refined_gate_m", c.refined_gate_m},
      {"range_sigma_m", c.range_sigma_m},
      {"huber_sigmas", c.huber_sigmas},
      {"position_walk_mps_per_sqrt_s", c.position_walk_mps_per_sqrt_s},
      {"heading_walk_rad_per_sqrt_s", c.heading_walk_rad_per_sqrt_s},
      {"position_anchor_sigma_m", c.position_anchor_sigma_m},
      {"heading_anchor_sigma_rad", c.heading_anchor_sigma_rad},
      {"mount_prior_scale_m", c.mount_prior_scale_m},
      {"max_knot_gap_s", c.max_knot_gap_s}};
  for (const auto& [name, value] : positive) {
    if (!(value > 0.0 && std::isfinite(value))) {
      throw RangerMountFitError(std::string(name) + " must be positive and finite");
    }
  }
  if (c.refined_gate_m > c.association_gate_m) {
    throw RangerMountFitError("refined_gate_m must not exceed association_gate_m");
  }
  if (c.outer_iterations < 1 || c.outer_iterations > 20) {
    throw RangerMountFitError("outer_iterations must be from 1 to 20");
  }
  if (!(c.min_associated_fraction >= 0.0 && c.min_associated_fraction <= 1.0)) {
    throw RangerMountFitError("min_associated_fraction must be from 0 to 1");
  }
  if (c.max_solver_iterations < 1) throw RangerMountFitError("max_solver_iterations must be at least 1");
  if (c.min_echoes_per_ranger < 1) throw RangerMountFitError("min_echoes_per_ranger must be at least 1");
}

}  // namespace rowloc::localization
