// Outline of a row part traced from its band points (see row_outline.hpp). Plain C++ and Eigen.
#include "rowloc/mapping/row_outline.hpp"

#include <Eigen/Eigenvalues>

#include <algorithm>
#include <cmath>
#include <limits>
#include <stdexcept>
#include <utility>
#include <vector>

namespace rowloc::mapping {
namespace {

double Cross(const Eigen::Vector2d& a, const Eigen::Vector2d& b) { return a.x() * b.y() - a.y() * b.x(); }

double Quantile(std::vector<double>& values, double q) {
  const double position = q * static_cast<double>(values.size() - 1);
  const auto lo = static_cast<std::size_t>(std::floor(position));
  std::nth_element(values.begin(), values.begin() + static_cast<std::ptrdiff_t>(lo), values.end());
  const double a = values[lo];
  if (lo + 1 >= values.size()) return a;
  const double b = *std::min_element(values.begin() + static_cast<std::ptrdiff_t>(lo) + 1, values.end());
  return a + (position - static_cast<double>(lo)) * (b - a);
}

/// Fills the NaN entries by linear interpolation between valid neighbours (constant beyond the
/// first and last valid one). Returns false if no entry is valid.
bool FillGaps(std::vector<double>& v) {
  std::vector<std::size_t> valid;
  for (std::size_t i = 0; i < v.size(); ++i) {
    if (!std::isnan(v[i])) valid.push_back(i);
  }
  if (valid.empty()) return false;
  for (std::size_t i = 0; i < valid.front(); ++i) v[i] = v[valid.front()];
  for (std::size_t i = valid.back() + 1; i < v.size(); ++i) v[i] = v[valid.back()];
  for (std::size_t k = 0; k + 1 < valid.size(); ++k) {
    const std::size_t a = valid[k];
    const std::size_t b = valid[k + 1];
    for (std::size_t i = a + 1; i < b; ++i) {
      v[i] = v[a] + (v[b] - v[a]) * static_cast<double>(i - a) / static_cast<double>(b - a);
    }
  }
  return true;
}

/// A running median of three (the ends keep their values): removes an edge estimate that one
/// stray point made in a station bin of few points, keeps steps and corners of two bins or more.
std::vector<double> MedianOfThree(const std::vector<double>& v) {
  std::vector<double> out = v;
  for (std::size_t i = 1; i + 1 < v.size(); ++i) {
    out[i] = std::max(std::min(v[i - 1], v[i]), std::min(std::max(v[i - 1], v[i]), v[i + 1]));
  }
  return out;
}

/// A polyline with arc length: projection of points and evaluation of position and normal.
class CentreLine {
 public:
  explicit CentreLine(std::vector<Eigen::Vector2d> points) : points_(std::move(points)) {
    station_.push_back(0.0);
    for (std::size_t i = 1; i < points_.size(); ++i) {
      station_.push_back(station_.back() + (points_[i] - points_[i - 1]).norm());
    }
    for (std::size_t i = 0; i + 1 < points_.size(); ++i) {
      const Eigen::Vector2d d = (points_[i + 1] - points_[i]).normalized();
      normal_.emplace_back(-d.y(), d.x());
    }
  }

  /// Station and signed lateral offset of p (nearest segment; segments searched by `hint`, the
  /// index of a segment near p, +-window).
  std::pair<double, double> Project(const Eigen::Vector2d& p, std::size_t hint, std::size_t window) const {
    const std::size_t segments = points_.size() - 1;
    const std::size_t first = hint > window ? hint - window : 0;
    const std::size_t last = std::min(segments - 1, hint + window);
    double best = std::numeric_limits<double>::infinity();
    std::pair<double, double> result{0.0, 0.0};
    for (std::size_t i = first; i <= last; ++i) {
      const Eigen::Vector2d a = points_[i];
      const Eigen::Vector2d d = points_[i + 1] - a;
      const double length2 = d.squaredNorm();
      const double t = length2 > 0.0 ? std::clamp((p - a).dot(d) / length2, 0.0, 1.0) : 0.0;
      const Eigen::Vector2d q = a + t * d;
      const double distance2 = (p - q).squaredNorm();
      if (distance2 < best) {
        best = distance2;
        result = {station_[i] + t * std::sqrt(length2), Cross(d.normalized(), p - a)};
      }
    }
    return result;
  }

