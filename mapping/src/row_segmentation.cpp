// Canopy band and row detection (see row_segmentation.hpp). Plain C++ and Eigen.
#include "rowloc/mapping/row_segmentation.hpp"

#include <Eigen/Eigenvalues>

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <limits>
#include <numeric>
#include <stdexcept>
#include <string>
#include <tuple>
#include <unordered_map>
#include <utility>

namespace rowloc::mapping {
namespace {

/// Centroid and principal direction of a set of points.
std::pair<Eigen::Vector2d, Eigen::Vector2d> PrincipalAxis(const std::vector<Eigen::Vector2d>& points) {
  Eigen::Vector2d c = Eigen::Vector2d::Zero();
  for (const auto& p : points) c += p;
  c /= static_cast<double>(points.size());
  Eigen::Matrix2d cov = Eigen::Matrix2d::Zero();
  for (const auto& p : points) cov += (p - c) * (p - c).transpose();
  const Eigen::SelfAdjointEigenSolver<Eigen::Matrix2d> solver(cov);
  Eigen::Vector2d axis = solver.eigenvectors().col(1);  // largest eigenvalue last
  if (!axis.allFinite() || axis.norm() < 0.5) axis = Eigen::Vector2d::UnitX();
  return {c, axis.normalized()};
}

double Cross(const Eigen::Vector2d& a, const Eigen::Vector2d& b) { return a.x() * b.y() - a.y() * b.x(); }

struct End {
  Eigen::Vector2d position;
  Eigen::Vector2d outward;  // unit
};

/// The end of a part on the side of +sign * axis.
End PartEnd(const RowPart& part, double sign, double window_m) {
  const Eigen::Vector2d a = sign * part.axis;
  double t_max = -std::numeric_limits<double>::infinity();
  for (const auto& p : part.points_m) t_max = std::max(t_max, a.dot(p - part.centroid_m));
  const double window = std::min(window_m, 0.5 * part.length_m);
  std::vector<Eigen::Vector2d> near;
  for (const auto& p : part.points_m) {
    if (a.dot(p - part.centroid_m) >= t_max - window) near.push_back(p);
  }
  End end{part.centroid_m + t_max * a, a};
  if (near.size() >= 3) {
    auto [c, d] = PrincipalAxis(near);
    if (d.dot(a) < 0.0) d = -d;
    double reach = -std::numeric_limits<double>::infinity();
    for (const auto& p : near) reach = std::max(reach, d.dot(p - c));
    end = End{c + reach * d, d};
  }
  return end;
}

struct UnionFind {
  std::vector<std::size_t> parent;
  explicit UnionFind(std::size_t n) : parent(n) { std::iota(parent.begin(), parent.end(), 0); }
  std::size_t Find(std::size_t i) {
    while (parent[i] != i) i = parent[i] = parent[parent[i]];
    return i;
  }
  bool Unite(std::size_t a, std::size_t b) {
    a = Find(a);
    b = Find(b);
    if (a == b) return false;
    parent[std::max(a, b)] = std::min(a, b);
    return true;
  }
};

}  // namespace

std::vector<Eigen::Vector2d> SelectCanopyBand(const PointCloud& cloud,
                                              const std::vector<double>& heights_above_terrain_m,
                                              const CanopyBandParams& params) {
  if (heights_above_terrain_m.size() != cloud.points_m.size()) {
    throw std::invalid_argument("SelectCanopyBand: " + std::to_string(cloud.points_m.size()) +
                                " points but " + std::to_string(heights_above_terrain_m.size()) + " heights");
  }
  std::vector<Eigen::Vector2d> band;
  for (std::size_t i = 0; i < cloud.points_m.size(); ++i) {
    if (std::abs(heights_above_terrain_m[i] - params.reference_height_m) <= params.band_half_width_m) {
      band.push_back(cloud.points_m[i].head<2>());
    }
  }
  return band;
}

RowDetection DetectRows(const std::vector<Eigen::Vector2d>& band_points_m, const RowParams& params) {
  if (!(params.raster_cell_m > 0.0) || !(params.link_radius_m >= 0.0) || params.min_part_points < 1 ||
      !(params.min_part_length_m >= 0.0) || !(params.max_gap_m >= 0.0) ||
      !(params.max_link_angle_rad >= 0.0) || !(params.max_link_offset_m >= 0.0) ||
      !(params.end_window_m > 0.0)) {
    throw std::invalid_argument("DetectRows: parameter outside its domain");
  }
  RowDetection result;
  if (band_points_m.empty()) return result;

  // 1. Occupancy raster.
  const double g = params.raster_cell_m;
  Eigen::Vector2d lo = band_points_m.front();
  Eigen::Vector2d hi = lo;
  for (const auto& p : band_points_m) {
    lo = lo.cwiseMin(p);
    hi = hi.cwiseMax(p);
  }
  // Cells are kept sparse (a hash map of the occupied ones), so memory follows the band's points,
  // not the survey's bounding box.
  const double fx = std::floor((hi.x() - lo.x()) / g) + 1.0;
  const double fy = std::floor((hi.y() - lo.y()) / g) + 1.0;
  if (fx * fy > 1e18) {
    throw std::invalid_argument("DetectRows: the raster would have " + std::to_string(fx * fy) +
                                " cells (more than 10^18); use a larger rows.raster_cell_m");
  }
  const auto nx = static_cast<std::int64_t>(fx);
  const auto ny = static_cast<std::int64_t>(fy);
  constexpr std::int32_t kUnlabelled = -1;
  std::unordered_map<std::int64_t, std::int32_t> label;
  label.reserve(band_points_m.size() / 4 + 16);
  std::vector<std::int64_t> point_cell(band_points_m.size());
  std::vector<std::int64_t> occupied;
  for (std::size_t k = 0; k < band_points_m.size(); ++k) {
    const auto i = std::min<std::int64_t>(nx - 1, static_cast<std::int64_t>((band_points_m[k].x() - lo.x()) / g));
    const auto j = std::min<std::int64_t>(ny - 1, static_cast<std::int64_t>((band_points_m[k].y() - lo.y()) / g));
    const std::int64_t c = j * nx + i;
    point_cell[k] = c;
    if (label.emplace(c, kUnlabelled).second) occupied.push_back(c);
  }
  std::sort(occupied.begin(), occupied.end());
  result.raster_cells = occupied.size();

  // 2. Connected parts (cells within link_radius_m of each other).
  const int r = static_cast<int>(std::floor(params.link_radius_m / g + 1e-9));
  const int reach = std::max(1, r);
  std::vector<std::pair<int, int>> offsets;
  for (int dj = -reach; dj <= reach; ++dj) {
    for (int di = -reach; di <= reach; ++di) {
      if ((di == 0 && dj == 0) || di * di + dj * dj > std::max(2, r * r)) continue;
      offsets.emplace_back(di, dj);
    }
  }
  std::int32_t parts = 0;
  std::vector<std::int64_t> stack;
  for (const std::int64_t seed : occupied) {
    std::int32_t& seed_label = label[seed];
    if (seed_label != kUnlabelled) continue;
    seed_label = parts;
    stack.push_back(seed);
    while (!stack.empty()) {
      const std::int64_t c = stack.back();
      stack.pop_back();
      const std::int64_t i = c % nx;
      const std::int64_t j = c / nx;
      for (const auto& [di, dj] : offsets) {
        const std::int64_t ii = i + di;
        const std::int64_t jj = j + dj;
        if (ii < 0 || jj < 0 || ii >= nx || jj >= ny) continue;
        const auto found = label.find(jj * nx + ii);
        if (found != label.end() && found->second == kUnlabelled) {
          found->second = parts;
          stack.push_back(found->first);
        }
      }
    }
    ++parts;
  }
  result.parts_found = static_cast<std::size_t>(parts);
  std::vector<RowPart> all(static_cast<std::size_t>(parts));
  for (std::size_t k = 0; k < band_points_m.size(); ++k) {
    all[static_cast<std::size_t>(label.at(point_cell[k]))].points_m.push_back(band_points_m[k]);
  }
  std::vector<RowPart> kept;
  for (RowPart& part : all) {
    bool keep = part.points_m.size() >= static_cast<std::size_t>(params.min_part_points);
    if (keep) {
      std::tie(part.centroid_m, part.axis) = PrincipalAxis(part.points_m);
      double t_lo = std::numeric_limits<double>::infinity();
      double t_hi = -t_lo;
      for (const auto& p : part.points_m) {
        const double t = part.axis.dot(p - part.centroid_m);
        t_lo = std::min(t_lo, t);
        t_hi = std::max(t_hi, t);
      }
      part.length_m = t_hi - t_lo;
      keep = part.length_m >= params.min_part_length_m;
    }
    if (keep) {
      kept.push_back(std::move(part));
    } else {
      ++result.parts_dropped;
      result.points_dropped += part.points_m.size();
    }
  }
  if (kept.empty()) return result;

  // Dominant direction (doubled angles, weighted by length), pointing to +x (or +y).
  double s2 = 0.0;
  double c2 = 0.0;
  for (const RowPart& part : kept) {
    const double phi = std::atan2(part.axis.y(), part.axis.x());
    s2 += part.length_m * std::sin(2.0 * phi);
    c2 += part.length_m * std::cos(2.0 * phi);
  }
  const double theta = 0.5 * std::atan2(s2, c2);
  Eigen::Vector2d dir(std::cos(theta), std::sin(theta));
  if (dir.x() < -1e-12 || (std::abs(dir.x()) <= 1e-12 && dir.y() < 0.0)) dir = -dir;
  result.direction = dir;
  const Eigen::Vector2d left(-dir.y(), dir.x());

  // 3-4. Ends and links.
  const std::size_t n = kept.size();
  std::vector<End> ends(2 * n);  // 2k: the end towards -axis, 2k+1: towards +axis
  for (std::size_t k = 0; k < n; ++k) {
    ends[2 * k] = PartEnd(kept[k], -1.0, params.end_window_m);
    ends[2 * k + 1] = PartEnd(kept[k], 1.0, params.end_window_m);
  }
  struct Candidate {
    double gap;
    std::size_t a;
    std::size_t b;
  };
  std::vector<Candidate> candidates;
  const double cos_limit = std::cos(params.max_link_angle_rad);
  for (std::size_t a = 0; a < ends.size(); ++a) {
    for (std::size_t b = a + 1; b < ends.size(); ++b) {
      if (a / 2 == b / 2) continue;
      const End& ea = ends[a];
      const End& eb = ends[b];
      const Eigen::Vector2d gap = eb.position - ea.position;
      const double length = gap.norm();
      if (length > params.max_gap_m) continue;
      if (-ea.outward.dot(eb.outward) < cos_limit) continue;
      // The gap must run along the mean of the two end directions (for a circular arc this is the
      // chord's direction) and lie ahead of both ends.
      const Eigen::Vector2d mean = (ea.outward - eb.outward).normalized();
      if (gap.dot(ea.outward) < -params.link_radius_m || -gap.dot(eb.outward) < -params.link_radius_m) continue;
      if (std::abs(Cross(mean, gap)) > params.max_link_offset_m) continue;
      candidates.push_back({length, a, b});
    }
  }
  std::sort(candidates.begin(), candidates.end(), [](const Candidate& x, const Candidate& y) {
    return x.gap != y.gap ? x.gap < y.gap : std::make_pair(x.a, x.b) < std::make_pair(y.a, y.b);
  });
  std::vector<std::ptrdiff_t> partner(ends.size(), -1);  // linked end
  UnionFind sets(n);
  for (const Candidate& c : candidates) {
    if (partner[c.a] >= 0 || partner[c.b] >= 0) continue;
    if (!sets.Unite(c.a / 2, c.b / 2)) continue;
    partner[c.a] = static_cast<std::ptrdiff_t>(c.b);
    partner[c.b] = static_cast<std::ptrdiff_t>(c.a);
    ++result.links;
  }

  // 5. Chains: start at a part with a free end, walk through the links.
  std::vector<bool> used(n, false);
  struct Chain {
    std::vector<std::size_t> parts;
    double lateral = 0.0;
  };
  std::vector<Chain> chains;
  for (std::size_t k = 0; k < n; ++k) {
    if (used[k]) continue;
    const bool free_low = partner[2 * k] < 0;
    const bool free_high = partner[2 * k + 1] < 0;
    if (!free_low && !free_high) continue;  // inside a chain: reached from its start
    Chain chain;
    std::size_t part = k;
    std::size_t entry = free_low ? 2 * k : 2 * k + 1;  // the free end we enter by
    while (true) {
      used[part] = true;
      chain.parts.push_back(part);
      const std::size_t exit = entry ^ 1U;
      if (partner[exit] < 0) break;
      entry = static_cast<std::size_t>(partner[exit]);
      part = entry / 2;
    }
    double weight = 0.0;
    double along_first = 0.0;
    double along_last = 0.0;
    for (std::size_t p : chain.parts) {
      const double w = static_cast<double>(kept[p].points_m.size());
      chain.lateral += w * left.dot(kept[p].centroid_m);
      weight += w;
    }
    chain.lateral /= weight;
    along_first = dir.dot(kept[chain.parts.front()].centroid_m);
    along_last = dir.dot(kept[chain.parts.back()].centroid_m);
    if (along_last < along_first) std::reverse(chain.parts.begin(), chain.parts.end());
    chains.push_back(std::move(chain));
  }
  std::stable_sort(chains.begin(), chains.end(),
                   [](const Chain& a, const Chain& b) { return a.lateral < b.lateral; });
  for (const Chain& chain : chains) {
    DetectedRow row;
    for (std::size_t p : chain.parts) row.parts.push_back(std::move(kept[p]));
    result.rows.push_back(std::move(row));
  }
  return result;
}

std::vector<std::vector<Eigen::Vector2d>> AssignPointsToParts(const RowDetection& detection,
                                                              const std::vector<Eigen::Vector2d>& points_m,
                                                              double radius_m) {
  if (!(radius_m > 0.0) || !std::isfinite(radius_m)) {
    throw std::invalid_argument("AssignPointsToParts: radius_m must be positive");
  }
  struct CellHash {
    std::size_t operator()(const std::pair<std::int64_t, std::int64_t>& c) const {
      return std::hash<std::int64_t>()(c.first * 73856093 ^ c.second * 19349663);
    }
  };
  const auto cell_of = [radius_m](const Eigen::Vector2d& p) {
    return std::make_pair(static_cast<std::int64_t>(std::floor(p.x() / radius_m)),
                          static_cast<std::int64_t>(std::floor(p.y() / radius_m)));
  };
  std::unordered_map<std::pair<std::int64_t, std::int64_t>, int, CellHash> owner;
  int parts = 0;
  for (const DetectedRow& row : detection.rows) {
    for (const RowPart& part : row.parts) {
      for (const auto& p : part.points_m) owner.emplace(cell_of(p), parts);  // the first part keeps a cell
      ++parts;
    }
  }
  std::vector<std::vector<Eigen::Vector2d>> assigned(static_cast<std::size_t>(parts));
  for (const auto& p : points_m) {
    const auto [i, j] = cell_of(p);
    int found = -1;
    for (int d = 0; d < 10 && found < 0; ++d) {
      // The point's own cell first, then its neighbours.
      const std::int64_t di = d == 0 ? 0 : (d - 1) % 3 - 1;
      const std::int64_t dj = d == 0 ? 0 : (d - 1) / 3 - 1;
      const auto it = owner.find({i + di, j + dj});
      if (it != owner.end()) found = it->second;
    }
    if (found >= 0) assigned[static_cast<std::size_t>(found)].push_back(p);
  }
  return assigned;
}

}  // namespace rowloc::mapping
