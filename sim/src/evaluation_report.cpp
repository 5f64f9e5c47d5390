// Text and JSON evaluation reports (see evaluation_report.hpp).
#include "rowloc/sim/evaluation_report.hpp"

#include "rowloc/mapio/output_file.hpp"

#include <nlohmann/json.hpp>

#include <algorithm>
#include <cstdio>
#include <fstream>
#include <numbers>
#include <sstream>
#include <stdexcept>
#include <vector>

namespace rowloc::sim {
namespace {

using nlohmann::json;
constexpr double kDegPerRad = 180.0 / std::numbers::pi;

std::string Num(double v, int precision) {
  char buffer[64];
  std::snprintf(buffer, sizeof buffer, "%.*f", precision, v);
  return buffer;
}
std::string Percent(double fraction) { return Num(100.0 * fraction, 1) + " %"; }
std::string Band(const ChiSquareBand& b, int precision) {
  std::string out = "[";
  out += Num(b.lower, precision);
  out += ", ";
  out += Num(b.upper, precision);
  out += "]";
  return out;
}

/// The batch-means columns of a consistency summary: interval, whether it holds the expected
/// value, correlation time and effective samples (batch_means.hpp), after the row's name.
std::vector<std::string> CorrelatedRow(const std::string& name, const ConsistencySummary& c) {
  if (!c.batch_means) {
    return {name, "run too short", "-", Num(c.correlation_time_samples, 1), Num(c.effective_sample_count, 0)};
  }
  return {name, Band(ChiSquareBand{c.batch_means->lower, c.batch_means->upper}, 3), c.expected_inside ? "yes" : "NO",
          Num(c.correlation_time_samples, 1), Num(c.effective_sample_count, 0)};
}
std::vector<std::string> CorrelatedHeader(const std::string& name) {
  return {name, "batch-means 95 % interval", "holds dof", "corr. time [samples]", "effective samples"};
}

/// A table with a left-aligned first column and right-aligned others.
class TextTable {
 public:
  explicit TextTable(std::vector<std::string> header) { rows_.push_back(std::move(header)); }
  void Add(std::vector<std::string> row) { rows_.push_back(std::move(row)); }
  std::string Format(const std::string& indent = "  ") const {
    std::vector<std::size_t> width;
    for (const auto& row : rows_) {
      width.resize(std::max(width.size(), row.size()), 0);
      for (std::size_t c = 0; c < row.size(); ++c) width[c] = std::max(width[c], row[c].size());
    }
    std::ostringstream out;
    for (const auto& row : rows_) {
      std::string line = indent;
      for (std::size_t c = 0; c < row.size(); ++c) {
        const std::string pad(width[c] - row[c].size(), ' ');
        line += c == 0 ? row[c] + pad : "  " + pad + row[c];
      }
      while (!line.empty() && line.back() == ' ') line.pop_back();
      out << line << '\n';
    }
    return out.str();
  }

