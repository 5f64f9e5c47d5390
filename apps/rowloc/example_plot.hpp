// `rowloc example --plot DIR`: the worked example as a picture (issue 5, "plots of a run: rows,
// truth, estimate and ellipses before and after each cut"): the rows around the vehicle, the true
// position, the predicted k-sigma ellipse, each slab and the ellipse after each parallel cut, as
// gnuplot data files, a script and (when gnuplot is installed) DIR/cuts.svg.
#pragma once

#include "rowloc/geometry/ellipsoid.hpp"
#include "rowloc/geometry/row_map.hpp"
#include "rowloc/localization/range_slab.hpp"

#include <Eigen/Core>

#include <filesystem>
#include <string>
#include <vector>

namespace rowloc::apps {

/// One step of the example: the slab of a sensor that measured, and the ellipse after its cut.
struct ExampleCutStep {
  std::string sensor;
  localization::RangeSlab slab;
  geometry::Ellipsoid<2> after;
};

/// Writes DIR/{rows,ellipses,slabs,points}.dat and DIR/cuts.gp, then runs gnuplot for DIR/cuts.svg.
/// Returns a one-line description of the outcome (which files, or why no SVG). Throws
/// std::runtime_error if a file cannot be written.
std::string WriteExamplePlot(const std::filesystem::path& directory, const geometry::RowMap& map,
                             const Eigen::Vector2d& truth_m, const geometry::Ellipsoid<2>& predicted,
                             const std::vector<ExampleCutStep>& steps);

}  // namespace rowloc::apps
