// Outline of a row part traced from its band points (see row_outline.hpp). Plain C++ and Eigen.
#include "rowloc/mapping/row_outline.hpp"

#include <Eigen/Eigenvalues>

#include <algorithm>
#include <cmath>
#include <initializer_list>
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

/// A part's centre line (step 1): the principal axis, the line, and its vertices' positions along
/// the axis (monotone: the projection's segment hint relies on it).
struct FittedLine {
  Eigen::Vector2d c = Eigen::Vector2d::Zero();
  Eigen::Vector2d axis = Eigen::Vector2d::UnitX();
  CentreLine centre;
  std::vector<double> vertex_t;

  FittedLine(const Eigen::Vector2d& c_in, const Eigen::Vector2d& axis_in, std::vector<Eigen::Vector2d> line)
      : c(c_in), axis(axis_in), centre(std::move(line)) {
    for (const auto& p : centre.points()) vertex_t.push_back(axis.dot(p - c));
  }

  /// Station and signed lateral offset of every point.
  std::vector<std::pair<double, double>> ProjectAll(const std::vector<Eigen::Vector2d>& points_m) const {
    const std::size_t segments = centre.points().size() - 1;
    std::vector<std::pair<double, double>> se(points_m.size());
    for (std::size_t k = 0; k < points_m.size(); ++k) {
      const double t = axis.dot(points_m[k] - c);
      const auto it = std::upper_bound(vertex_t.begin(), vertex_t.end(), t);
      const std::size_t hint = std::min(
          segments - 1, static_cast<std::size_t>(std::max<std::ptrdiff_t>(0, (it - vertex_t.begin()) - 1)));
      se[k] = centre.Project(points_m[k], hint, 3);
    }
    return se;
  }
};

/// Extends both ends of a line along their last segment so that every point projects inside it.
std::vector<Eigen::Vector2d> Extended(const std::vector<Eigen::Vector2d>& v, double margin) {
  std::vector<Eigen::Vector2d> line;
  line.push_back(v.front() - margin * (v[1] - v[0]).normalized());
  line.insert(line.end(), v.begin(), v.end());
  line.push_back(v.back() + margin * (v.back() - v[v.size() - 2]).normalized());
  return line;
}

