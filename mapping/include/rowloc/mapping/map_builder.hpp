// `rowloc map build` (issue 27; docs/mapping.md): survey point cloud -> georeferenced row map, the whole
// pipeline and its outputs.
//
//   read in chunks into tiles (tiled_cloud.hpp) -> per tile: clean (cloud_cleaning.hpp), terrain
//   (terrain_grid.hpp), normalize + band (tile_processing.hpp) -> rows (row_segmentation.hpp) ->
//   outline per part (row_outline.hpp) -> simplify (polyline_simplification.hpp) -> mesh per part
//   (part_meshes.hpp) -> write
//
// Georeferencing. The cloud is either in local ENU metres around a stated WGS84 origin
// (Georeference::Local), or in UTM metres of a zone (Georeference::Utm, "EPSG:326zz" north,
// "EPSG:327zz" south). Coordinates are read in double; the pipeline works relative to an offset
// (the floor of the cloud's minimum x and y), so float steps (PCL's outlier filter) see small
// numbers. UTM outlines are converted vertex by vertex, UTM -> WGS84 (GeographicLib::UTMUPS) ->
// local ENU of the map origin (mapio::LocalFrame), the origin being the centre of the cloud's
// extent at the median terrain height; no UTM grid convergence or scale error enters the map.
//
// Outputs in the output directory:
//   row-map.geojson  the map (mapio::WriteRowMapGeoJson); not written when no rows are found;
//   dtm.json         the terrain grid, in the cloud's own coordinates;
//   report.txt, report.json  rows and parts, points and time per stage, data reduction;
//   map.svg          top view of the outlines over a sample of the cleaned cloud;
//   meshes.ply       a lofted mesh per row part (part_meshes.hpp), map frame; not written without
//                    mesh levels (MeshParams::levels 0) or parts;
//   canopy.bt        optional (MapBuildRequest::octomap_resolution_m): an OctoMap of the cleaned
//                    points more than terrain.ground_tolerance_m above the terrain, in the map's
//                    ENU frame (z relative to the origin's altitude), for CanopyOccupancyMap.
#pragma once

#include "rowloc/geometry/row_map.hpp"
#include "rowloc/mapping/map_build_config.hpp"
#include "rowloc/mapping/point_cloud.hpp"
#include "rowloc/mapping/terrain_grid.hpp"
#include "rowloc/mapping/tile_processing.hpp"
#include "rowloc/mapping/tiled_cloud.hpp"
#include "rowloc/mapping/triangle_mesh.hpp"

#include <Eigen/Core>

#include <cstdint>
#include <filesystem>
#include <optional>
#include <string>
#include <string_view>
#include <vector>

namespace rowloc::mapping {

/// How the cloud's coordinates relate to WGS84.
struct Georeference {
  enum class Kind { kLocal, kUtm };
  Kind kind = Kind::kLocal;
  geometry::GeoOrigin origin;  ///< kLocal: the origin of the cloud's ENU frame
  int utm_zone = 0;            ///< kUtm: 1..60
  bool utm_north = true;       ///< kUtm: hemisphere

