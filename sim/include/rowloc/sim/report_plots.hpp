// Plots of an evaluation (issue 3, "Metrics and reports"), drawn by gnuplot (Debian package
// gnuplot-nox, installed by scripts/setup) as SVG files.
//
// WritePlotFiles writes whitespace-separated data files (*.dat; '?' marks a missing value,
// blank lines separate polylines) and one script plots.gp into the plot directory; the script
// uses file names relative to that directory, so RunGnuplot runs `gnuplot plots.gp` there
// (fork + chdir + execvp: no shell, so no quoting of user paths is involved). It draws:
//  1. trajectory.svg: row map polylines (if any), truth, estimate and k-sigma position ellipses
//     every ellipse_interval_s seconds, equal axes. Ellipse of N(c, S_xy) at k sigma: the points
//     c + k L [cos a, sin a]' with S_xy = L L' (shape matrix P = k^2 S), k = 2 by default.
//  2. errors.svg: across, along and heading error vs time with the +-k sigma envelope from the
//     estimate's covariance (sigma_across, sigma_along, sigma_heading of metrics.hpp).
//  3. histograms.svg: histograms of the across, along and heading errors.
//  4. consistency.svg: NEES and each sensor's NIS vs time with the per-sample 95 % chi-square
//     interval and the band of the time average (only when there is a NEES or an update).
#pragma once

#include "rowloc/formats/trajectory_streams.hpp"
#include "rowloc/geometry/row_map.hpp"
#include "rowloc/sim/metrics.hpp"

#include <filesystem>
#include <optional>
#include <string>
#include <vector>

namespace rowloc::sim {

struct PlotOptions {
  double ellipse_interval_s = 1.0;  ///< one ellipse per this many seconds of estimates (> 0)
  double k_sigma = 2.0;             ///< ellipse and envelope scale k (> 0)
  int histogram_bins = 30;          ///< >= 1
  /// Throws std::invalid_argument naming the field when out of range.
  void Validate() const;
};

/// What WritePlotFiles wrote (file names relative to `directory`).
struct PlotFiles {
  std::filesystem::path directory;
  std::string script;                  ///< "plots.gp"
  std::vector<std::string> data_files;
  std::vector<std::string> svg_files;  ///< what the script will produce
};

/// Writes the data files and the script; creates the directory. Throws std::runtime_error
/// naming a file that cannot be written.
PlotFiles WritePlotFiles(const EvaluationResult& result, const formats::TruthStream& truth,
                         const formats::EstimateStream& estimates, const std::optional<geometry::RowMap>& map,
                         const std::filesystem::path& directory,
                         const PlotOptions& options = {});

/// First executable `name` on $PATH, if any.
std::optional<std::filesystem::path> FindExecutableOnPath(const std::string& name);

struct GnuplotRun {
  bool ran = false;       ///< gnuplot was found and started
  int exit_code = -1;     ///< its exit status (0: success)
  std::string message;    ///< human-readable outcome
};

/// Runs `gnuplot <script>` with the working directory set to `files.directory`.
GnuplotRun RunGnuplot(const PlotFiles& files);

}  // namespace rowloc::sim
