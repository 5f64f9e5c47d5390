// The evaluation report of `rowloc evaluate` (issue 3, "Metrics and reports"): aligned text
// tables for a person and JSON (nlohmann-json) with every summary number for programs.
//
// Units: the text shows metres, degrees for headings and percentages for fractions; the JSON
// keeps SI units named in the keys (`_m`, `_rad`, `_s`) and fractions in [0, 1]. Per-sample
// series are not in the report (they are in the plot data files, report_plots.hpp); the whiteness
// autocorrelation rho(1..L) is. Metric definitions: metrics.hpp and docs/validation.md.
#pragma once

#include "rowloc/sim/metrics.hpp"

#include <filesystem>
#include <string>

namespace rowloc::sim {

/// What the report says about its inputs.
struct ReportInputs {
  std::string truth_path;
  std::string estimates_path;
  std::string map_path;  ///< empty without --map
  std::size_t update_count = 0;
  std::size_t skipped_truth_lines = 0;     ///< lines of an unknown type
  std::size_t skipped_estimate_lines = 0;
};

/// Human-readable report: header lines and aligned tables, '\n'-terminated.
std::string FormatReportText(const EvaluationResult& result, const ReportInputs& inputs);

/// Machine-readable report (pretty JSON with 2-space indent, '\n'-terminated). Schema
/// "rowloc-evaluation/1"; see docs/validation.md.
std::string FormatReportJson(const EvaluationResult& result, const ReportInputs& inputs);

/// Writes report.txt and report.json into dir (created if missing). Throws std::runtime_error
/// naming the file when it cannot be written.
void WriteReport(const EvaluationResult& result, const ReportInputs& inputs, const std::filesystem::path& dir);

}  // namespace rowloc::sim
