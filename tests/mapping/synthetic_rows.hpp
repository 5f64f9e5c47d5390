// Test-only synthetic survey clouds for the map build tests: straight box-shaped rows of canopy
// (both faces, the top and the end caps sampled on a regular grid, like rowloc world's survey) over
// a tilted ground plane (sampled outside the rows' footprints).
#pragma once

#include "rowloc/mapping/point_cloud.hpp"

#include <Eigen/Core>

#include <cmath>
#include <random>
#include <vector>

namespace rowloc::test {

struct BoxRow {
  double x0 = 0.0;          ///< start along x
  double x1 = 10.0;         ///< end along x
  double y = 0.0;           ///< centre line
  double half_width = 0.25;
};

struct SyntheticField {
  std::vector<BoxRow> rows;
  double grade_x = 0.0;     ///< ground z = grade_x x + grade_y y + z0
  double grade_y = 0.0;
  double z0 = 0.0;
  double bottom = 0.5;      ///< canopy band above the ground
  double top = 1.8;
  double spacing = 0.05;    ///< sampling step
  double ground_margin = 1.5;  ///< ground sampled this far around the rows
  bool ground = true;
  bool one_sided = false;   ///< leave out the faces at y + half_width (a scan from one side)
  /// Leafy faces: each face's column of points at one x is moved across the row by a normal
  /// offset of this standard deviation (seeded: the same field gives the same cloud).
  double face_roughness_m = 0.0;

  double Ground(double x, double y) const { return grade_x * x + grade_y * y + z0; }

  bool InsideFootprint(double x, double y) const {
    for (const BoxRow& r : rows) {
      if (x >= r.x0 && x <= r.x1 && std::abs(y - r.y) <= r.half_width) return true;
    }
    return false;
  }

  mapping::PointCloud Cloud() const {
    mapping::PointCloud cloud;
    auto add = [&](double x, double y, double h) { cloud.points_m.emplace_back(x, y, Ground(x, y) + h); };
    const double s = spacing;
    std::mt19937_64 rng(17);
    std::normal_distribution<double> leaf(0.0, 1.0);
    for (const BoxRow& r : rows) {
      for (double x = r.x0; x <= r.x1 + 1e-9; x += s) {
        const double out_right = face_roughness_m * leaf(rng);
        const double out_left = face_roughness_m * leaf(rng);
        for (double h = bottom; h <= top + 1e-9; h += s) {
          add(x, r.y - r.half_width - out_right, h);
          if (!one_sided) add(x, r.y + r.half_width + out_left, h);
        }
        for (double y = r.y - r.half_width + s; y < r.y + r.half_width - 1e-9; y += s) add(x, y, top);
      }
      for (double y = r.y - r.half_width + s; y < r.y + r.half_width - 1e-9; y += s) {
        for (double h = bottom; h < top - 1e-9; h += s) {
          add(r.x0, y, h);
          add(r.x1, y, h);
        }
      }
    }
    if (ground && !rows.empty()) {
      double xl = rows.front().x0, xh = rows.front().x1, yl = rows.front().y, yh = rows.front().y;
      for (const BoxRow& r : rows) {
        xl = std::min(xl, r.x0);
        xh = std::max(xh, r.x1);
        yl = std::min(yl, r.y - r.half_width);
        yh = std::max(yh, r.y + r.half_width);
      }
      for (double x = xl - ground_margin; x <= xh + ground_margin; x += 2 * s) {
        for (double y = yl - ground_margin; y <= yh + ground_margin; y += 2 * s) {
          if (!InsideFootprint(x, y)) add(x, y, 0.0);
        }
      }
    }
    return cloud;
  }
};

}  // namespace rowloc::test
