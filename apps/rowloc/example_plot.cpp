#include "example_plot.hpp"

#include "rowloc/mapio/output_file.hpp"
#include "rowloc/sim/report_plots.hpp"

#include <fmt/format.h>

#include <cmath>
#include <exception>
#include <sstream>
#include <utility>
#include <numbers>
#include <stdexcept>

namespace rowloc::apps {
namespace {

/// A plot file: its text is collected, then written checked and atomically (mapio::OutputFile).
class PlotFile {
 public:
  explicit PlotFile(std::filesystem::path path) : path_(std::move(path)) {}
  ~PlotFile() noexcept(false) {
    if (std::uncaught_exceptions() == 0) mapio::WriteFileAtomically(path_, text_.str());
  }
  PlotFile(const PlotFile&) = delete;
  PlotFile& operator=(const PlotFile&) = delete;
  template <typename T>
  PlotFile& operator<<(const T& value) {
    text_ << value;
    return *this;
  }

 private:
  std::filesystem::path path_;
  std::ostringstream text_;
};

/// The boundary of E(c, P) as a closed polyline: c + L (cos t, sin t), P = L L^T.
void WriteEllipse(PlotFile& out, const geometry::Ellipsoid<2>& e) {
  constexpr int kPoints = 96;
  for (int i = 0; i <= kPoints; ++i) {
    const double t = 2.0 * std::numbers::pi * i / kPoints;
    const Eigen::Vector2d p = e.center() + e.cholesky_factor() * Eigen::Vector2d(std::cos(t), std::sin(t));
    out << fmt::format("{:.6f} {:.6f}\n", p.x(), p.y());
  }
  out << "\n\n";  // next gnuplot index
}

/// A bound n^T p = beta as a 12 m segment centred on the point of the line nearest to `near`.
void WriteLine(PlotFile& out, const Eigen::Vector2d& n, double beta, const Eigen::Vector2d& near) {
  const Eigen::Vector2d foot = near + (beta - n.dot(near)) * n;
  const Eigen::Vector2d t(-n.y(), n.x());
  for (const double s : {-6.0, 6.0}) {
    const Eigen::Vector2d p = foot + s * t;
    out << fmt::format("{:.6f} {:.6f}\n", p.x(), p.y());
  }
  out << "\n";
}

}  // namespace

std::string WriteExamplePlot(const std::filesystem::path& directory, const geometry::RowMap& map,
                             const Eigen::Vector2d& truth_m, const geometry::Ellipsoid<2>& predicted,
                             const std::vector<ExampleCutStep>& steps) {
  std::filesystem::create_directories(directory);
  {
    PlotFile rows(directory / "rows.dat");
    for (const geometry::Row& row : map.rows) {
      for (const Eigen::Vector2d& p : row.points_m) rows << fmt::format("{:.6f} {:.6f}\n", p.x(), p.y());
      if (row.closed) rows << fmt::format("{:.6f} {:.6f}\n", row.points_m.front().x(), row.points_m.front().y());
      rows << "\n";
    }
  }
  std::string titles = "predicted";
  {
    PlotFile ellipses(directory / "ellipses.dat");
    WriteEllipse(ellipses, predicted);
    PlotFile slabs(directory / "slabs.dat");
    for (const ExampleCutStep& step : steps) {
      WriteEllipse(ellipses, step.after);
      WriteLine(slabs, step.slab.normal, step.slab.lower_m, truth_m);
      WriteLine(slabs, step.slab.normal, step.slab.upper_m, truth_m);
      titles += " after:" + step.sensor;
    }
  }
  {
    PlotFile points(directory / "points.dat");
    points << fmt::format("{:.6f} {:.6f} truth\n", truth_m.x(), truth_m.y());
    const Eigen::Vector2d c = steps.empty() ? predicted.center() : steps.back().after.center();
    points << fmt::format("{:.6f} {:.6f} estimate\n", c.x(), c.y());
  }
  {
    PlotFile gp(directory / "cuts.gp");
    gp << "set terminal svg size 960,720 dynamic enhanced font 'sans,11'\nset output 'cuts.svg'\n"
       << "set title 'Worked example: predicted ellipse, slabs of the four rangers, ellipse after each cut'\n"
       << "set size ratio -1\nset xlabel 'East [m]'\nset ylabel 'North [m]'\nset key outside right\n"
       << fmt::format("set xrange [{:.3f}:{:.3f}]\nset yrange [{:.3f}:{:.3f}]\n", truth_m.x() - 3.5,
                      truth_m.x() + 3.5, truth_m.y() - 2.5, truth_m.y() + 2.5)
       << fmt::format("titles = '{}'\n", titles)
       << "plot 'rows.dat' with lines lc rgb 'dark-green' lw 2 title 'rows (map)', \\\n"
       << "     'slabs.dat' with lines lc rgb 'magenta' dt 2 title 'slabs d +- k sigma' noenhanced, \\\n"
       << fmt::format("     for [i=0:{}] 'ellipses.dat' index i with lines lw 1.5 title word(titles, i+1) noenhanced, \\\n",
                      steps.size())
       << "     'points.dat' using 1:2 every ::0::0 with points pt 7 ps 1.2 lc rgb 'black' title 'truth', \\\n"
       << "     'points.dat' using 1:2 every ::1::1 with points pt 2 ps 1.5 lc rgb 'red' title 'estimate'\n";
  }
  const sim::PlotFiles files{directory, "cuts.gp", {"rows.dat", "ellipses.dat", "slabs.dat", "points.dat"},
                             {"cuts.svg"}};
  const sim::GnuplotRun run = sim::RunGnuplot(files);
  if (!run.ran || run.exit_code != 0) {
    return fmt::format("plot data in {} (no SVG: {})", directory.string(), run.message);
  }
  return fmt::format("plot: {}", (directory / "cuts.svg").string());
}

}  // namespace rowloc::apps
