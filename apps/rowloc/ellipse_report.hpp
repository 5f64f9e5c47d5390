// Human-readable description of a 2-D ellipse E(c, P) for the command line.
#pragma once

#include <Eigen/Core>
#include <Eigen/Eigenvalues>
#include <fmt/format.h>

#include <cmath>
#include <numbers>
#include <string>

namespace rowloc::apps {

/// Semi-axes (m), orientation of the major axis (deg from +East) and area (m^2) of E(c, P).
struct EllipseSummary {
  Eigen::Vector2d center_m;
  double semi_major_m;
  double semi_minor_m;
  double major_axis_deg;
  double area_m2;
};

inline EllipseSummary Summarize(const Eigen::Vector2d& center, const Eigen::Matrix2d& shape) {
  const Eigen::SelfAdjointEigenSolver<Eigen::Matrix2d> eig(shape);  // ascending eigenvalues
  const Eigen::Vector2d major = eig.eigenvectors().col(1);
  double angle = std::atan2(major.y(), major.x()) * 180.0 / std::numbers::pi;
  if (angle <= -90.0) angle += 180.0;
  if (angle > 90.0) angle -= 180.0;
  const double a = std::sqrt(eig.eigenvalues()(1));
  const double b = std::sqrt(eig.eigenvalues()(0));
  return {center, a, b, angle, std::numbers::pi * a * b};
}

inline std::string FormatEllipse(const EllipseSummary& s) {
  return fmt::format("centre ({:.4f}, {:.4f}) m, semi-axes {:.4f} x {:.4f} m at {:+.1f} deg, area {:.5f} m^2",
                     s.center_m.x(), s.center_m.y(), s.semi_major_m, s.semi_minor_m,
                     s.major_axis_deg, s.area_m2);
}

}  // namespace rowloc::apps
