// Lofting a part's outlines at several heights into a closed mesh (see row_mesh.hpp).
#include "rowloc/mapping/row_mesh.hpp"

#include "rowloc/geometry/row_map.hpp"
#include "rowloc/mapping/polyline_simplification.hpp"

#include <algorithm>
#include <cmath>
#include <stdexcept>

namespace rowloc::mapping {
namespace {

/// > 0 for a counter-clockwise ring (geometry::OutlineSignedArea, Boost.Geometry).
double SignedArea(const std::vector<Eigen::Vector2d>& ring) {
  return geometry::OutlineSignedArea(geometry::Row{"", ring, true, 0.0});
}

std::size_t NearestVertex(const std::vector<Eigen::Vector2d>& ring, const Eigen::Vector2d& to) {
  std::size_t best = 0;
  for (std::size_t i = 1; i < ring.size(); ++i) {
    if ((ring[i] - to).squaredNorm() < (ring[best] - to).squaredNorm()) best = i;
  }
  return best;
}

}  // namespace

double RingPerimeter(const std::vector<Eigen::Vector2d>& ring_m) {
  double length = 0.0;
  for (std::size_t i = 0; i < ring_m.size(); ++i) length += (ring_m[(i + 1) % ring_m.size()] - ring_m[i]).norm();
  return length;
}

std::vector<Eigen::Vector2d> ResampleRing(const std::vector<Eigen::Vector2d>& ring_m, std::size_t start,
                                          std::size_t count) {
  if (ring_m.size() < 3 || count < 3 || start >= ring_m.size()) {
    throw std::invalid_argument("ResampleRing: need a ring of >= 3 points, count >= 3 and a start inside it");
  }
  const double perimeter = RingPerimeter(ring_m);
  if (!(perimeter > 0.0) || !std::isfinite(perimeter)) throw std::invalid_argument("ResampleRing: zero perimeter");
  std::vector<Eigen::Vector2d> out;
  out.reserve(count);
  const double step = perimeter / static_cast<double>(count);
  std::size_t edge = 0;        // edges walked from `start`
  double edge_start_s = 0.0;   // arc length at the edge's first vertex
  for (std::size_t k = 0; k < count; ++k) {
    const double s = step * static_cast<double>(k);
    for (;;) {
      const Eigen::Vector2d& a = ring_m[(start + edge) % ring_m.size()];
      const Eigen::Vector2d& b = ring_m[(start + edge + 1) % ring_m.size()];
      const double length = (b - a).norm();
      if (s <= edge_start_s + length || edge + 1 >= ring_m.size()) {
        const double t = length > 0.0 ? std::clamp((s - edge_start_s) / length, 0.0, 1.0) : 0.0;
        out.push_back(a + t * (b - a));
        break;
      }
      edge_start_s += length;
      ++edge;
    }
  }
  return out;
}

namespace {

double PolylineLength(const std::vector<Eigen::Vector2d>& line) {
  double length = 0.0;
  for (std::size_t i = 1; i < line.size(); ++i) length += (line[i] - line[i - 1]).norm();
  return length;
}

/// An open polyline resampled to `count` >= 2 points equally spaced by arc length, ends included.
std::vector<Eigen::Vector2d> ResamplePolyline(const std::vector<Eigen::Vector2d>& line, std::size_t count) {
  const double length = PolylineLength(line);
  std::vector<Eigen::Vector2d> out;
  std::size_t segment = 0;
  double segment_start_s = 0.0;
  for (std::size_t k = 0; k < count; ++k) {
    const double s = length * static_cast<double>(k) / static_cast<double>(count - 1);
    while (segment + 2 < line.size() && s > segment_start_s + (line[segment + 1] - line[segment]).norm()) {
      segment_start_s += (line[segment + 1] - line[segment]).norm();
      ++segment;
    }
    const Eigen::Vector2d& a = line[segment];
    const Eigen::Vector2d& b = line[std::min(segment + 1, line.size() - 1)];
    const double l = (b - a).norm();
    out.push_back(l > 0.0 ? Eigen::Vector2d(a + std::clamp((s - segment_start_s) / l, 0.0, 1.0) * (b - a)) : a);
  }
  out.back() = line.back();
  return out;
}

/// kTwoEdges: both edges of every ring resampled corner to corner; nullopt if a ring is not made so.
std::optional<std::vector<std::vector<Eigen::Vector2d>>> ResampleTwoEdges(const std::vector<OutlineAtHeight>& rings,
                                                                         double spacing_m) {
  double longest = 0.0;
  for (const OutlineAtHeight& level : rings) {
    const std::vector<Eigen::Vector2d>& ring = level.ring_m;
    if (ring.size() % 2 != 0 || ring.size() < 4 || SignedArea(ring) <= 0.0) return std::nullopt;
    const auto half = static_cast<std::ptrdiff_t>(ring.size() / 2);
    longest = std::max({longest, PolylineLength({ring.begin(), ring.begin() + half}),
                        PolylineLength({ring.begin() + half, ring.end()})});
  }
  const auto count = static_cast<std::size_t>(std::max(2.0, std::ceil(longest / spacing_m) + 1.0));
  std::vector<std::vector<Eigen::Vector2d>> out;
  for (const OutlineAtHeight& level : rings) {
    std::vector<Eigen::Vector2d> source = level.ring_m;
    const auto half = static_cast<std::ptrdiff_t>(source.size() / 2);
    // An outline traced along the opposite direction starts at the other corner: its halves are
    // swapped (the ring rotated by half), which would twist the loft.
    if (!out.empty() && (source[static_cast<std::size_t>(half)] - out.back().front()).squaredNorm() <
                            (source.front() - out.back().front()).squaredNorm()) {
      std::rotate(source.begin(), source.begin() + half, source.end());
    }
    std::vector<Eigen::Vector2d> ring = ResamplePolyline({source.begin(), source.begin() + half}, count);
    const std::vector<Eigen::Vector2d> left = ResamplePolyline({source.begin() + half, source.end()}, count);
    ring.insert(ring.end(), left.begin(), left.end());
    out.push_back(std::move(ring));
  }
  return out;
}

}  // namespace

std::optional<TriangleMesh> LoftRings(const std::vector<OutlineAtHeight>& rings, double vertex_spacing_m,
                                      RingSampling sampling) {
  if (!(vertex_spacing_m > 0.0) || !std::isfinite(vertex_spacing_m)) {
    throw std::invalid_argument("LoftRings: vertex_spacing_m must be positive");
  }
  if (rings.size() < 2) throw std::invalid_argument("LoftRings: need at least two rings");
  double longest = 0.0;
  for (std::size_t k = 0; k < rings.size(); ++k) {
    if (!std::isfinite(rings[k].height_m) || (k > 0 && !(rings[k].height_m > rings[k - 1].height_m))) {
      throw std::invalid_argument("LoftRings: heights must be finite and strictly increasing");
    }
    if (rings[k].ring_m.size() < 3) throw std::invalid_argument("LoftRings: a ring has fewer than 3 vertices");
    for (const auto& p : rings[k].ring_m) {
      if (!p.allFinite()) throw std::invalid_argument("LoftRings: non-finite vertex");
    }
    longest = std::max(longest, RingPerimeter(rings[k].ring_m));
  }
  std::vector<std::vector<Eigen::Vector2d>> resampled;
  if (sampling == RingSampling::kTwoEdges) {
    auto edges = ResampleTwoEdges(rings, vertex_spacing_m);
    if (!edges) return std::nullopt;
    resampled = std::move(*edges);
  } else {
    const auto points = static_cast<std::size_t>(std::max(8.0, std::ceil(longest / vertex_spacing_m)));
    for (const OutlineAtHeight& level : rings) {
      std::vector<Eigen::Vector2d> ring = level.ring_m;
      if (SignedArea(ring) < 0.0) std::reverse(ring.begin(), ring.end());
      const std::size_t start = resampled.empty() ? 0 : NearestVertex(ring, resampled.back().front());
      resampled.push_back(ResampleRing(ring, start, points));
    }
  }
  const std::size_t count = resampled.front().size();
  const std::vector<std::array<int, 3>> bottom = TriangulatePolygon(resampled.front());
  const std::vector<std::array<int, 3>> top = TriangulatePolygon(resampled.back());
  if (bottom.empty() || top.empty()) return std::nullopt;

  TriangleMesh mesh;
  for (std::size_t k = 0; k < rings.size(); ++k) {
    for (const auto& p : resampled[k]) mesh.vertices_m.emplace_back(p.x(), p.y(), rings[k].height_m);
  }
  const auto index = [count](std::size_t ring, std::size_t i) { return static_cast<int>(ring * count + i % count); };
  for (std::size_t k = 0; k + 1 < rings.size(); ++k) {
    for (std::size_t i = 0; i < count; ++i) {
      // Ring k runs counter-clockwise seen from above: (a, b, c) and (a, c, d) face outward.
      const int a = index(k, i);
      const int b = index(k, i + 1);
      const int c = index(k + 1, i + 1);
      const int d = index(k + 1, i);
      mesh.triangles.push_back({a, b, c});
      mesh.triangles.push_back({a, c, d});
    }
  }
  const int top_offset = index(rings.size() - 1, 0);
  for (const auto& t : bottom) mesh.triangles.push_back({t[0], t[2], t[1]});  // facing down
  for (const auto& t : top) mesh.triangles.push_back({t[0] + top_offset, t[1] + top_offset, t[2] + top_offset});
  return mesh;
}

}  // namespace rowloc::mapping