/// Step 1: the centre line of >= 3 points, from bin means along their principal axis; if
/// `between_faces`, then re-centred twice between the median left and right offsets per bin (the
/// first pass is biased where the part's ends are oblique to its axis: one face reaches further
/// than the other).
FittedLine FitCentreLine(const std::vector<Eigen::Vector2d>& points_m, double bin_m, bool between_faces) {
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
  const auto bins = static_cast<std::size_t>(std::max(1.0, std::ceil((t_hi - t_lo) / bin_m)));
  const double bin = std::max((t_hi - t_lo) / static_cast<double>(bins), 1e-9);
  std::vector<Eigen::Vector2d> sum(bins, Eigen::Vector2d::Zero());
  std::vector<std::size_t> count(bins, 0);
  for (const auto& p : points_m) {
    const double t = axis.dot(p - c);
    const std::size_t b = std::min(bins - 1, static_cast<std::size_t>(std::max(0.0, (t - t_lo) / bin)));
    sum[b] += Eigen::Vector2d(t, across.dot(p - c));
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
  const double margin = bin + 1.0;
  for (int pass = 0; between_faces && pass < 2 && vertices.size() >= 2; ++pass) {
    const FittedLine fit(c, axis, Extended(vertices, margin));
    const auto se = fit.ProjectAll(points_m);
    double s_min = std::numeric_limits<double>::infinity();
    double s_max = -s_min;
    for (const auto& [s, e] : se) {
      s_min = std::min(s_min, s);
      s_max = std::max(s_max, s);
    }
    const auto n = static_cast<std::size_t>(std::max(1.0, std::ceil((s_max - s_min) / bin_m)));
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
      const auto [position, normal] = fit.centre.At(s_mean);
      refined.push_back(position + shift * normal);
    }
    if (refined.size() < 2) break;
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
  return FittedLine(c, axis, Extended(vertices, margin));
}

/// Step 2's station range: from the third lowest to the third highest station. Up to two stray
/// points beyond an end (an outlier the cleaning kept, within rows.link_radius_m of the row) are
/// left out instead of moving the end cap out to them; `se` loses them.
std::pair<double, double> TrimStrays(std::vector<std::pair<double, double>>& se) {
  std::vector<double> stations;
  stations.reserve(se.size());
  for (const auto& [s, e] : se) stations.push_back(s);
  std::sort(stations.begin(), stations.end());
  const std::size_t strays = std::min<std::size_t>(2, (stations.size() - 1) / 2);
  const double s_lo = stations[strays];
  const double s_hi = stations[stations.size() - 1 - strays];
  std::erase_if(se, [&](const std::pair<double, double>& p) { return p.first < s_lo || p.first > s_hi; });
  return {s_lo, s_hi};
}

/// The station bins of step 3 over [s_lo, s_hi].
struct StationBins {
  double s_lo = 0.0;
  std::size_t count = 1;
  double step = 1.0;

  StationBins(double lo, double hi, double step_m)
      : s_lo(lo),
        count(static_cast<std::size_t>(std::max(1.0, std::round((hi - lo) / step_m)))),
        step(std::max((hi - lo) / static_cast<double>(count), 1e-9)) {}

  std::size_t Of(double s) const {
    return std::min(count - 1, static_cast<std::size_t>(std::max(0.0, (s - s_lo) / step)));
  }
  double Centre(std::size_t k) const { return s_lo + (static_cast<double>(k) + 0.5) * step; }
};

/// Step 4: the polygon, right edge forward and left edge backward, closed by caps at cap_lo and
/// cap_hi (edges: magnitudes of the offsets per station bin).
std::vector<Eigen::Vector2d> AssemblePolygon(const CentreLine& centre, const StationBins& bins, double cap_lo,
                                             double cap_hi, const std::vector<double>& left_edge,
                                             const std::vector<double>& right_edge) {
  std::vector<double> at;          // stations of the vertices
  std::vector<std::size_t> which;  // their station bins
  at.push_back(cap_lo);
  which.push_back(0);
  for (std::size_t k = 0; k < bins.count; ++k) {
    const double s = bins.Centre(k);
    if (s <= cap_lo || s >= cap_hi) continue;
    at.push_back(s);
    which.push_back(k);
  }
  at.push_back(cap_hi);
  which.push_back(bins.count - 1);
  std::vector<Eigen::Vector2d> polygon;
  for (std::size_t v = 0; v < at.size(); ++v) {
    const auto [position, normal] = centre.At(at[v]);
    polygon.push_back(position - right_edge[which[v]] * normal);
  }
  for (std::size_t v = at.size(); v-- > 0;) {
    const auto [position, normal] = centre.At(at[v]);
    polygon.push_back(position + left_edge[which[v]] * normal);
  }
  return polygon;
}

/// The end caps' stations: per end, the median station of the points within end_exclusion_m of
/// it and well inside the edges (at most half-way from the middle of the outline to its nearer
/// edge: the cap samples); the extreme station is biased outward by the noise. Without three such
/// points (no cap sampled), the extreme station.
std::pair<double, double> CapStations(const std::vector<std::pair<double, double>>& se, double s_lo, double s_hi,
                                      double end_exclusion_m, const std::vector<double>& left_edge,
                                      const std::vector<double>& right_edge) {
  const auto cap = [&](bool low) {
    const double left = low ? left_edge.front() : left_edge.back();
    const double right = low ? right_edge.front() : right_edge.back();
    const double middle = 0.5 * (left - right);
    const double half = 0.25 * (left + right);
    std::vector<double> near;
    for (const auto& [s, e] : se) {
      const bool at_end = low ? s < s_lo + end_exclusion_m : s > s_hi - end_exclusion_m;
      if (at_end && std::abs(e - middle) < half) near.push_back(s);
    }
    return near.size() >= 3 ? Quantile(near, 0.5) : (low ? s_lo : s_hi);
  };
  const double cap_lo = cap(true);
  return {cap_lo, std::max(cap(false), cap_lo + 1e-3)};
}

/// The farthest distance reached from 0 through the sorted values with gaps of at most kTopGapM
/// (sorts `d`; 0 if none is within kTopGapM).
double ContiguousReach(std::vector<double>& d) {
  std::sort(d.begin(), d.end());
  double reach = 0.0;
  for (std::size_t n = 0; n < d.size() && d[n] <= reach + kTopGapM; ++n) reach = std::max(reach, d[n]);
  return reach;
}

/// The noise left in the outline by the per-station edge estimates, estimated from the raw
/// estimates (before their median of three): 1.4826 MAD of their second differences
/// e_k - (e_{k-1} + e_{k+1}) / 2 over every edge given, / sqrt(1.5) (the second difference of white
/// noise of variance s^2 has variance 1.5 s^2; a smooth edge's curvature is negligible at 5 cm
/// stations), times 0.67 (the standard deviation of the median of three normal samples is
/// 0.670 s). 0 with fewer than three stations.
double EdgeNoise(std::initializer_list<const std::vector<double>*> edges) {
  std::vector<double> d;
  for (const std::vector<double>* e : edges) {
    for (std::size_t k = 1; k + 1 < e->size(); ++k) d.push_back((*e)[k] - 0.5 * ((*e)[k - 1] + (*e)[k + 1]));
  }
  if (d.empty()) return 0.0;
  const double median = Quantile(d, 0.5);
  for (double& v : d) v = std::abs(v - median);
  constexpr double kMedianOfThree = 0.670;
  return kMedianOfThree * 1.4826 * Quantile(d, 0.5) / std::sqrt(1.5);
}

void CheckParams(const OutlineParams& params) {
  if (!(params.centreline_bin_m > 0.0) || !(params.station_step_m > 0.0) ||
      !(params.edge_quantile >= 0.0 && params.edge_quantile <= 1.0) || !(params.end_exclusion_m >= 0.0) ||
      !(params.min_width_m >= 0.0) || !(params.one_sided_max_width_m >= 0.0) ||
      !(params.one_sided_window_m > 0.0)) {
    throw std::invalid_argument("TraceOutline: parameter outside its domain");
  }
}

}  // namespace

