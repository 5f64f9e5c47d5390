// Planar slices of a triangle mesh (map build step 6: the row outline at height h_ref), computed by
// CGAL::Polygon_mesh_slicer on a CGAL::Surface_mesh with the Epick kernel (exact predicates,
// inexact constructions; CGAL manual, "Polygon Mesh Processing", section "Slicer").
//
// The plane is {x : n^T x = d}. Each connected component of the intersection is a polyline whose
// points lie on the plane (up to rounding) and on the mesh's edges. A closed component (the slice
// of a closed surface) is returned with closed = true and its first point NOT repeated at the end.
//
// This header exposes Eigen and the standard library only; CGAL stays in mesh_slicer.cpp.
#pragma once

#include "rowloc/mapping/triangle_mesh.hpp"

#include <Eigen/Core>

#include <vector>

namespace rowloc::mapping {

struct Polyline3 {
  std::vector<Eigen::Vector3d> points_m;  ///< vertices, metres; closed: last != first
  bool closed = false;                    ///< true: the last point joins the first
};

/// Slices `mesh` with the plane {x : plane_normal^T x = plane_offset_m}. plane_normal need not be
/// unit (plane_offset_m is then in metres times |plane_normal|). Returns no polyline if the plane
/// misses the mesh.
/// Throws InvalidMeshError if ValidateTriangleMesh fails or CGAL cannot build a manifold,
/// consistently oriented surface from the triangles (the message says which triangle);
/// std::invalid_argument if plane_normal is zero or non-finite or plane_offset_m non-finite.
std::vector<Polyline3> SliceMesh(const TriangleMesh& mesh, const Eigen::Vector3d& plane_normal,
                                 double plane_offset_m);

}  // namespace rowloc::mapping