  static Georeference Local(const geometry::GeoOrigin& origin);
  /// "EPSG:326zz" (UTM zone zz north) or "EPSG:327zz" (south), zz in 01..60. Throws
  /// std::invalid_argument naming the text otherwise.
  static Georeference FromCrs(std::string_view crs);
  /// "local ENU at 45.07030000 N, 7.68690000 E, 240.000 m" or "EPSG:32632 (UTM 32N)".
  std::string Describe() const;
};

struct StageReport {
  std::string name;
  std::size_t points = 0;  ///< points (or cells, vertices: see `unit`) after the stage
  std::string unit = "points";
  double seconds = 0.0;
};

struct PartReport {
  std::string id;
  std::size_t points = 0;          ///< band points of the part
  double length_m = 0.0;           ///< along its centre line
  std::size_t traced_vertices = 0; ///< before simplification
  std::size_t vertices = 0;        ///< in the map
  bool simplified = false;         ///< false: CGAL refused (not simple) or tolerance 0
  bool one_sided = false;          ///< seen from one side: the hidden face from the canopy top (row_outline.hpp)
  double width_m = 0.0;            ///< median width of its outline at h_ref
  double width_spread_m = 0.0;     ///< one-sided: spread of the width over its stations (IQR / 1.349)
  double outline_sigma_m = 0.0;    ///< the outline's estimated accuracy across it, written to the map
  int mesh_levels = 0;             ///< outlines lofted into its mesh (0: no mesh)
  std::size_t mesh_triangles = 0;
  std::optional<double> mesh_slice_max_m;  ///< its mesh cut at h_ref against its outline, largest distance
};

struct MapBuildResult {
  std::optional<geometry::RowMap> map;  ///< nullopt: no rows found
  std::size_t rows = 0;                 ///< rows (chains of parts)
  std::vector<PartReport> parts;        ///< one per map row (part), in map order
  std::vector<StageReport> stages;
  std::optional<TerrainGrid> terrain;   ///< in cloud coordinates minus offset_m
  Eigen::Vector2d offset_m = Eigen::Vector2d::Zero();  ///< subtracted from the cloud's x, y
  std::size_t points_in = 0;
  std::size_t band_points = 0;
  std::size_t parts_dropped = 0;
  std::size_t links = 0;
  std::size_t outlines_failed = 0;      ///< parts without a usable outline (skipped)
  std::size_t one_sided_parts = 0;      ///< parts in the map traced from one face and the canopy top
  std::size_t tiles = 0;                ///< tiles processed (steps 1-3)
  int tile_threads = 1;                 ///< threads of the outlier removal
  std::size_t largest_tile_points = 0;  ///< points of the largest tile, overlap included
  double wall_seconds = 0.0;            ///< RunMapBuild: the whole run, wall clock
  std::vector<Eigen::Vector2d> cloud_sample_m;  ///< cleaned cloud sample in the map frame (SVG)
  std::vector<double> cloud_sample_height_m;    ///< their heights above the terrain
  PointCloud canopy_m;  ///< with keep_canopy: the cleaned points above the ground, map frame
  TriangleMesh meshes;  ///< every part's mesh, map frame (z relative to the map origin's altitude for UTM)
  std::string message;                  ///< "7 rows (9 parts)" or "no rows found: ..."
};

/// Runs the pipeline on a cloud. Throws std::invalid_argument for an empty cloud or an invalid
/// configuration, and for UTM coordinates outside the zone's valid range. keep_canopy fills
/// MapBuildResult::canopy_m.
MapBuildResult BuildRowMap(const PointCloud& cloud, const MapBuildConfig& config,
                           const Georeference& georeference, bool keep_canopy = false);

/// The same on a tiled cloud (in memory or spilled to disk); its tiles are released as they are
/// processed. progress, if set, is called per batch of tiles ("tiles", done, total).
MapBuildResult BuildRowMap(TiledCloud& cloud, const MapBuildConfig& config, const Georeference& georeference,
                           bool keep_canopy = false, const ProgressCallback& progress = {});

struct MapBuildRequest {
  std::filesystem::path survey_path;
  std::filesystem::path output_dir;
  Georeference georeference;
  MapBuildConfig config;
  std::string config_source = "built-in defaults";  ///< for the report
  std::optional<double> octomap_resolution_m;        ///< set: also write canopy.bt at this voxel size
  ProgressCallback progress;  ///< optional: ("read", points, 0) per chunk read, ("tiles", done, total)
};

/// Reads the survey in chunks into tiles spilled to output_dir/.rowloc-tiles (removed at the end),
/// builds the map and writes every output (creating output_dir). Peak memory: the reader's (a
/// chunk for LAS, the whole cloud for PLY/PCD, which PCL reads whole) or, after reading, `threads`
/// tiles plus the merged products (tile_processing.hpp). Throws PointCloudError on problems with
/// the survey. Returns the result; the report's read and write stages are included.
MapBuildResult RunMapBuild(const MapBuildRequest& request);

/// The SVG top view (plain SVG text): outlines over the cloud sample, coloured by height.
std::string FormatMapSvg(const MapBuildResult& result);

}  // namespace rowloc::mapping
