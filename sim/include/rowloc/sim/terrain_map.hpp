// TerrainMap: which terrain class lies under a point of the world (issue 3, "Terrain patches with
// their own slip behaviour"; the design's "terrain-dependent slip"). Documented in
// docs/simulation-routes.md ("Terrain map").
//
// Patches are simple polygons in world ENU metres (Boost.Geometry polygons internally). A point
// belongs to a patch if it lies inside it or on its boundary (boost::geometry::covered_by); where
// patches overlap, the LAST listed patch containing the point wins; elsewhere the default class.
// Validation: >= 3 finite vertices (a repeated closing vertex is dropped), and the polygon must be
// valid for boost::geometry::is_valid after orientation correction (no self-intersection, no
// spikes, non-zero area). Either orientation is accepted.
#pragma once

#include "rowloc/sim/terrain.hpp"

#include <Eigen/Core>

#include <memory>
#include <string_view>
#include <vector>

namespace rowloc::sim {

struct TerrainPatch {
  TerrainClass terrain = TerrainClass::kTiles;
  std::vector<Eigen::Vector2d> polygon_m;  ///< >= 3 vertices, simple polygon, not repeated at the end
};

class TerrainMap {
 public:
  /// Tiles everywhere (not explicit, so that aggregates holding a TerrainMap can be value-initialized).
  TerrainMap();
  /// Throws std::invalid_argument naming the patch ("patches[i]") and the problem.
  explicit TerrainMap(TerrainClass default_terrain, std::vector<TerrainPatch> patches = {});

  /// The class under the point. Throws std::invalid_argument on a non-finite point.
  TerrainClass ClassAt(const Eigen::Vector2d& point_m) const;

  TerrainClass default_terrain() const { return default_terrain_; }
  /// The patches as given (closing vertex removed).
  const std::vector<TerrainPatch>& patches() const { return patches_; }

 private:
  struct Index;  // Boost.Geometry polygons and their bounding boxes (immutable, shared by copies)
  TerrainClass default_terrain_;
  std::vector<TerrainPatch> patches_;
  std::shared_ptr<const Index> index_;
};

/// Parses {"default": "<class>", "patches": [{"terrain": "<class>", "polygon": [[x, y], ...]},
/// {"terrain": "<class>", "rectangle": {"min": [x, y], "max": [x, y]}}, ...]}: every key required
/// (a patch has exactly one of "polygon" and "rectangle"), unknown keys rejected. key_path_prefix
/// starts every key path in errors (e.g. "terrain_map"). Throws TerrainConfigError
/// "<source>: <key path>: <reason>".
TerrainMap ParseTerrainMap(std::string_view json_object_text, std::string_view source_name);
TerrainMap ParseTerrainMap(std::string_view json_object_text, std::string_view source_name,
                           std::string_view key_path_prefix);

}  // namespace rowloc::sim
