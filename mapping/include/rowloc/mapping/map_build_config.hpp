// Parameters of `rowloc map build` (issue 27): one struct per pipeline step, gathered in
// MapBuildConfig and read from a strict JSON file (config/mapping/default.json; docs/mapping.md
// lists every key, its default and its domain).
//
// The file follows the rules of every rowloc configuration file: every key is required, unknown
// keys are rejected, numbers must be finite and inside their domain; errors name the file, the key
// path and the reason ("m.json: rows.max_gap_m: must be in [0, 100], got -1").
#pragma once

#include <filesystem>
#include <optional>
#include <stdexcept>
#include <string>
#include <vector>

namespace rowloc::mapping {

/// Tiling: steps 1-3 run per square tile of the survey (plus an overlap on every side), so that
/// memory is bounded by a tile, not by the survey (docs/mapping.md, "Tiles and memory").
struct TileParams {
  double size_m = 40.0;     ///< edge of a tile's core; every point belongs to exactly one core
  double overlap_m = 3.0;   ///< margin read around each core; >= terrain.classification_radius_m
  int threads = 0;          ///< threads of the outlier removal (per tile); 0: one per hardware thread. Results do not depend on it
};

/// Step 1, clean: voxel downsampling and statistical outlier removal.
struct CleanParams {
  double voxel_size_m = 0.02;        ///< voxel edge; one centroid per occupied voxel. 0: no downsampling
  int outlier_neighbours = 16;       ///< k of the statistical outlier removal; 0: no removal
  double outlier_stddev_factor = 3.0;///< a point is an outlier if its mean k-NN distance > mean + f * stddev
};

/// Step 2, terrain: ground cells of a grid of lowest points, filled and smoothed into a DTM.
struct TerrainParams {
  double cell_size_m = 0.5;          ///< DTM cell edge
  double classification_radius_m = 2.0;  ///< neighbourhood of the robust local plane per cell
  double ground_tolerance_m = 0.15;  ///< a cell is ground if its lowest point is <= plane + this
  double ground_thickness_m = 0.05;  ///< ground height of a cell: median of points <= lowest + this
  int min_ground_points = 3;         ///< a cell's lowest level needs this many points within ground_thickness_m
  int smoothing_passes = 1;          ///< 3x3 mean filter passes over the filled grid
};

/// Step 3, normalize: the canopy band around the reference height above the terrain.
struct CanopyBandParams {
  double reference_height_m = 1.0;   ///< h_ref: height of the map outline above the terrain
  double band_half_width_m = 0.15;   ///< keep points with |h - h_ref| <= this
};

/// Step 4, rows: occupancy raster of the band, connected parts, parts linked into rows.
struct RowParams {
  double raster_cell_m = 0.05;       ///< occupancy raster cell
  double link_radius_m = 0.25;       ///< occupied cells closer than this join one part (dilation)
  int min_part_points = 100;         ///< smaller parts are dropped as clutter
  double min_part_length_m = 0.5;    ///< shorter parts (longest extent) are dropped as clutter
  double max_gap_m = 4.0;            ///< parts whose ends are at most this far apart, aligned, are one row
  double max_link_angle_rad = 0.35;  ///< largest angle between the directions of two linked ends
  double max_link_offset_m = 0.3;    ///< largest lateral offset of a gap from the mean end direction
  double end_window_m = 2.0;         ///< length of a part's end used for its direction
};

/// Steps 5-7, outline: centre line, edges per station, simplification.
struct OutlineParams {
  double centreline_bin_m = 0.5;     ///< bin of the first centre-line estimate along the part's axis
  double station_step_m = 0.05;      ///< edge estimate every this much along the centre line
  double edge_quantile = 0.5;        ///< quantile of the lateral offsets of one side in a station bin
  double end_exclusion_m = 0.1;      ///< points this close to a part's end are left out of the edges
  double min_width_m = 0.1;          ///< narrower outlines (median width) are rejected: a lone face
  double simplify_tolerance_m = 0.01;   ///< CGAL Polyline_simplification_2 tolerance; 0: none
  double one_sided_max_width_m = 2.0;   ///< parts seen from one side: widest canopy; 0: not mapped
  double one_sided_window_m = 1.0;      ///< parts seen from one side: window of each width estimate
};

/// Steps 5-6, mesh route: outlines at `levels` heights from lowest_m to highest_m above the terrain
/// lofted into one mesh per part (row_mesh.hpp), written to meshes.ply.
struct MeshParams {
  int levels = 4;                  ///< outline heights; 0: no meshes; else >= 2
  double lowest_m = 0.6;           ///< height of the lowest outline above the terrain
  double highest_m = 1.6;          ///< height of the highest outline (> lowest_m)
  double vertex_spacing_m = 2.0;   ///< spacing of the rings' vertices along the outline
};

/// The outline heights of the mesh route: levels values from lowest_m to highest_m, equally spaced
/// (none when levels is 0).
std::vector<double> MeshLevelHeights(const MeshParams& mesh);

struct MapBuildConfig {
  TileParams tiles;
  CleanParams clean;
  TerrainParams terrain;
  CanopyBandParams band;
  RowParams rows;
  OutlineParams outline;
  MeshParams mesh;
};

/// A configuration file or value is invalid; what() names the file, the key and the reason.
class MapBuildConfigError : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

/// Why the configuration is invalid ("rows.max_gap_m: must be in [0, 100], got -1"); empty if valid.
std::optional<std::string> ValidateMapBuildConfig(const MapBuildConfig& config);

/// Reads a configuration file: an overlay on the defaults (a section or key left out keeps its
/// default value), no unknown section or key, every value in its domain. Throws MapBuildConfigError.
MapBuildConfig LoadMapBuildConfig(const std::filesystem::path& path);

/// The JSON text of a configuration (the format LoadMapBuildConfig reads).
std::string FormatMapBuildConfig(const MapBuildConfig& config);

}  // namespace rowloc::mapping
