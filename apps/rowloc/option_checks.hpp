// CLI11 validators of numeric options with short messages: CLI::PositiveNumber prints its range
// with std::to_string, 309 digits for the largest double, and lets "nan" through.
#pragma once

#include <CLI/CLI.hpp>
#include <fmt/format.h>

#include <cmath>
#include <string>

namespace rowloc::apps {

/// Accepts a finite number in [min, max] (inclusive); the message prints both bounds with %g.
inline CLI::Validator FiniteInRange(double min, double max, const std::string& name) {
  return CLI::Validator(
      [min, max](std::string& input) -> std::string {
        double value = 0.0;
        if (!CLI::detail::lexical_cast(input, value) || !std::isfinite(value)) {
          return fmt::format("'{}' is not a finite number", input);
        }
        if (value < min || value > max) return fmt::format("{} is not in [{:g}, {:g}]", input, min, max);
        return {};
      },
      name);
}

/// Accepts a finite number > 0.
inline CLI::Validator PositiveNumber() {
  return CLI::Validator(
      [](std::string& input) -> std::string {
        double value = 0.0;
        if (!CLI::detail::lexical_cast(input, value) || !std::isfinite(value) || !(value > 0.0)) {
          return fmt::format("'{}' is not a finite number > 0", input);
        }
        return {};
      },
      "POSITIVE");
}

/// Accepts a finite number >= 0.
inline CLI::Validator NonNegativeNumber() {
  return CLI::Validator(
      [](std::string& input) -> std::string {
        double value = 0.0;
        if (!CLI::detail::lexical_cast(input, value) || !std::isfinite(value) || !(value >= 0.0)) {
          return fmt::format("'{}' is not a finite number >= 0", input);
        }
        return {};
      },
      "NONNEGATIVE");
}

}  // namespace rowloc::apps