PartOutline TraceOutline(const std::vector<Eigen::Vector2d>& points_m, const OutlineParams& params) {
  CheckParams(params);
  PartOutline outline;
  if (points_m.size() < 3) return outline;

  // 1-2. Centre line; station and offset of every point.
  const FittedLine fit = FitCentreLine(points_m, params.centreline_bin_m, true);
  outline.centreline_m = fit.centre.points();
  std::vector<std::pair<double, double>> se = fit.ProjectAll(points_m);
  const auto [s_lo, s_hi] = TrimStrays(se);

  // 3. Edges per station bin.
  const StationBins bins(s_lo, s_hi, params.station_step_m);
  std::vector<std::vector<double>> left(bins.count);
  std::vector<std::vector<double>> right(bins.count);
  const bool exclude_ends = s_hi - s_lo > 4.0 * params.end_exclusion_m;
  for (const auto& [s, e] : se) {
    if (exclude_ends && (s < s_lo + params.end_exclusion_m || s > s_hi - params.end_exclusion_m)) continue;
    (e > 0.0 ? left : right)[bins.Of(s)].push_back(std::abs(e));
  }
  const double nan = std::numeric_limits<double>::quiet_NaN();
  std::vector<double> left_edge(bins.count, nan);
  std::vector<double> right_edge(bins.count, nan);
  for (std::size_t k = 0; k < bins.count; ++k) {
    if (!left[k].empty()) left_edge[k] = Quantile(left[k], params.edge_quantile);
    if (!right[k].empty()) right_edge[k] = Quantile(right[k], params.edge_quantile);
  }
  if (!FillGaps(left_edge) || !FillGaps(right_edge)) return outline;
  outline.edge_noise_m = EdgeNoise({&left_edge, &right_edge});
  left_edge = MedianOfThree(left_edge);
  right_edge = MedianOfThree(right_edge);
  std::vector<double> widths(bins.count);
  for (std::size_t k = 0; k < bins.count; ++k) widths[k] = left_edge[k] + right_edge[k];
  outline.median_width_m = Quantile(widths, 0.5);
  if (outline.median_width_m < params.min_width_m) return outline;

  const auto [cap_lo, cap_hi] = CapStations(se, s_lo, s_hi, params.end_exclusion_m, left_edge, right_edge);

  // 4. Polygon.
  outline.polygon_m = AssemblePolygon(fit.centre, bins, cap_lo, cap_hi, left_edge, right_edge);
  outline.length_m = cap_hi - cap_lo;
  return outline;
}

