// CLI11 validators of numeric options with short messages: CLI::PositiveNumber prints its range
// with std::to_string, 309 digits for the largest double, and lets "nan" through; an integer
// option without a check says only "Could not convert".
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

/// Accepts a whole number in [min, max] (inclusive), written as digits with an optional sign; the
/// message prints both bounds (CLI11's own conversion says only "Could not convert").
inline CLI::Validator IntegerInRange(long long min, long long max, const std::string& name) {
  return CLI::Validator(
      [min, max](std::string& input) -> std::string {
        const std::size_t digits = !input.empty() && (input[0] == '+' || input[0] == '-') ? 1 : 0;
        if (input.size() == digits || input.find_first_not_of("0123456789", digits) != std::string::npos) {
          return fmt::format("'{}' is not a whole number", input);
        }
        long long value = 0;
        if (!CLI::detail::lexical_cast(input, value) || value < min || value > max) {
          return fmt::format("{} is not in [{}, {}]", input, min, max);
        }
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