 private:
  std::vector<std::vector<std::string>> rows_;
};

std::vector<std::string> StatsRow(const std::string& name, const ErrorStatistics& s, double scale, int precision) {
  return {name, std::to_string(s.count), Num(s.mean * scale, precision), Num(s.std * scale, precision),
          Num(s.rms * scale, precision), Num(s.max_abs * scale, precision)};
}

std::string ReferenceText(const EvaluationResult& r, const ReportInputs& in) {
  return r.reference == AlongAcrossReference::kRowDirection
             ? "row direction (nearest row segment of " + in.map_path + ")"
             : "true heading (no row map given)";
}

std::string PositionSection(const EvaluationResult& r) {
  const PositionSummary& p = r.position;
  TextTable t({"error", "count", "mean", "std", "rms", "max"});
  t.Add(StatsRow("position, total [m]", p.total_m, 1.0, 4));
  t.Add(StatsRow("along (signed) [m]", p.along_m, 1.0, 4));
  t.Add(StatsRow("across |.| [m]", p.across_abs_m, 1.0, 4));
  t.Add({"across, signed mean [m]", "", Num(p.across_signed_mean_m, 4)});
  if (p.heading_rad.count > 0) t.Add(StatsRow("heading (signed) [deg]", p.heading_rad, kDegPerRad, 3));
  std::string out = "Pose error (estimate - truth; across: left of the reference positive)\n" + t.Format();
  if (p.heading_rad.count == 0) out += "  heading: not reported (no estimate has phi_rad)\n";
  return out;
}

std::string NeesSection(const EvaluationResult& r) {
  const ConsistencySummary& n = r.nees;
  const std::string singular =
      r.singular_covariance_count == 0
          ? ""
          : "  " + std::to_string(r.singular_covariance_count) + " estimates have a singular covariance: no NEES\n";
  if (n.count == 0) return "NEES: not reported (no estimate has a non-singular covariance_xy_phi)\n" + singular;
  const double dof = n.total_dof / static_cast<double>(n.count);
  TextTable t({"NEES", "samples", "dof/sample", "mean", "95 % band of mean", "mean inside",
               "samples inside 95 %"});
  t.Add({"position+heading", std::to_string(n.count), Num(dof, 2), Num(n.mean, 3), Band(n.band, 3),
         n.mean_inside ? "yes" : "NO", Percent(n.fraction_inside)});
  TextTable correlated(CorrelatedHeader("NEES"));
  correlated.Add(CorrelatedRow("position+heading", n));
  return "Normalized estimation error squared (chi-square test)\n" + t.Format() + singular +
         "The band of the mean assumes independent samples; with correlated ones (batch means: up to 20\n"
         "batches of >= 4 correlation times; \"run too short\": fewer than 5 such batches):\n" +
         correlated.Format();
}

std::string NisSection(const EvaluationResult& r) {
  if (r.innovations.empty()) return "NIS: not reported (no update lines)\n";
  TextTable t({"sensor", "updates", "gated out", "mean NIS", "95 % band of mean", "inside", "samples inside",
               "nis mismatches", "white lags", "K", "+-band"});
  for (const SensorInnovationResult& s : r.innovations) {
    const bool has_nis = s.nis.count > 0;
    const bool white = s.whiteness.not_computed.empty();
    t.Add({s.sensor, std::to_string(s.update_count), Percent(s.gated_out_fraction),
           has_nis ? Num(s.nis.mean, 3) : "-", has_nis ? Band(s.nis.band, 3) : "-",
           has_nis ? (s.nis.mean_inside ? "yes" : "NO") : "-", has_nis ? Percent(s.nis.fraction_inside) : "-",
           std::to_string(s.nis_mismatch_count), white ? Percent(s.whiteness.fraction_inside) : "-",
           std::to_string(s.whiteness.sample_count), white ? Num(s.whiteness.band_half_width, 4) : "-"});
  }
  TextTable correlated(CorrelatedHeader("sensor"));
  for (const SensorInnovationResult& s : r.innovations) {
    if (s.nis.count > 0) correlated.Add(CorrelatedRow(s.sensor, s.nis));
  }
  std::string out =
      "Innovations per sensor (accepted updates; whiteness: lags 1.." + std::to_string(r.options.max_lag) +
      " inside +-1.96/sqrt(K m), Lindgren et al. 2002, Eq. 42)\n" + t.Format() +
      "Mean NIS with correlated samples (batch means: up to 20 batches of >= 4 correlation times):\n" + correlated.Format();
  for (const SensorInnovationResult& s : r.innovations) {
    if (!s.whiteness.not_computed.empty()) out += "  " + s.sensor + ": whiteness not computed: " + s.whiteness.not_computed + "\n";
    if (s.nis_mismatch_count > 0) {
      out += "  WARNING " + s.sensor + ": " + std::to_string(s.nis_mismatch_count) +
             " recorded nis differ from v' S^-1 v (max relative difference " + Num(s.max_nis_relative_difference, 9) + ")\n";
    }
  }
  return out;
}

std::string DriftSection(const EvaluationResult& r) {
  if (r.drift.empty()) {
    return "Drift after loss of absolute fixes: no GNSS outage of >= " + Num(r.options.drift_min_duration_s, 1) +
           " s in the truth\n";
  }
  TextTable t({"outage", "start [s]", "end [s]", "fixes back", "estimates", "error start [m]", "error end [m]",
               "growth [m]", "max [m]"});
  for (std::size_t i = 0; i < r.drift.size(); ++i) {
    const DriftInterval& d = r.drift[i];
    t.Add({std::to_string(i + 1), Num(d.start_s, 2), Num(d.end_s, 2), d.fixes_returned ? "yes" : "no (end of run)",
           std::to_string(d.estimate_count), Num(d.error_start_m, 4), Num(d.error_end_m, 4), Num(d.growth_m, 4),
           Num(d.max_error_m, 4)});
  }
  return "Drift after loss of absolute fixes (truth gnss_available = false for >= " +
         Num(r.options.drift_min_duration_s, 1) + " s)\n" + t.Format();
}

std::string SlipSection(const EvaluationResult& r) {
  if (r.slip.empty()) return "Slip error: not reported (no wheel has a slip in both streams)\n";
  TextTable t({"wheel", "count", "mean", "std", "rms", "max"});
  for (const WheelSlipError& w : r.slip) t.Add(StatsRow(w.wheel, w.error, 1.0, 5));
  return "Slip error per wheel (estimate - truth, SAE slip)\n" + t.Format();
}

std::string RollingRadiusSection(const EvaluationResult& r) {
  if (r.rolling_radius.empty()) {
    return "Rolling radius: not reported (no wheel has a wheel_calibration and a truth rolling_radius_m)\n";
  }
  TextTable t({"wheel", "count", "mean [mm]", "std [mm]", "rms [mm]", "max [mm]", "mean NEES", "95 % band of mean",
               "inside", "final R_w +- sigma [m]", "truth [m]"});
  for (const RollingRadiusError& w : r.rolling_radius) {
    std::vector<std::string> row = StatsRow(w.wheel, w.error_m, 1000.0, 2);
    const bool has_nees = w.nees.count > 0;
    row.push_back(has_nees ? Num(w.nees.mean, 3) : "-");
    row.push_back(has_nees ? Band(w.nees.band, 3) : "-");
    row.push_back(has_nees ? (w.nees.mean_inside ? "yes" : "NO") : "-");
    row.push_back(Num(w.final_estimate_m, 5) + " +- " + Num(w.final_sigma_m, 5));
    row.push_back(Num(w.final_truth_m, 5));
    t.Add(std::move(row));
  }
  TextTable correlated(CorrelatedHeader("wheel"));
  for (const RollingRadiusError& w : r.rolling_radius) {
    if (w.nees.count > 0) correlated.Add(CorrelatedRow(w.wheel, w.nees));
  }
  std::string out = "Rolling radius per wheel (slip-aware odometry R_w - truth; NEES (R_w - R_a)^2 / sigma^2, 1 dof)\n" +
                    t.Format() + "Mean NEES with correlated samples (batch means):\n" + correlated.Format();
  for (const RollingRadiusError& w : r.rolling_radius) {
    if (w.zero_sigma_count > 0) {
      out += "  " + w.wheel + ": " + std::to_string(w.zero_sigma_count) + " estimates with sigma 0: no NEES\n";
    }
  }
  return out;
}

json StatsJson(const ErrorStatistics& s) {
  return {{"count", s.count}, {"mean", s.mean}, {"std", s.std}, {"rms", s.rms}, {"max_abs", s.max_abs}};
}

json ConsistencyJson(const ConsistencySummary& c) {
  json out = {{"count", c.count},         {"total_dof", c.total_dof},       {"mean", c.mean},
              {"band_lower", c.band.lower}, {"band_upper", c.band.upper},   {"mean_inside", c.mean_inside},
              {"fraction_inside", c.fraction_inside}, {"probability", c.probability},
              {"correlation_time_samples", c.correlation_time_samples},
              {"effective_sample_count", c.effective_sample_count}};
  if (c.batch_means) {
    const BatchMeansInterval& b = *c.batch_means;
    out["batch_means"] = {{"batches", b.batch_count},
                          {"batch_length", b.batch_length},
                          {"lower", b.lower},
                          {"upper", b.upper},
                          {"batch_lag1_autocorrelation", b.batch_lag1_autocorrelation},
                          {"expected_inside", c.expected_inside}};
  }
  return out;
}

json InnovationsJson(const std::vector<SensorInnovationResult>& sensors) {
  json out = json::array();
  for (const SensorInnovationResult& s : sensors) {
    json w = {{"sample_count", s.whiteness.sample_count}, {"band_half_width", s.whiteness.band_half_width},
              {"fraction_inside", s.whiteness.fraction_inside}, {"autocorrelation", s.whiteness.autocorrelation}};
    if (!s.whiteness.not_computed.empty()) w["not_computed"] = s.whiteness.not_computed;
    out.push_back({{"sensor", s.sensor}, {"update_count", s.update_count}, {"gated_out_count", s.gated_out_count},
                   {"gated_out_fraction", s.gated_out_fraction}, {"nis_mismatch_count", s.nis_mismatch_count},
                   {"max_nis_relative_difference", s.max_nis_relative_difference},
                   {"nis", ConsistencyJson(s.nis)}, {"whiteness", w}});
  }
  return out;
}

json DriftJson(const std::vector<DriftInterval>& drift) {
  json out = json::array();
  for (const DriftInterval& d : drift) {
    out.push_back({{"start_s", d.start_s}, {"end_s", d.end_s}, {"fixes_returned", d.fixes_returned},
                   {"estimate_count", d.estimate_count}, {"error_start_m", d.error_start_m},
                   {"error_end_m", d.error_end_m}, {"growth_m", d.growth_m}, {"max_error_m", d.max_error_m}});
  }
  return out;
}

/// Checked and atomic (mapio::OutputFile: never over an input, a device or a directory).
void WriteFile(const std::filesystem::path& path, const std::string& text) { mapio::WriteFileAtomically(path, text); }

}  // namespace

std::string FormatReportText(const EvaluationResult& r, const ReportInputs& in) {
  std::ostringstream out;
  out << "rowloc evaluation report\n"
      << "truth:      " << in.truth_path << " (" << r.truth_count << " samples)\n"
      << "estimates:  " << in.estimates_path << " (" << r.estimate_count << " estimates, " << in.update_count
      << " updates)\n"
      << "time span:  " << Num(r.start_s, 3) << " .. " << Num(r.end_s, 3) << " s\n"
      << "along/across reference: " << ReferenceText(r, in) << "\n";
  if (in.skipped_truth_lines + in.skipped_estimate_lines > 0) {
    out << "skipped lines of unknown type: truth " << in.skipped_truth_lines << ", estimates "
        << in.skipped_estimate_lines << "\n";
  }
  out << "\n" << PositionSection(r) << "\n" << NeesSection(r) << "\n" << NisSection(r) << "\n"
      << DriftSection(r) << "\n" << SlipSection(r) << "\n" << RollingRadiusSection(r);
  return out.str();
}

std::string FormatReportJson(const EvaluationResult& r, const ReportInputs& in) {
  json slip = json::array();
  for (const WheelSlipError& w : r.slip) slip.push_back({{"wheel", w.wheel}, {"error", StatsJson(w.error)}});
  json rolling_radius = json::array();
  for (const RollingRadiusError& w : r.rolling_radius) {
    rolling_radius.push_back({{"wheel", w.wheel},
                              {"error_m", StatsJson(w.error_m)},
                              {"nees", ConsistencyJson(w.nees)},
                              {"zero_sigma_count", w.zero_sigma_count},
                              {"final_estimate_m", w.final_estimate_m},
                              {"final_sigma_m", w.final_sigma_m},
                              {"final_truth_m", w.final_truth_m}});
  }
  const PositionSummary& p = r.position;
  json j = {
      {"schema", "rowloc-evaluation/1"},
      {"inputs",
       {{"truth", in.truth_path}, {"estimates", in.estimates_path}, {"map", in.map_path},
        {"truth_samples", r.truth_count}, {"estimates_count", r.estimate_count}, {"updates", in.update_count},
        {"skipped_truth_lines", in.skipped_truth_lines}, {"skipped_estimate_lines", in.skipped_estimate_lines}}},
      {"start_s", r.start_s},
      {"end_s", r.end_s},
      {"reference", r.reference == AlongAcrossReference::kRowDirection ? "row_direction" : "true_heading"},
      {"options",
       {{"max_lag", r.options.max_lag}, {"probability", r.options.probability},
        {"drift_min_duration_s", r.options.drift_min_duration_s}}},
      {"position",
       {{"total_m", StatsJson(p.total_m)}, {"along_m", StatsJson(p.along_m)},
        {"across_abs_m", StatsJson(p.across_abs_m)}, {"across_signed_mean_m", p.across_signed_mean_m},
        {"heading_rad", StatsJson(p.heading_rad)}}},
      {"nees", ConsistencyJson(r.nees)},
      {"nees_singular_covariance_count", r.singular_covariance_count},
      {"innovations", InnovationsJson(r.innovations)},
      {"drift", DriftJson(r.drift)},
      {"slip", slip},
      {"rolling_radius", rolling_radius}};
  return j.dump(2) + "\n";
}

void WriteReport(const EvaluationResult& result, const ReportInputs& inputs, const std::filesystem::path& dir) {
  std::error_code ec;
  std::filesystem::create_directories(dir, ec);
  if (ec) throw std::runtime_error(dir.string() + ": cannot create directory: " + ec.message());
  WriteFile(dir / "report.txt", FormatReportText(result, inputs));
  WriteFile(dir / "report.json", FormatReportJson(result, inputs));
}

}  // namespace rowloc::sim
