// libFuzzer target over the vehicle configuration reader (mapio/vehicle_config.hpp; docs/building.md,
// "Fuzzing"): the input is the text of a vehicle file, given to ParseVehicleConfig. It may throw
// VehicleConfigError only; a configuration it returns must pass VehicleConfigProblem and keep its
// values in their documented domains (VehicleConfigLimits). Anything else is a finding.
#include "rowloc/mapio/vehicle_config.hpp"

#include <cmath>
#include <cstdint>
#include <cstdlib>
#include <string_view>

namespace {

using Limits = rowloc::mapio::VehicleConfigLimits;

bool InDomain(const rowloc::mapio::VehicleConfig& config) {
  if (!(config.mass_kg >= Limits::kMinMassKg && config.mass_kg <= Limits::kMaxMassKg)) return false;
  if (config.wheels.empty() || config.wheels.size() > Limits::kMaxWheels) return false;
  for (const auto& wheel : config.wheels) {
    if (!(wheel.nominal_radius_m >= Limits::kMinWheelRadiusM && wheel.nominal_radius_m <= Limits::kMaxWheelRadiusM)) {
      return false;
    }
    if (!(wheel.position_m.cwiseAbs().maxCoeff() <= Limits::kMaxAbsPositionM)) return false;
  }
  return config.ultrasonic.size() <= Limits::kMaxUltrasonicSensors;
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  const std::string_view input(reinterpret_cast<const char*>(data), size);
  try {
    const rowloc::mapio::VehicleConfig config = rowloc::mapio::ParseVehicleConfig(input, "fuzz");
    if (rowloc::mapio::VehicleConfigProblem(config) || !InDomain(config)) std::abort();
  } catch (const rowloc::mapio::VehicleConfigError&) {
  }
  return 0;
}
