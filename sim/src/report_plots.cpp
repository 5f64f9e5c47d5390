// Plot data files and the gnuplot script of an evaluation (see report_plots.hpp).
#include "rowloc/sim/report_plots.hpp"

#include "rowloc/mapio/output_file.hpp"

#include <Eigen/Cholesky>

#include <algorithm>
#include <cctype>
#include <cmath>
#include <cstdio>
#include <fstream>
#include <limits>
#include <numbers>
#include <sstream>
#include <stdexcept>

namespace rowloc::sim {
namespace {

constexpr double kDegPerRad = 180.0 / std::numbers::pi;
constexpr int kEllipsePoints = 48;

/// Shortest round-trip representation of a double ("?" for a missing value).
std::string Val(double v) {
  char buffer[32];
  std::snprintf(buffer, sizeof buffer, "%.17g", v);
  return buffer;
}
std::string Val(const std::optional<double>& v, double scale = 1.0) { return v ? Val(*v * scale) : "?"; }

/// Checked and atomic (mapio::OutputFile: never over an input, a device or a directory).
void WriteText(const std::filesystem::path& path, const std::string& text) { mapio::WriteFileAtomically(path, text); }

/// A gnuplot single-quoted string literal: a quote is doubled inside single quotes, and control
/// characters (a newline would end the command and start another) become spaces.
std::string Quote(const std::string& s) {
  std::string out = "'";
  for (char c : s) {
    if (c == '\'') {
      out += "''";
    } else {
      out += std::iscntrl(static_cast<unsigned char>(c)) ? ' ' : c;
    }
  }
  return out + "'";
}

/// File-name-safe form of a sensor name.
std::string Sanitize(const std::string& s) {
  std::string out;
  for (char c : s) out += (std::isalnum(static_cast<unsigned char>(c)) || c == '-' || c == '_') ? c : '_';
  return out.substr(0, 40);
}

class PlotWriter {
 public:
  PlotWriter(std::filesystem::path dir, PlotFiles& files) : dir_(std::move(dir)), files_(files) {}
  void Data(const std::string& name, const std::string& text) {
    WriteText(dir_ / name, text);
    files_.data_files.push_back(name);
  }

