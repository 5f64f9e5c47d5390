// Planar mesh slices through CGAL::Polygon_mesh_slicer (see mesh_slicer.hpp). This is the only
// translation unit of rowloc that includes CGAL: it is slow to compile.
#include "rowloc/mapping/mesh_slicer.hpp"

#include <CGAL/Exact_predicates_inexact_constructions_kernel.h>
#include <CGAL/Polygon_mesh_slicer.h>
#include <CGAL/Surface_mesh.h>
#include <CGAL/boost/graph/helpers.h>

#include <array>
#include <cmath>
#include <iterator>
#include <string>
#include <vector>

namespace rowloc::mapping {
namespace {

using Kernel = CGAL::Exact_predicates_inexact_constructions_kernel;
using Point = Kernel::Point_3;
using Mesh = CGAL::Surface_mesh<Point>;
using Slicer = CGAL::Polygon_mesh_slicer<Mesh, Kernel>;

/// Builds the halfedge surface; Surface_mesh::add_face refuses a face that would make the surface
/// non-manifold or inconsistently oriented, which is reported here.
Mesh ToSurfaceMesh(const TriangleMesh& mesh) {
  Mesh surface;
  std::vector<Mesh::Vertex_index> vertex_ids;
  vertex_ids.reserve(mesh.vertices_m.size());
  for (const Eigen::Vector3d& v : mesh.vertices_m) {
    vertex_ids.push_back(surface.add_vertex(Point(v.x(), v.y(), v.z())));
  }
  for (std::size_t t = 0; t < mesh.triangles.size(); ++t) {
    const std::array<int, 3>& tri = mesh.triangles[t];
    const Mesh::Face_index face =
        surface.add_face(vertex_ids[static_cast<std::size_t>(tri[0])],
                         vertex_ids[static_cast<std::size_t>(tri[1])],
                         vertex_ids[static_cast<std::size_t>(tri[2])]);
    if (face == Mesh::null_face()) {
      throw InvalidMeshError("SliceMesh: triangle " + std::to_string(t) +
                             " makes the surface non-manifold or inconsistently oriented "
                             "(an edge used by more than two triangles, or twice in one direction)");
    }
  }
  if (!CGAL::is_triangle_mesh(surface)) {
    throw InvalidMeshError("SliceMesh: CGAL does not accept the surface as a triangle mesh");
  }
  return surface;
}

Polyline3 ToPolyline(const std::vector<Point>& points) {
  Polyline3 polyline;
  polyline.closed = points.size() >= 3 && points.front() == points.back();
  const std::size_t kept = polyline.closed ? points.size() - 1 : points.size();
  polyline.points_m.reserve(kept);
  for (std::size_t i = 0; i < kept; ++i) {
    polyline.points_m.emplace_back(points[i].x(), points[i].y(), points[i].z());
  }
  return polyline;
}

}  // namespace

std::vector<Polyline3> SliceMesh(const TriangleMesh& mesh, const Eigen::Vector3d& plane_normal,
                                 double plane_offset_m) {
  if (!plane_normal.allFinite() || plane_normal.isZero(0.0) || !std::isfinite(plane_offset_m)) {
    throw std::invalid_argument("SliceMesh: the plane normal must be finite and non-zero and the "
                                "offset finite");
  }
  if (auto problem = ValidateTriangleMesh(mesh)) throw InvalidMeshError("SliceMesh: " + *problem);
  const Mesh surface = ToSurfaceMesh(mesh);
  const Slicer slicer(surface);
  // CGAL's Plane_3(a, b, c, d) is a x + b y + c z + d = 0, i.e. n^T x = offset with d = -offset.
  const Kernel::Plane_3 plane(plane_normal.x(), plane_normal.y(), plane_normal.z(), -plane_offset_m);
  std::vector<std::vector<Point>> cgal_polylines;
  slicer(plane, std::back_inserter(cgal_polylines));
  std::vector<Polyline3> polylines;
  polylines.reserve(cgal_polylines.size());
  for (const std::vector<Point>& points : cgal_polylines) polylines.push_back(ToPolyline(points));
  return polylines;
}

}  // namespace rowloc::mapping
