// Indexed triangle meshes in local metres (map build step 5: the per-row low-complexity canopy mesh),
// their validation, and two closed test meshes (a box and a vertical n-sided prism standing in for
// a cylinder) used as fixtures and as row-canopy stand-ins.
//
// Orientation: every triangle (a, b, c) of the generated meshes is counter-clockwise seen from
// outside, so the outward normal is (b - a) x (c - a) and the signed volume
// sum_t a . (b x c) / 6 (divergence theorem) equals the enclosed volume.
#pragma once

#include <Eigen/Core>

#include <array>
#include <optional>
#include <stdexcept>
#include <string>
#include <vector>

namespace rowloc::mapping {

struct TriangleMesh {
  std::vector<Eigen::Vector3d> vertices_m;   ///< vertex positions, metres
  std::vector<std::array<int, 3>> triangles;  ///< vertex indices, counter-clockwise from outside
};

/// A mesh is not usable for the operation asked (see ValidateTriangleMesh, SliceMesh).
class InvalidMeshError : public std::invalid_argument {
 public:
  using std::invalid_argument::invalid_argument;
};

/// Why a mesh is not valid; empty if it is. Checks: at least one triangle; finite vertices; every
/// index in [0, vertex count); no degenerate triangle, i.e. no repeated index and
/// |(b - a) x (c - a)| > 1e-12 * (longest edge)^2 (zero-area and needle triangles).
/// Does not check manifoldness or orientation (SliceMesh does, through CGAL).
std::optional<std::string> ValidateTriangleMesh(const TriangleMesh& mesh);

/// Closed box [min_m, max_m]: 8 vertices, 12 triangles, outward orientation.
/// Throws std::invalid_argument unless the corners are finite and min_m < max_m on every axis.
TriangleMesh MakeBoxMesh(const Eigen::Vector3d& min_m, const Eigen::Vector3d& max_m);

/// Closed vertical prism inscribed in the cylinder of axis +z through base_center_m: `sides`
/// vertices on the base circle (the first at angle 0 from +x) and the same on the top circle,
/// plus one centre vertex per cap (caps are triangle fans around it): 2 n + 2 vertices and 4 n
/// triangles for n = sides, outward orientation. Its horizontal section is the inscribed regular n-gon,
/// of area (n/2) r^2 sin(2 pi / n).
/// Throws std::invalid_argument unless the centre is finite, radius_m > 0, height_m > 0 (finite)
/// and sides >= 3.
TriangleMesh MakeCylinderMesh(const Eigen::Vector3d& base_center_m, double radius_m, double height_m,
                              int sides);

}  // namespace rowloc::mapping