 private:
  std::filesystem::path dir_;
  PlotFiles& files_;
};

std::string RowsData(const geometry::RowMap& map) {
  std::ostringstream out;
  out << "# x_m y_m; one block per row\n";
  for (const geometry::Row& row : map.rows) {
    for (const auto& p : row.points_m) out << Val(p.x()) << ' ' << Val(p.y()) << '\n';
    if (row.closed && !row.points_m.empty()) out << Val(row.points_m.front().x()) << ' ' << Val(row.points_m.front().y()) << '\n';
    out << '\n';
  }
  return out.str();
}

std::string TruthData(const formats::TruthStream& truth, double t0, double t1) {
  std::ostringstream out;
  out << "# t_s x_m y_m phi_rad (truth over the estimates' span)\n";
  for (const formats::TruthSample& s : truth.samples) {
    if (s.t_s < t0 || s.t_s > t1) continue;
    out << Val(s.t_s) << ' ' << Val(s.position_m.x()) << ' ' << Val(s.position_m.y()) << ' ' << Val(s.phi_rad) << '\n';
  }
  return out.str();
}

std::string EstimateData(const formats::EstimateStream& est) {
  std::ostringstream out;
  out << "# t_s x_m y_m phi_rad\n";
  for (const formats::EstimateSample& s : est.estimates) {
    out << Val(s.t_s) << ' ' << Val(s.position_m.x()) << ' ' << Val(s.position_m.y()) << ' ' << Val(s.phi_rad) << '\n';
  }
  return out.str();
}

/// k-sigma ellipses of the position covariance, one block each; count returned through `count`.
std::string EllipseData(const formats::EstimateStream& est, const PlotOptions& o, std::size_t& count) {
  std::ostringstream out;
  out << "# x_m y_m: " << Val(o.k_sigma) << "-sigma position ellipses, one block each\n";
  std::optional<double> next_t;
  count = 0;
  for (const formats::EstimateSample& s : est.estimates) {
    if (!s.covariance || (next_t && s.t_s < *next_t)) continue;
    const Eigen::LLT<Eigen::Matrix2d> llt(s.covariance->topLeftCorner<2, 2>());
    if (llt.info() != Eigen::Success) continue;  // singular: no ellipse
    next_t = s.t_s + o.ellipse_interval_s;
    const Eigen::Matrix2d l = llt.matrixL();
    for (int i = 0; i <= kEllipsePoints; ++i) {
      const double a = 2.0 * std::numbers::pi * i / kEllipsePoints;
      const Eigen::Vector2d p = s.position_m + o.k_sigma * l * Eigen::Vector2d(std::cos(a), std::sin(a));
      out << Val(p.x()) << ' ' << Val(p.y()) << '\n';
    }
    out << '\n';
    ++count;
  }
  return out.str();
}

std::string ErrorData(const std::vector<PoseError>& errors) {
  std::ostringstream out;
  out << "# t_s along_m across_m heading_deg total_m sigma_along_m sigma_across_m sigma_heading_deg nees\n";
  for (const PoseError& e : errors) {
    out << Val(e.t_s) << ' ' << Val(e.along_m) << ' ' << Val(e.across_m) << ' ' << Val(e.heading_rad, kDegPerRad)
        << ' ' << Val(e.total_m) << ' ' << Val(e.sigma_along_m) << ' ' << Val(e.sigma_across_m) << ' '
        << Val(e.sigma_heading_rad, kDegPerRad) << ' ' << Val(e.nees) << '\n';
  }
  return out.str();
}

std::string Histogram(const std::vector<double>& values, int bins) {
  std::ostringstream out;
  out << "# bin_centre count\n";
  if (values.empty()) return out.str();
  const auto [lo_it, hi_it] = std::minmax_element(values.begin(), values.end());
  double lo = *lo_it;
  double hi = *hi_it;
  if (hi - lo <= 0.0) {
    lo -= 0.5;
    hi += 0.5;
  }
  const double width = (hi - lo) / bins;
  std::vector<std::size_t> counts(static_cast<std::size_t>(bins), 0);
  for (double v : values) {
    const auto b = std::min(static_cast<std::size_t>((v - lo) / width), counts.size() - 1);
    ++counts[b];
  }
  for (std::size_t b = 0; b < counts.size(); ++b) {
    out << Val(lo + (static_cast<double>(b) + 0.5) * width) << ' ' << counts[b] << '\n';
  }
  return out.str();
}

/// t value lower upper (per-sample 95 % interval).
std::string ConsistencyData(const std::vector<double>& t, const std::vector<double>& v, const std::vector<int>& dof,
                            double probability) {
  std::ostringstream out;
  out << "# t_s value per_sample_lower per_sample_upper\n";
  for (std::size_t k = 0; k < t.size(); ++k) {
    const ChiSquareBand b = ChiSquareInterval(dof[k], probability);
    out << Val(t[k]) << ' ' << Val(v[k]) << ' ' << Val(b.lower) << ' ' << Val(b.upper) << '\n';
  }
  return out.str();
}

std::string ScriptHeader() {
  return "# Generated by rowloc evaluate; run `gnuplot plots.gp` in this directory.\n"
         "set datafile missing '?'\nset grid\nset key outside bottom center horizontal noenhanced\n";
}

std::string Terminal(const std::string& svg, int width, int height) {
  return "set terminal svg size " + std::to_string(width) + "," + std::to_string(height) +
         " dynamic noenhanced font 'sans,11'\nset output " + Quote(svg) + "\n";
}

/// Plot ranges around the estimates (and the rows): equal axes, each span at least a quarter of
/// the other plus 1 m, so that a straight run does not give gnuplot an extreme aspect ratio.
std::string TrajectoryRanges(const formats::EstimateStream& est, const std::optional<geometry::RowMap>& map) {
  Eigen::Vector2d lo = Eigen::Vector2d::Constant(std::numeric_limits<double>::infinity());
  Eigen::Vector2d hi = -lo;
  for (const formats::EstimateSample& s : est.estimates) {
    lo = lo.cwiseMin(s.position_m);
    hi = hi.cwiseMax(s.position_m);
  }
  if (map) {
    for (const geometry::Row& row : map->rows) {
      for (const auto& p : row.points_m) {
        lo = lo.cwiseMin(p);
        hi = hi.cwiseMax(p);
      }
    }
  }
  const Eigen::Vector2d centre = 0.5 * (lo + hi);
  const double span = (hi - lo).maxCoeff();
  const Eigen::Vector2d half = 0.5 * (hi - lo).cwiseMax(0.25 * span + 1.0) * 1.05;
  return "set xrange [" + Val(centre.x() - half.x()) + ":" + Val(centre.x() + half.x()) + "]\nset yrange [" +
         Val(centre.y() - half.y()) + ":" + Val(centre.y() + half.y()) + "]\n";
}

std::string TrajectoryScript(bool has_map, bool has_ellipses, const std::string& ranges, const PlotOptions& o) {
  std::string s = Terminal("trajectory.svg", 1000, 900) +
                  "set title 'Trajectory (truth, estimate, " + Val(o.k_sigma) + "-sigma ellipses)'\n"
                  "set xlabel 'east [m]'\nset ylabel 'north [m]'\nset size ratio -1\n" + ranges + "plot ";
  if (has_map) s += "'rows.dat' using 1:2 with lines lc rgb '#2e8b57' lw 2 title 'rows', ";
  s += "'truth.dat' using 2:3 with lines lc rgb 'black' lw 1.5 title 'truth', "
       "'estimate.dat' using 2:3 with lines lc rgb '#d62728' lw 1 title 'estimate'";
  if (has_ellipses) s += ", 'ellipses.dat' using 1:2 with lines lc rgb '#1f77b4' title 'ellipses'";
  return s + "\nset size noratio\nset autoscale xy\n";
}

std::string ErrorPanel(const std::string& title, const std::string& ylabel, int value_col, int sigma_col,
                       const PlotOptions& o) {
  const std::string k = Val(o.k_sigma);
  return "set title " + Quote(title) + "\nset ylabel " + Quote(ylabel) +
         "\nplot 'errors.dat' using 1:" + std::to_string(value_col) + " with lines lc rgb '#d62728' title 'error', "
         "'' using 1:(" + k + "*$" + std::to_string(sigma_col) + ") with lines dt 2 lc rgb '#1f77b4' title '+" + k +
         " sigma', '' using 1:(-" + k + "*$" + std::to_string(sigma_col) +
         ") with lines dt 2 lc rgb '#1f77b4' title '-" + k + " sigma'\n";
}

std::string ErrorsScript(bool has_heading, const PlotOptions& o) {
  const int panels = has_heading ? 3 : 2;
  std::string s = Terminal("errors.svg", 1000, 300 * panels) + "set multiplot layout " + std::to_string(panels) +
                  ",1\nset xlabel 'time [s]'\n";
  s += ErrorPanel("across-row error (left positive)", "across [m]", 3, 7, o);
  s += ErrorPanel("along-row error", "along [m]", 2, 6, o);
  if (has_heading) s += ErrorPanel("heading error", "heading [deg]", 4, 8, o);
  return s + "unset multiplot\n";
}

std::string HistogramsScript(bool has_heading) {
  const int panels = has_heading ? 3 : 2;
  std::string s = Terminal("histograms.svg", 400 * panels, 400) + "set multiplot layout 1," + std::to_string(panels) +
                  "\nset style fill solid 0.5\nset ylabel 'count'\nset key off\n";
  s += "set title 'across error'\nset xlabel 'across [m]'\nplot 'hist_across.dat' using 1:2 with boxes\n";
  s += "set title 'along error'\nset xlabel 'along [m]'\nplot 'hist_along.dat' using 1:2 with boxes\n";
  if (has_heading) s += "set title 'heading error'\nset xlabel 'heading [deg]'\nplot 'hist_heading.dat' using 1:2 with boxes\n";
  return s + "unset multiplot\nset key outside bottom center horizontal noenhanced\n";
}

std::string ConsistencyPanel(const std::string& title, const std::string& data, const ConsistencySummary& c) {
  return "set title " + Quote(title) + "\nplot " + Quote(data) +
         " using 1:2 with points pt 7 ps 0.6 lc rgb '#d62728' title 'value', '' using 1:3 with lines dt 2 lc rgb "
         "'#1f77b4' title 'per-sample 95 %', '' using 1:4 with lines dt 2 lc rgb '#1f77b4' notitle, " +
         Val(c.band.lower) + " with lines lc rgb 'black' title 'band of the mean', " + Val(c.band.upper) +
         " with lines lc rgb 'black' notitle, " + Val(c.mean) + " with lines lc rgb '#2ca02c' title 'mean'\n";
}

}  // namespace

void PlotOptions::Validate() const {
  if (!(ellipse_interval_s > 0.0) || !std::isfinite(ellipse_interval_s)) {
    throw std::invalid_argument("plot ellipse_interval_s must be positive and finite");
  }
  if (!(k_sigma > 0.0) || !std::isfinite(k_sigma)) throw std::invalid_argument("plot k_sigma must be positive and finite");
  if (histogram_bins < 1) throw std::invalid_argument("plot histogram_bins must be >= 1");
}

PlotFiles WritePlotFiles(const EvaluationResult& result, const formats::TruthStream& truth,
                         const formats::EstimateStream& estimates, const std::optional<geometry::RowMap>& map,
                         const std::filesystem::path& directory,
                         const PlotOptions& options) {
  options.Validate();
  std::error_code ec;
  std::filesystem::create_directories(directory, ec);
  if (ec) throw std::runtime_error(directory.string() + ": cannot create directory: " + ec.message());
  PlotFiles files;
  files.directory = directory;
  files.script = "plots.gp";
  PlotWriter w(directory, files);
  if (map) w.Data("rows.dat", RowsData(*map));
  w.Data("truth.dat", TruthData(truth, result.start_s, result.end_s));
  w.Data("estimate.dat", EstimateData(estimates));
  std::size_t ellipse_count = 0;
  w.Data("ellipses.dat", EllipseData(estimates, options, ellipse_count));
  w.Data("errors.dat", ErrorData(result.pose_errors));
  std::vector<double> along, across, heading;
  for (const PoseError& e : result.pose_errors) {
    along.push_back(e.along_m);
    across.push_back(e.across_m);
    if (e.heading_rad) heading.push_back(*e.heading_rad * kDegPerRad);
  }
  w.Data("hist_across.dat", Histogram(across, options.histogram_bins));
  w.Data("hist_along.dat", Histogram(along, options.histogram_bins));
  const bool has_heading = !heading.empty();
  if (has_heading) w.Data("hist_heading.dat", Histogram(heading, options.histogram_bins));

  std::string script = ScriptHeader() + TrajectoryScript(map.has_value(), ellipse_count > 0, TrajectoryRanges(estimates, map), options) +
                       ErrorsScript(has_heading, options) + HistogramsScript(has_heading);
  files.svg_files = {"trajectory.svg", "errors.svg", "histograms.svg"};
  std::string panels;
  int panel_count = 0;
  if (result.nees.count > 0) {
    std::vector<double> t, v;
    std::vector<int> dof;
    for (const PoseError& e : result.pose_errors) {
      if (!e.nees) continue;
      t.push_back(e.t_s);
      v.push_back(*e.nees);
      dof.push_back(e.nees_dof);
    }
    w.Data("nees.dat", ConsistencyData(t, v, dof, result.options.probability));
    panels += ConsistencyPanel("NEES", "nees.dat", result.nees);
    ++panel_count;
  }
  for (std::size_t i = 0; i < result.innovations.size(); ++i) {
    const SensorInnovationResult& s = result.innovations[i];
    const std::string name = "nis_" + std::to_string(i) + "_" + Sanitize(s.sensor) + ".dat";
    w.Data(name, ConsistencyData(s.times_s, s.nis_values, s.dofs, result.options.probability));
    panels += ConsistencyPanel("NIS " + s.sensor + " (band: accepted updates)", name, s.nis);
    ++panel_count;
  }
  if (panel_count > 0) {
    script += Terminal("consistency.svg", 1000, 300 * panel_count) + "set multiplot layout " +
              std::to_string(panel_count) + ",1\nset xlabel 'time [s]'\nset ylabel 'chi-square statistic'\n" + panels +
              "unset multiplot\n";
    files.svg_files.push_back("consistency.svg");
  }
  script += "unset output\n";
  WriteText(directory / files.script, script);
  return files;
}

}  // namespace rowloc::sim
