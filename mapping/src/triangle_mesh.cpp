// Triangle mesh validation and closed test meshes (see triangle_mesh.hpp).
#include "rowloc/mapping/triangle_mesh.hpp"

#include <Eigen/Geometry>

#include <algorithm>
#include <cmath>
#include <limits>
#include <numbers>

namespace rowloc::mapping {
namespace {

/// Relative area threshold below which a triangle counts as degenerate (see header).
constexpr double kDegenerateRelativeArea = 1e-12;

std::optional<std::string> TriangleProblem(const TriangleMesh& mesh, std::size_t t) {
  const std::array<int, 3>& tri = mesh.triangles[t];
  const int vertex_count = static_cast<int>(mesh.vertices_m.size());
  for (int index : tri) {
    if (index < 0 || index >= vertex_count) {
      return "triangle " + std::to_string(t) + " has vertex index " + std::to_string(index) +
             " out of range [0, " + std::to_string(vertex_count) + ")";
    }
  }
  if (tri[0] == tri[1] || tri[1] == tri[2] || tri[0] == tri[2]) {
    return "triangle " + std::to_string(t) + " repeats a vertex index";
  }
  const Eigen::Vector3d& a = mesh.vertices_m[static_cast<std::size_t>(tri[0])];
  const Eigen::Vector3d& b = mesh.vertices_m[static_cast<std::size_t>(tri[1])];
  const Eigen::Vector3d& c = mesh.vertices_m[static_cast<std::size_t>(tri[2])];
  const double longest_sq =
      std::max({(b - a).squaredNorm(), (c - b).squaredNorm(), (a - c).squaredNorm()});
  if ((b - a).cross(c - a).norm() <= kDegenerateRelativeArea * longest_sq) {
    return "triangle " + std::to_string(t) + " is degenerate (zero area or collinear vertices)";
  }
  return std::nullopt;
}

}  // namespace

std::optional<std::string> ValidateTriangleMesh(const TriangleMesh& mesh) {
  if (mesh.triangles.empty()) return "the mesh has no triangles";
  if (mesh.vertices_m.size() > static_cast<std::size_t>(std::numeric_limits<int>::max())) {
    return "too many vertices for int indices";
  }
  for (std::size_t v = 0; v < mesh.vertices_m.size(); ++v) {
    if (!mesh.vertices_m[v].allFinite()) return "vertex " + std::to_string(v) + " is not finite";
  }
  for (std::size_t t = 0; t < mesh.triangles.size(); ++t) {
    if (auto problem = TriangleProblem(mesh, t)) return problem;
  }
  return std::nullopt;
}

TriangleMesh MakeBoxMesh(const Eigen::Vector3d& min_m, const Eigen::Vector3d& max_m) {
  if (!min_m.allFinite() || !max_m.allFinite() || !(min_m.array() < max_m.array()).all()) {
    throw std::invalid_argument("MakeBoxMesh: corners must be finite with min_m < max_m per axis");
  }
  TriangleMesh mesh;
  // Vertex v has x from bit 0, y from bit 1, z from bit 2 (0: min, 1: max).
  for (int v = 0; v < 8; ++v) {
    mesh.vertices_m.emplace_back((v & 1) ? max_m.x() : min_m.x(), (v & 2) ? max_m.y() : min_m.y(),
                                 (v & 4) ? max_m.z() : min_m.z());
  }
  // Each face as a quad counter-clockwise seen from outside, split along its first diagonal.
  const std::array<std::array<int, 4>, 6> quads = {{
      {0, 2, 3, 1},  // z = min (normal -z)
      {4, 5, 7, 6},  // z = max (+z)
      {0, 1, 5, 4},  // y = min (-y)
      {2, 6, 7, 3},  // y = max (+y)
      {0, 4, 6, 2},  // x = min (-x)
      {1, 3, 7, 5},  // x = max (+x)
  }};
  for (const auto& q : quads) {
    mesh.triangles.push_back({q[0], q[1], q[2]});
    mesh.triangles.push_back({q[0], q[2], q[3]});
  }
  return mesh;
}

TriangleMesh MakeCylinderMesh(const Eigen::Vector3d& base_center_m, double radius_m, double height_m,
                              int sides) {
  if (!base_center_m.allFinite() || !(radius_m > 0.0) || !std::isfinite(radius_m) ||
      !(height_m > 0.0) || !std::isfinite(height_m) || sides < 3) {
    throw std::invalid_argument(
        "MakeCylinderMesh: need a finite centre, finite radius_m > 0, height_m > 0 and sides >= 3");
  }
  TriangleMesh mesh;
  const Eigen::Vector3d up(0.0, 0.0, height_m);
  // Vertices: base ring 0..n-1, top ring n..2n-1, base centre 2n, top centre 2n+1.
  for (int ring = 0; ring < 2; ++ring) {
    for (int i = 0; i < sides; ++i) {
      const double angle = 2.0 * std::numbers::pi * i / sides;
      mesh.vertices_m.push_back(base_center_m + static_cast<double>(ring) * up +
                                radius_m * Eigen::Vector3d(std::cos(angle), std::sin(angle), 0.0));
    }
  }
  mesh.vertices_m.push_back(base_center_m);
  mesh.vertices_m.push_back(base_center_m + up);
  const int base_centre = 2 * sides;
  const int top_centre = 2 * sides + 1;
  for (int i = 0; i < sides; ++i) {
    const int j = (i + 1) % sides;
    mesh.triangles.push_back({i, j, sides + j});           // side, lower-right half
    mesh.triangles.push_back({i, sides + j, sides + i});   // side, upper-left half
    mesh.triangles.push_back({base_centre, j, i});         // base cap, normal -z
    mesh.triangles.push_back({top_centre, sides + i, sides + j});  // top cap, normal +z
  }
  return mesh;
}

}  // namespace rowloc::mapping