  /// Position and unit left normal at station s (normals blended between segment midpoints).
  std::pair<Eigen::Vector2d, Eigen::Vector2d> At(double s) const {
    const std::size_t segments = points_.size() - 1;
    const auto it = std::upper_bound(station_.begin(), station_.end(), s);
    std::size_t i = it == station_.begin() ? 0 : static_cast<std::size_t>(it - station_.begin()) - 1;
    i = std::min(i, segments - 1);
    const double length = station_[i + 1] - station_[i];
    const double t = length > 0.0 ? (s - station_[i]) / length : 0.0;
    const Eigen::Vector2d position = points_[i] + t * (points_[i + 1] - points_[i]);
    Eigen::Vector2d normal = normal_[i];
    if (t < 0.5 && i > 0) {
      const double w = 0.5 - t;  // 0.5 at the vertex: the mean of both segments
      normal = ((1.0 - w) * normal_[i] + w * normal_[i - 1]).normalized();
    } else if (t > 0.5 && i + 1 < segments) {
      const double w = t - 0.5;
      normal = ((1.0 - w) * normal_[i] + w * normal_[i + 1]).normalized();
    }
    return {position, normal};
  }

  const std::vector<Eigen::Vector2d>& points() const { return points_; }

 private:
  std::vector<Eigen::Vector2d> points_;
  std::vector<double> station_;
  std::vector<Eigen::Vector2d> normal_;
};

}  // namespace

PartOutline TraceOutline(const std::vector<Eigen::Vector2d>& points_m, const OutlineParams& params) {
  if (!(params.centreline_bin_m > 0.0) || !(params.station_step_m > 0.0) ||
      !(params.edge_quantile >= 0.0 && params.edge_quantile <= 1.0) || !(params.end_exclusion_m >= 0.0) ||
      !(params.min_width_m >= 0.0)) {
    throw std::invalid_argument("TraceOutline: parameter outside its domain");
  }
  PartOutline outline;
  if (points_m.size() < 3) return outline;

  // 1. Principal axis and the centre line from bin means along it.
  Eigen::Vector2d c = Eigen::Vector2d::Zero();
  for (const auto& p : points_m) c += p;
  c /= static_cast<double>(points_m.size());
  Eigen::Matrix2d cov = Eigen::Matrix2d::Zero();
  for (const auto& p : points_m) cov += (p - c) * (p - c).transpose();
  Eigen::Vector2d axis = Eigen::SelfAdjointEigenSolver<Eigen::Matrix2d>(cov).eigenvectors().col(1);
  if (!axis.allFinite() || axis.norm() < 0.5) axis = Eigen::Vector2d::UnitX();
  axis.normalize();
  const Eigen::Vector2d across(-axis.y(), axis.x());
  double t_lo = std::numeric_limits<double>::infinity();
  double t_hi = -t_lo;
  for (const auto& p : points_m) {
    const double t = axis.dot(p - c);
    t_lo = std::min(t_lo, t);
    t_hi = std::max(t_hi, t);
  }
  const auto bins = static_cast<std::size_t>(std::max(1.0, std::ceil((t_hi - t_lo) / params.centreline_bin_m)));
  const double bin = std::max((t_hi - t_lo) / static_cast<double>(bins), 1e-9);
  std::vector<Eigen::Vector2d> sum(bins, Eigen::Vector2d::Zero());
  std::vector<std::size_t> count(bins, 0);
  const auto bin_of = [&](double t) {
    return std::min(bins - 1, static_cast<std::size_t>(std::max(0.0, (t - t_lo) / bin)));
  };
  for (const auto& p : points_m) {
    const std::size_t b = bin_of(axis.dot(p - c));
    sum[b] += Eigen::Vector2d(axis.dot(p - c), across.dot(p - c));
    ++count[b];
  }
  std::vector<Eigen::Vector2d> means;  // (t, u)
  for (std::size_t b = 0; b < bins; ++b) {
    if (count[b] > 0) means.push_back(sum[b] / static_cast<double>(count[b]));
  }
  std::vector<Eigen::Vector2d> smoothed = means;
  for (std::size_t k = 1; k + 1 < means.size(); ++k) {
    smoothed[k].y() = (means[k - 1].y() + means[k].y() + means[k + 1].y()) / 3.0;
  }
  std::vector<Eigen::Vector2d> vertices;  // the centre line before its end extensions
  const auto to_xy = [&](const Eigen::Vector2d& tu) { return c + tu.x() * axis + tu.y() * across; };
  if (smoothed.size() == 1) {
    vertices = {to_xy({t_lo, smoothed[0].y()}), to_xy({t_hi, smoothed[0].y()})};
  } else {
    for (const auto& tu : smoothed) vertices.push_back(to_xy(tu));
  }
  // Extends both ends along their last segment so that every point projects inside the line.
  const auto extended = [margin = bin + 1.0](const std::vector<Eigen::Vector2d>& v) {
    std::vector<Eigen::Vector2d> line;
    line.push_back(v.front() - margin * (v[1] - v[0]).normalized());
    line.insert(line.end(), v.begin(), v.end());
    line.push_back(v.back() + margin * (v.back() - v[v.size() - 2]).normalized());
    return line;
  };
  // Projects every point (segment hint from its nearest vertex along the axis, which is monotone).
  std::vector<double> vertex_t;
  const auto project_all = [&](const CentreLine& centre, std::vector<std::pair<double, double>>& se) {
    vertex_t.clear();
    for (const auto& p : centre.points()) vertex_t.push_back(axis.dot(p - c));
    const std::size_t segments = centre.points().size() - 1;
    se.resize(points_m.size());
    for (std::size_t k = 0; k < points_m.size(); ++k) {
      const double t = axis.dot(points_m[k] - c);
      const auto it = std::upper_bound(vertex_t.begin(), vertex_t.end(), t);
      const std::size_t hint = std::min(segments - 1, static_cast<std::size_t>(std::max<std::ptrdiff_t>(
                                                          0, (it - vertex_t.begin()) - 1)));
      se[k] = centre.Project(points_m[k], hint, 3);
    }
  };

  // 1b. Refinement: the centre line of the first pass is biased where the part's ends are oblique
  // to its axis (one face reaches further along the axis than the other). Re-centre it between the
  // median left and right offsets per station bin, twice.
  std::vector<std::pair<double, double>> se;
  for (int pass = 0; pass < 2 && vertices.size() >= 2; ++pass) {
    const CentreLine centre(extended(vertices));
    project_all(centre, se);
    double s_min = std::numeric_limits<double>::infinity();
    double s_max = -s_min;
    for (const auto& [s, e] : se) {
      s_min = std::min(s_min, s);
      s_max = std::max(s_max, s);
    }
    const auto n = static_cast<std::size_t>(std::max(1.0, std::ceil((s_max - s_min) / params.centreline_bin_m)));
    const double width = std::max((s_max - s_min) / static_cast<double>(n), 1e-9);
    std::vector<std::vector<double>> lefts(n);
    std::vector<std::vector<double>> rights(n);
    std::vector<double> s_sum(n, 0.0);
    for (const auto& [s, e] : se) {
      const auto k = std::min(n - 1, static_cast<std::size_t>((s - s_min) / width));
      (e > 0.0 ? lefts[k] : rights[k]).push_back(std::abs(e));
      s_sum[k] += s;
    }
    std::vector<Eigen::Vector2d> refined;
    for (std::size_t k = 0; k < n; ++k) {
      if (lefts[k].empty() || rights[k].empty()) continue;
      const double s_mean = s_sum[k] / static_cast<double>(lefts[k].size() + rights[k].size());
      const double shift = 0.5 * (Quantile(lefts[k], 0.5) - Quantile(rights[k], 0.5));
      const auto [position, normal] = centre.At(s_mean);
      refined.push_back(position + shift * normal);
    }
    if (refined.size() < 2) break;
    // Keep the line monotone along the axis (the projection hint relies on it).
    std::vector<Eigen::Vector2d> monotone;
    for (const auto& p : refined) {
      if (monotone.empty() || axis.dot(p - monotone.back()) > 1e-6) monotone.push_back(p);
    }
    if (monotone.size() < 2) break;
    std::vector<Eigen::Vector2d> smooth = monotone;
    for (std::size_t k = 1; k + 1 < monotone.size(); ++k) {
      smooth[k] = (monotone[k - 1] + monotone[k] + monotone[k + 1]) / 3.0;
    }
    vertices = std::move(smooth);
  }
  const std::vector<Eigen::Vector2d> line = extended(vertices);
  const CentreLine centre(line);
  outline.centreline_m = line;

  // 2. Station and offset of every point. The part spans from its third lowest to its third highest
  //    station: up to two stray points beyond an end (an outlier the cleaning kept, within
  //    rows.link_radius_m of the row) are left out instead of moving the end cap out to them.
  project_all(centre, se);
  std::vector<double> stations_sorted;
  stations_sorted.reserve(se.size());
  for (const auto& [s, e] : se) stations_sorted.push_back(s);
  std::sort(stations_sorted.begin(), stations_sorted.end());
  const std::size_t strays = std::min<std::size_t>(2, (stations_sorted.size() - 1) / 2);
  const double s_lo = stations_sorted[strays];
  const double s_hi = stations_sorted[stations_sorted.size() - 1 - strays];
  std::erase_if(se, [&](const std::pair<double, double>& p) { return p.first < s_lo || p.first > s_hi; });

  // 3. Edges per station bin.
  const auto stations = static_cast<std::size_t>(std::max(1.0, std::round((s_hi - s_lo) / params.station_step_m)));
  const double step = std::max((s_hi - s_lo) / static_cast<double>(stations), 1e-9);
  std::vector<std::vector<double>> left(stations);
  std::vector<std::vector<double>> right(stations);
  const bool exclude_ends = s_hi - s_lo > 4.0 * params.end_exclusion_m;
  for (const auto& [s, e] : se) {
    if (exclude_ends && (s < s_lo + params.end_exclusion_m || s > s_hi - params.end_exclusion_m)) continue;
    const auto k = std::min(stations - 1, static_cast<std::size_t>((s - s_lo) / step));
    (e > 0.0 ? left[k] : right[k]).push_back(std::abs(e));
  }
  const double nan = std::numeric_limits<double>::quiet_NaN();
  std::vector<double> left_edge(stations, nan);
  std::vector<double> right_edge(stations, nan);
  for (std::size_t k = 0; k < stations; ++k) {
    if (!left[k].empty()) left_edge[k] = Quantile(left[k], params.edge_quantile);
    if (!right[k].empty()) right_edge[k] = Quantile(right[k], params.edge_quantile);
  }
  if (!FillGaps(left_edge) || !FillGaps(right_edge)) return outline;
  left_edge = MedianOfThree(left_edge);
  right_edge = MedianOfThree(right_edge);
  std::vector<double> widths(stations);
  for (std::size_t k = 0; k < stations; ++k) widths[k] = left_edge[k] + right_edge[k];
  outline.median_width_m = Quantile(widths, 0.5);
  if (outline.median_width_m < params.min_width_m) return outline;

  // The end caps: the median station of the points near an end and well inside the edges (cap
  // samples); the extreme station is biased outward by the noise. Without such points (no cap
  // sampled), the extreme station.
  const auto cap = [&](bool low, double extreme) {
    const double half = 0.5 * std::min(low ? left_edge.front() : left_edge.back(),
                                       low ? right_edge.front() : right_edge.back());
    std::vector<double> near;
    for (const auto& [s, e] : se) {
      const bool at_end = low ? s < s_lo + params.end_exclusion_m : s > s_hi - params.end_exclusion_m;
      if (at_end && std::abs(e) < half) near.push_back(s);
    }
    return near.size() >= 3 ? Quantile(near, 0.5) : extreme;
  };
  const double cap_lo = cap(true, s_lo);
  const double cap_hi = std::max(cap(false, s_hi), cap_lo + 1e-3);

  // 4. Polygon: right edge forward, left edge backward; the caps close it.
  std::vector<double> at;          // stations of the vertices
  std::vector<std::size_t> which;  // their station bins
  at.push_back(cap_lo);
  which.push_back(0);
  for (std::size_t k = 0; k < stations; ++k) {
    const double s = s_lo + (static_cast<double>(k) + 0.5) * step;
    if (s <= cap_lo || s >= cap_hi) continue;
    at.push_back(s);
    which.push_back(k);
  }
  at.push_back(cap_hi);
  which.push_back(stations - 1);
  for (std::size_t v = 0; v < at.size(); ++v) {
    const auto [position, normal] = centre.At(at[v]);
    outline.polygon_m.push_back(position - right_edge[which[v]] * normal);
  }
  for (std::size_t v = at.size(); v-- > 0;) {
    const auto [position, normal] = centre.At(at[v]);
    outline.polygon_m.push_back(position + left_edge[which[v]] * normal);
  }
  outline.length_m = cap_hi - cap_lo;
  return outline;
}

}  // namespace rowloc::mapping