PartOutline TraceOneSidedOutline(const std::vector<Eigen::Vector2d>& face_m, const std::vector<Eigen::Vector2d>& top_m,
                                 const OutlineParams& params) {
  CheckParams(params);
  PartOutline outline;
  if (face_m.size() < 3 || params.one_sided_max_width_m <= 0.0) return outline;

  // The face: its line, its station range and its offset from the line per station bin. The end
  // caps' points lie across the canopy, not on the face: the line is fitted again without them
  // (they would bend its ends), and they are left out of the offsets as in TraceOutline.
  FittedLine fit = FitCentreLine(face_m, params.centreline_bin_m, false);
  std::vector<std::pair<double, double>> se = fit.ProjectAll(face_m);
  {
    std::vector<std::pair<double, double>> trimmed = se;
    const auto [lo, hi] = TrimStrays(trimmed);
    std::vector<Eigen::Vector2d> inner;
    for (std::size_t k = 0; k < face_m.size(); ++k) {
      if (se[k].first > lo + params.end_exclusion_m && se[k].first < hi - params.end_exclusion_m) inner.push_back(face_m[k]);
    }
    if (inner.size() >= 3) {
      fit = FitCentreLine(inner, params.centreline_bin_m, false);
      se = fit.ProjectAll(face_m);
    }
  }
  outline.centreline_m = fit.centre.points();
  const auto [s_lo, s_hi] = TrimStrays(se);
  const StationBins bins(s_lo, s_hi, params.station_step_m);
  const double nan = std::numeric_limits<double>::quiet_NaN();
  std::vector<std::vector<double>> face_offsets(bins.count);
  const bool exclude_ends = s_hi - s_lo > 4.0 * params.end_exclusion_m;
  for (const auto& [s, e] : se) {
    if (exclude_ends && (s < s_lo + params.end_exclusion_m || s > s_hi - params.end_exclusion_m)) continue;
    face_offsets[bins.Of(s)].push_back(e);
  }
  std::vector<double> face(bins.count, nan);
  for (std::size_t k = 0; k < bins.count; ++k) {
    if (!face_offsets[k].empty()) face[k] = Quantile(face_offsets[k], 0.5);
  }
  if (!FillGaps(face)) return outline;
  const double face_noise_m = EdgeNoise({&face});
  face = MedianOfThree(face);

  // The top's cells by station bin, as distances from the face (> 0: to the face's left).
  std::vector<std::vector<double>> depth(bins.count);
  for (const auto& [s, e] : fit.ProjectAll(top_m)) {
    if (s < s_lo || s > s_hi) continue;
    const std::size_t k = bins.Of(s);
    const double d = e - face[k];
    if (std::abs(d) <= params.one_sided_max_width_m) depth[k].push_back(d);
  }

  // Per station, over a window of one_sided_window_m: the cells of each side that are contiguous
  // with the face (gaps of at most kTopGapM; beyond a wider gap lies the next row), and the width
  // from their upper quantile (cells spread evenly from the face to the far edge).
  const auto half_window = static_cast<std::size_t>(std::ceil(0.5 * params.one_sided_window_m / bins.step));
  std::vector<double> width[2] = {std::vector<double>(bins.count, nan), std::vector<double>(bins.count, nan)};
  std::size_t cells[2] = {0, 0};
  std::vector<double> window_cells[2];  // cells per measured window
  for (std::size_t k = 0; k < bins.count; ++k) {
    const std::size_t first = k > half_window ? k - half_window : 0;
    const std::size_t last = std::min(bins.count - 1, k + half_window);
    for (int i = 0; i < 2; ++i) {
      const double sign = i == 0 ? 1.0 : -1.0;  // 0: to the face's left
      std::vector<double> window;
      for (std::size_t j = first; j <= last; ++j) {
        for (double d : depth[j]) {
          if (sign * d >= -kTopGapM) window.push_back(sign * d);
        }
      }
      const double reach = ContiguousReach(window);
      std::erase_if(window, [&](double d) { return d > reach; });
      cells[i] += window.size();
      if (window.size() >= kMinTopCells) {
        width[i][k] = std::max(0.0, Quantile(window, kTopQuantile)) / kTopQuantile;
        window_cells[i].push_back(static_cast<double>(window.size()));
      }
    }
  }
  const int canopy_side = cells[0] >= cells[1] ? 0 : 1;
  std::vector<double>& w = width[canopy_side];
  std::size_t measured = 0;
  for (double v : w) measured += std::isnan(v) ? 0 : 1;
  // The top must be seen along at least half the part: elsewhere its width is interpolated.
  if (2 * measured < bins.count || !FillGaps(w)) return outline;
  w = MedianOfThree(w);
  std::vector<double> sorted = w;
  outline.median_width_m = Quantile(sorted, 0.5);
  sorted = w;
  outline.width_spread_m = 0.5 * (Quantile(sorted, 0.75) - Quantile(sorted, 0.25)) / 0.6745;
  // The quantile of n points spread evenly over [0, W] has the standard deviation
  // W sqrt(q (1 - q) / n); n: the median window.
  const double n = window_cells[canopy_side].empty() ? 0.0 : Quantile(window_cells[canopy_side], 0.5);
  outline.width_sigma_m =
      n > 0.0 ? outline.median_width_m * std::sqrt(kTopQuantile * (1.0 - kTopQuantile) / n) / kTopQuantile : 0.0;
  outline.edge_noise_m = face_noise_m;
  if (outline.median_width_m < params.min_width_m) return outline;

  std::vector<double> left_edge(bins.count);
  std::vector<double> right_edge(bins.count);
  for (std::size_t k = 0; k < bins.count; ++k) {
    left_edge[k] = canopy_side == 0 ? face[k] + w[k] : face[k];
    right_edge[k] = canopy_side == 0 ? -face[k] : w[k] - face[k];
  }
  const auto [cap_lo, cap_hi] = CapStations(se, s_lo, s_hi, params.end_exclusion_m, left_edge, right_edge);
  outline.polygon_m = AssemblePolygon(fit.centre, bins, cap_lo, cap_hi, left_edge, right_edge);
  outline.length_m = cap_hi - cap_lo;
  outline.one_sided = true;
  return outline;
}

}  // namespace rowloc::mapping
