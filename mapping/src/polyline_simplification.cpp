// Outline simplification with CGAL::Polyline_simplification_2 (see polyline_simplification.hpp).
// A CGAL translation unit (slow to compile, ~35 s and 1.5 GB): keep it small.
#include "rowloc/mapping/polyline_simplification.hpp"

#include <CGAL/Constrained_Delaunay_triangulation_2.h>
#include <CGAL/Exact_predicates_inexact_constructions_kernel.h>
#include <CGAL/Polygon_2.h>
#include <CGAL/Triangulation_face_base_with_info_2.h>
#include <CGAL/Triangulation_vertex_base_with_info_2.h>
#include <CGAL/Polyline_simplification_2/Squared_distance_cost.h>
#include <CGAL/Polyline_simplification_2/Stop_above_cost_threshold.h>
#include <CGAL/Polyline_simplification_2/simplify.h>

#include <cmath>
#include <list>
#include <stdexcept>

namespace rowloc::mapping {
namespace {

using Kernel = CGAL::Exact_predicates_inexact_constructions_kernel;
using Polygon = CGAL::Polygon_2<Kernel>;
namespace PS = CGAL::Polyline_simplification_2;

// Polygon triangulation: a constrained Delaunay triangulation of the polygon's edges whose faces
// are marked inside or outside by their nesting level (the number of constraints crossed from the
// infinite face), as in CGAL's "Triangulating a Polygonal Domain" (2D Triangulations manual).
struct FaceInfo {
  int nesting_level = -1;
};
using TriangulationVertex = CGAL::Triangulation_vertex_base_with_info_2<int, Kernel>;
using TriangulationFaceBase = CGAL::Triangulation_face_base_with_info_2<FaceInfo, Kernel>;
using TriangulationFace = CGAL::Constrained_triangulation_face_base_2<Kernel, TriangulationFaceBase>;
using TriangulationData = CGAL::Triangulation_data_structure_2<TriangulationVertex, TriangulationFace>;
using Cdt = CGAL::Constrained_Delaunay_triangulation_2<Kernel, TriangulationData, CGAL::Exact_predicates_tag>;

void MarkDomain(Cdt& cdt, Cdt::Face_handle start, int level, std::list<Cdt::Edge>& border) {
  if (start->info().nesting_level != -1) return;
  std::list<Cdt::Face_handle> queue{start};
  while (!queue.empty()) {
    const Cdt::Face_handle face = queue.front();
    queue.pop_front();
    if (face->info().nesting_level != -1) continue;
    face->info().nesting_level = level;
    for (int i = 0; i < 3; ++i) {
      const Cdt::Edge edge(face, i);
      const Cdt::Face_handle next = face->neighbor(i);
      if (next->info().nesting_level != -1) continue;
      if (cdt.is_constrained(edge)) {
        border.push_back(edge);
      } else {
        queue.push_back(next);
      }
    }
  }
}

void MarkDomains(Cdt& cdt) {
  std::list<Cdt::Edge> border;
  MarkDomain(cdt, cdt.infinite_face(), 0, border);
  while (!border.empty()) {
    const Cdt::Edge edge = border.front();
    border.pop_front();
    const Cdt::Face_handle next = edge.first->neighbor(edge.second);
    if (next->info().nesting_level == -1) MarkDomain(cdt, next, edge.first->info().nesting_level + 1, border);
  }
}

}  // namespace

std::vector<std::array<int, 3>> TriangulatePolygon(const std::vector<Eigen::Vector2d>& polygon_m) {
  for (const auto& p : polygon_m) {
    if (!p.allFinite()) throw std::invalid_argument("TriangulatePolygon: non-finite point");
  }
  std::vector<std::array<int, 3>> triangles;
  if (polygon_m.size() < 3) return triangles;
  Polygon polygon;
  for (const auto& p : polygon_m) polygon.push_back(Kernel::Point_2(p.x(), p.y()));
  if (!polygon.is_simple()) return triangles;
  Cdt cdt;
  std::vector<Cdt::Vertex_handle> vertices;
  for (std::size_t i = 0; i < polygon_m.size(); ++i) {
    vertices.push_back(cdt.insert(Kernel::Point_2(polygon_m[i].x(), polygon_m[i].y())));
    vertices.back()->info() = static_cast<int>(i);
  }
  for (std::size_t i = 0; i < vertices.size(); ++i) {
    cdt.insert_constraint(vertices[i], vertices[(i + 1) % vertices.size()]);
  }
  MarkDomains(cdt);
  for (auto face = cdt.finite_faces_begin(); face != cdt.finite_faces_end(); ++face) {
    if (face->info().nesting_level % 2 != 1) continue;  // outside the polygon
    // CGAL's faces run counter-clockwise.
    triangles.push_back({face->vertex(0)->info(), face->vertex(1)->info(), face->vertex(2)->info()});
  }
  return triangles;
}

SimplifiedPolygon SimplifyPolygon(const std::vector<Eigen::Vector2d>& polygon_m, double tolerance_m) {
  if (!(tolerance_m >= 0.0) || !std::isfinite(tolerance_m)) {
    throw std::invalid_argument("SimplifyPolygon: tolerance must be finite and >= 0");
  }
  for (const auto& p : polygon_m) {
    if (!p.allFinite()) throw std::invalid_argument("SimplifyPolygon: non-finite point");
  }
  SimplifiedPolygon result{polygon_m, false};
  if (tolerance_m == 0.0 || polygon_m.size() < 4) return result;
  Polygon polygon;
  for (const auto& p : polygon_m) polygon.push_back(Kernel::Point_2(p.x(), p.y()));
  // The constrained triangulation refuses intersecting constraints (exact predicates tag).
  if (!polygon.is_simple()) return result;
  const Polygon simple = PS::simplify(polygon, PS::Squared_distance_cost(),
                                      PS::Stop_above_cost_threshold(tolerance_m * tolerance_m));
  result.points_m.clear();
  for (auto it = simple.vertices_begin(); it != simple.vertices_end(); ++it) {
    result.points_m.emplace_back(CGAL::to_double(it->x()), CGAL::to_double(it->y()));
  }
  result.simplified = true;
  return result;
}

}  // namespace rowloc::mapping
