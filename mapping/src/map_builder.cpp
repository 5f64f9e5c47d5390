// The map build pipeline and its outputs (see map_builder.hpp).
#include "rowloc/mapping/map_builder.hpp"

#include "rowloc/mapio/local_frame.hpp"
#include "rowloc/mapio/output_file.hpp"
#include "rowloc/geometry/segment2.hpp"
#include "rowloc/mapio/row_map_geojson.hpp"
#include "rowloc/mapping/canopy_occupancy_map.hpp"
#include "rowloc/mapping/part_meshes.hpp"
#include "rowloc/mapping/polyline_simplification.hpp"
#include "rowloc/mapping/row_outline.hpp"
#include "rowloc/mapping/row_segmentation.hpp"
#include "rowloc/mapping/tile_processing.hpp"
#include "rowloc/mapping/tiled_cloud.hpp"

#include <GeographicLib/UTMUPS.hpp>
#include <boost/geometry.hpp>
#include <boost/geometry/index/rtree.hpp>
#include <fmt/format.h>
#include <nlohmann/json.hpp>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <fstream>
#include <limits>
#include <optional>
#include <stdexcept>
#include <string>
#include <system_error>
#include <utility>
#include <vector>

namespace rowloc::mapping {
namespace {

namespace bg = boost::geometry;
namespace bgi = boost::geometry::index;

using Clock = std::chrono::steady_clock;

double SecondsSince(Clock::time_point start) {
  return std::chrono::duration<double>(Clock::now() - start).count();
}

void WriteText(const std::filesystem::path& path, const std::string& text) { mapio::WriteFileAtomically(path, text); }

/// `value` to a multiple of `unit` (a power of ten below 1), divided rather than multiplied by its
/// inverse so that JSON prints the shortest decimal (0.0042, not 0.004200000000000001).
double Round(double value, double unit) {
  const double per_unit = std::round(1.0 / unit);
  return std::round(value * per_unit) / per_unit;
}

/// The canopy top's cells (SurveyProducts::top_m) in an R-tree, for the parts seen from one side.
class TopCells {
 public:
  explicit TopCells(const std::vector<Eigen::Vector2d>& top_m) : top_m_(top_m) {}

  /// The cells within margin_m of the bounding box of `points_m` (built on first use).
  std::vector<Eigen::Vector2d> Near(const std::vector<Eigen::Vector2d>& points_m, double margin_m) {
    if (top_m_.empty() || points_m.empty()) return {};
    if (!tree_) {
      std::vector<std::pair<BoostPoint, std::size_t>> entries;
      entries.reserve(top_m_.size());
      for (std::size_t i = 0; i < top_m_.size(); ++i) entries.emplace_back(BoostPoint(top_m_[i].x(), top_m_[i].y()), i);
      tree_.emplace(entries.begin(), entries.end());  // packing construction
    }
    Eigen::Vector2d lo = points_m.front();
    Eigen::Vector2d hi = lo;
    for (const auto& p : points_m) {
      lo = lo.cwiseMin(p);
      hi = hi.cwiseMax(p);
    }
    const bg::model::box<BoostPoint> box(BoostPoint(lo.x() - margin_m, lo.y() - margin_m),
                                         BoostPoint(hi.x() + margin_m, hi.y() + margin_m));
    std::vector<Eigen::Vector2d> out;
    for (auto it = tree_->qbegin(bgi::intersects(box)); it != tree_->qend(); ++it) out.push_back(top_m_[it->second]);
    return out;
  }

 private:
  using BoostPoint = bg::model::point<double, 2, bg::cs::cartesian>;
  const std::vector<Eigen::Vector2d>& top_m_;
  std::optional<bgi::rtree<std::pair<BoostPoint, std::size_t>, bgi::rstar<16>>> tree_;
};

/// RMS distance of the points from the closed polygon (every segment tried: a part's traced
/// outline has ~20 vertices per metre, its simplified polygon ~1-7).
double RmsDistanceToPolygon(const std::vector<Eigen::Vector2d>& points_m, const std::vector<Eigen::Vector2d>& polygon_m) {
  if (points_m.empty() || polygon_m.size() < 2) return 0.0;
  double sum = 0.0;
  for (const Eigen::Vector2d& p : points_m) {
    double best = std::numeric_limits<double>::infinity();
    for (std::size_t i = 0; i < polygon_m.size(); ++i) {
      best = std::min(best, geometry::Segment2{polygon_m[i], polygon_m[(i + 1) % polygon_m.size()]}.Distance(p));
    }
    sum += best * best;
  }
  return std::sqrt(sum / static_cast<double>(points_m.size()));
}

/// The outline's accuracy across it (geometry::Row::outline_sigma_m), an RMS over the outline: in
/// quadrature, what the simplification moved the traced outline by (RMS), the noise of the traced
/// edges (roughness and sampling the outline cannot follow) and, seen from one side, the width
/// estimate's deviation, which moves the hidden face only (half the outline: weight 1/2).
double OutlineSigma(const PartOutline& traced, const std::vector<Eigen::Vector2d>& simplified_m) {
  const double moved = RmsDistanceToPolygon(traced.polygon_m, simplified_m);
  return std::sqrt(moved * moved + traced.edge_noise_m * traced.edge_noise_m +
                   0.5 * traced.width_sigma_m * traced.width_sigma_m);
}

/// Drops vertices closer than 1e-6 m to their predecessor (the GeoJSON writer refuses them).
std::vector<Eigen::Vector2d> DropRepeated(const std::vector<Eigen::Vector2d>& polygon) {
  std::vector<Eigen::Vector2d> out;
  for (const auto& p : polygon) {
    if (out.empty() || (p - out.back()).norm() > 1e-6) out.push_back(p);
  }
  while (out.size() > 1 && (out.front() - out.back()).norm() <= 1e-6) out.pop_back();
  return out;
}

}  // namespace

Georeference Georeference::Local(const geometry::GeoOrigin& origin) {
  const std::string problem =
      mapio::GeodeticPositionProblem(origin.latitude_deg, origin.longitude_deg, origin.altitude_m);
  if (!problem.empty()) throw std::invalid_argument("origin: " + problem);
  Georeference g;
  g.kind = Kind::kLocal;
  g.origin = origin;
  return g;
}

Georeference Georeference::FromCrs(std::string_view crs) {
  const std::string text(crs);
  const auto bad = [&text]() {
    return std::invalid_argument("--crs '" + text +
                                 "': expected EPSG:326zz (UTM zone zz north) or EPSG:327zz (south), zz in 01..60");
  };
  std::string upper = text;
  std::transform(upper.begin(), upper.end(), upper.begin(), [](unsigned char ch) { return std::toupper(ch); });
  if (upper.rfind("EPSG:", 0) != 0 || upper.size() != 10) throw bad();
  const std::string code = upper.substr(5);
  if (!std::all_of(code.begin(), code.end(), [](unsigned char ch) { return std::isdigit(ch); })) throw bad();
  const int number = std::stoi(code);
  const int zone = number % 100;
  if ((number / 100 != 326 && number / 100 != 327) || zone < 1 || zone > 60) throw bad();
  Georeference g;
  g.kind = Kind::kUtm;
  g.utm_zone = zone;
  g.utm_north = number / 100 == 326;
  return g;
}

std::string Georeference::Describe() const {
  if (kind == Kind::kUtm) {
    return fmt::format("EPSG:{}{:02d} (UTM {}{})", utm_north ? 326 : 327, utm_zone, utm_zone, utm_north ? 'N' : 'S');
  }
  return fmt::format("local ENU at {:.8f} N, {:.8f} E, {:.3f} m", origin.latitude_deg, origin.longitude_deg,
                     origin.altitude_m);
}

MapBuildResult BuildRowMap(const PointCloud& cloud, const MapBuildConfig& config,
                           const Georeference& georeference, bool keep_canopy) {
  if (cloud.points_m.empty()) throw std::invalid_argument("the cloud has no points");
  if (const auto problem = ValidateMapBuildConfig(config)) throw std::invalid_argument("configuration: " + *problem);
  TiledCloud tiled(config.tiles.size_m, config.tiles.overlap_m);
  tiled.Add(cloud.points_m);
  return BuildRowMap(tiled, config, georeference, keep_canopy);
}

MapBuildResult BuildRowMap(TiledCloud& tiled, const MapBuildConfig& config, const Georeference& georeference,
                           bool keep_canopy, const ProgressCallback& progress) {
  if (tiled.point_count() == 0) throw std::invalid_argument("the cloud has no points");
  if (const auto problem = ValidateMapBuildConfig(config)) throw std::invalid_argument("configuration: " + *problem);
  MapBuildResult result;
  result.points_in = tiled.point_count();

  // Offset: keeps the working coordinates small (UTM northings are ~5e6 m).
  const Eigen::Vector2d lo = tiled.min_m();
  const Eigen::Vector2d hi = tiled.max_m();
  result.offset_m = Eigen::Vector2d(std::floor(lo.x()), std::floor(lo.y()));

  // 1-3. Clean, terrain, normalize: per tile.
  SurveyProducts survey = ProcessTiles(tiled, result.offset_m, config, keep_canopy, progress);
  result.tiles = survey.tiles;
  result.tile_threads = survey.threads;
  result.largest_tile_points = survey.largest_tile_points;
  const std::string per_tile = fmt::format("(summed over {} tiles)", survey.tiles);
  result.stages.push_back({"tiles: steps 1-3", survey.tiles,
                           fmt::format("tiles, {} threads, wall clock", survey.threads), survey.wall_seconds});
  result.stages.push_back({"clean: voxel downsampling", survey.points_after_voxel, "points " + per_tile,
                           survey.voxel_seconds});
  result.stages.push_back({"clean: outlier removal", survey.points_cleaned, "points " + per_tile,
                           survey.outlier_seconds});
  if (survey.points_cleaned == 0) throw std::invalid_argument("no points left after cleaning");
  result.terrain = std::move(survey.terrain);
  result.stages.push_back({"terrain: ground cells", result.terrain->GroundCellCount(),
                           fmt::format("of {} cells {}", result.terrain->heights_m().size(), per_tile),
                           survey.terrain_seconds});
  const std::vector<Eigen::Vector2d> band = std::move(survey.band_m);
  result.band_points = band.size();
  result.stages.push_back({"normalize: canopy band", band.size(), "points " + per_tile, survey.normalize_seconds});
  auto start = Clock::now();

  // 4. Rows.
  RowDetection detection = DetectRows(band, config.rows);
  result.parts_dropped = detection.parts_dropped;
  result.links = detection.links;
  std::size_t part_count = 0;
  for (const auto& row : detection.rows) part_count += row.parts.size();
  result.stages.push_back({"rows: parts", part_count,
                           fmt::format("parts, {} rows, {} clutter, {} links", detection.rows.size(),
                                       detection.parts_dropped, detection.links),
                           SecondsSince(start)});

  // Map frame.
  std::optional<mapio::LocalFrame> frame;
  geometry::GeoOrigin origin = georeference.origin;
  if (georeference.kind == Georeference::Kind::kUtm) {
    std::vector<double> ground(result.terrain->heights_m());
    std::nth_element(ground.begin(), ground.begin() + static_cast<std::ptrdiff_t>(ground.size() / 2), ground.end());
    const Eigen::Vector2d centre = 0.5 * (lo + hi);
    try {
      GeographicLib::UTMUPS::Reverse(georeference.utm_zone, georeference.utm_north, centre.x(), centre.y(),
                                     origin.latitude_deg, origin.longitude_deg);
    } catch (const std::exception& e) {
      throw std::invalid_argument(fmt::format("the cloud's centre ({:.3f}, {:.3f}) is not a valid {} position: {}",
                                              centre.x(), centre.y(), georeference.Describe(), e.what()));
    }
    origin.altitude_m = Round(ground[ground.size() / 2], 0.001);
    origin.latitude_deg = Round(origin.latitude_deg, 1e-9);
    origin.longitude_deg = Round(origin.longitude_deg, 1e-9);
    frame.emplace(origin);
  }
  const auto to_map = [&](const Eigen::Vector2d& working) -> Eigen::Vector2d {
    const Eigen::Vector2d xy = working + result.offset_m;
    if (!frame) return xy;
    double lat = 0.0;
    double lon = 0.0;
    try {
      GeographicLib::UTMUPS::Reverse(georeference.utm_zone, georeference.utm_north, xy.x(), xy.y(), lat, lon);
    } catch (const std::exception& e) {
      throw std::invalid_argument(fmt::format("({:.3f}, {:.3f}) is not a valid {} position: {}", xy.x(), xy.y(),
                                              georeference.Describe(), e.what()));
    }
    return frame->ToEnu(lat, lon, origin.altitude_m).head<2>();
  };

  // 5-7. Outline and simplification per part.
  double outline_seconds = 0.0;
  double simplify_seconds = 0.0;
  std::size_t traced_vertices = 0;
  std::size_t map_vertices = 0;
  geometry::RowMap map;
  map.origin = origin;
  std::size_t row_number = 0;
  std::vector<std::vector<Eigen::Vector2d>> traced_outlines;  // per part (flattened), for the meshes
  std::vector<int> part_report;                               // per part: its index in result.parts, or -1
  TopCells top(survey.top_m);
  for (const DetectedRow& row : detection.rows) {
    std::vector<std::pair<PartReport, std::vector<Eigen::Vector2d>>> outlines;
    for (const RowPart& part : row.parts) {
      start = Clock::now();
      PartOutline outline = TraceOutline(part.points_m, config.outline);
      if (outline.polygon_m.size() < 3 && outline.median_width_m < config.outline.min_width_m) {
        // One face only: the hidden one from the canopy top, if the route is on and the top seen.
        outline = TraceOneSidedOutline(part.points_m, top.Near(part.points_m, config.outline.one_sided_max_width_m),
                                       config.outline);
      }
      outline_seconds += SecondsSince(start);
      traced_outlines.push_back(outline.polygon_m);
      part_report.push_back(-1);
      if (outline.polygon_m.size() < 3) {
        ++result.outlines_failed;
        continue;
      }
      start = Clock::now();
      SimplifiedPolygon simple = SimplifyPolygon(outline.polygon_m, config.outline.simplify_tolerance_m);
      if (simple.points_m.size() < 3) simple = SimplifiedPolygon{outline.polygon_m, false};
      simplify_seconds += SecondsSince(start);
      PartReport report;
      report.points = part.points_m.size();
      report.length_m = outline.length_m;
      report.traced_vertices = outline.polygon_m.size();
      report.simplified = simple.simplified;
      report.one_sided = outline.one_sided;
      report.outline_sigma_m = OutlineSigma(outline, simple.points_m);
      report.width_m = outline.median_width_m;
      report.width_spread_m = outline.width_spread_m;
      std::vector<Eigen::Vector2d> polygon;
      for (const auto& p : simple.points_m) polygon.push_back(to_map(p));
      polygon = DropRepeated(polygon);
      if (polygon.size() < 3) {
        ++result.outlines_failed;
        continue;
      }
      report.vertices = polygon.size();
      traced_vertices += report.traced_vertices;
      map_vertices += report.vertices;
      part_report.back() = static_cast<int>(result.parts.size() + outlines.size());
      outlines.emplace_back(report, std::move(polygon));
    }
    if (outlines.empty()) continue;
    ++row_number;
    for (std::size_t k = 0; k < outlines.size(); ++k) {
      auto& [report, polygon] = outlines[k];
      report.id = outlines.size() == 1 ? fmt::format("row-{}", row_number)
                                       : fmt::format("row-{}.part-{}", row_number, k + 1);
      map.rows.push_back(geometry::Row{report.id, std::move(polygon), true, Round(report.outline_sigma_m, 1e-4)});
      result.one_sided_parts += report.one_sided ? 1 : 0;
      result.parts.push_back(report);
    }
  }
  result.rows = row_number;
  result.stages.push_back({"outline: traced", traced_vertices, "vertices", outline_seconds});
  result.stages.push_back({"simplify: CGAL Polyline_simplification_2", map_vertices, "vertices", simplify_seconds});

  // 5-6, mesh route: a lofted mesh per part, in the map frame (z: height of the terrain plus h).
  start = Clock::now();
  for (std::size_t k = 0; k < traced_outlines.size(); ++k) {
    if (part_report[k] < 0) traced_outlines[k].clear();  // not in the map: no mesh either
  }
  const std::vector<PartMesh> meshes = BuildPartMeshes(detection, std::move(survey.level_band_m), traced_outlines, config);
  const double z0 = frame ? origin.altitude_m : 0.0;
  for (std::size_t k = 0; k < meshes.size(); ++k) {
    if (!meshes[k].mesh || part_report[k] < 0) continue;
    PartReport& report = result.parts[static_cast<std::size_t>(part_report[k])];
    report.mesh_levels = meshes[k].levels;
    report.mesh_triangles = meshes[k].mesh->triangles.size();
    report.mesh_slice_max_m = meshes[k].slice_max_m;
    const int offset = static_cast<int>(result.meshes.vertices_m.size());
    for (const Eigen::Vector3d& v : meshes[k].mesh->vertices_m) {
      const Eigen::Vector2d xy = to_map(v.head<2>());
      result.meshes.vertices_m.emplace_back(xy.x(), xy.y(), v.z() + result.terrain->HeightAt(v.head<2>()) - z0);
    }
    for (const auto& t : meshes[k].mesh->triangles) result.meshes.triangles.push_back({t[0] + offset, t[1] + offset, t[2] + offset});
  }
  result.stages.push_back({"mesh: lofted outlines, CGAL slicer check", result.meshes.triangles.size(), "triangles",
                           SecondsSince(start)});

  if (map.rows.empty()) {
    result.message = fmt::format(
        "no rows found: {} of {} cleaned points in the band {:.2f} +- {:.2f} m above the terrain, {} parts "
        "found, {} dropped as clutter (rows.min_part_points {}, rows.min_part_length_m {})",
        band.size(), survey.points_cleaned, config.band.reference_height_m, config.band.band_half_width_m,
        detection.parts_found, detection.parts_dropped, config.rows.min_part_points, config.rows.min_part_length_m);
    if (result.outlines_failed > 0) {
      result.message += fmt::format(
          "; {} parts narrower than outline.min_width_m ({} m): single canopy faces, as a scan from one side of "
          "each row gives, without enough of the canopy top above them to measure their width from (or with "
          "outline.one_sided_max_width_m 0); a row's width cannot be measured from one face, so these rows are not "
          "mapped (survey both sides of every row, or its top)",
          result.outlines_failed, config.outline.min_width_m);
    }
  } else {
    result.message = fmt::format("{} rows ({} parts, {} vertices)", result.rows, map.rows.size(), map_vertices);
    if (result.outlines_failed > 0) {
      result.message += fmt::format(
          "; {} parts without an outline (narrower than outline.min_width_m: single canopy faces without enough "
          "of the canopy top above them, from a scan of one side of the rows, or from a survey sparser than "
          "rows.link_radius_m allows)",
          result.outlines_failed);
    }
    if (result.one_sided_parts > 0) {
      result.message += fmt::format(
          "; {} parts seen from one side only: their hidden face placed at the edge of the canopy top's "
          "footprint, which assumes vertical canopy walls (see each part's width spread)",
          result.one_sided_parts);
    }
    result.map = std::move(map);
  }

  if (keep_canopy) {
    result.canopy_m.points_m.reserve(survey.canopy_m.size());
    for (const Eigen::Vector3d& p : survey.canopy_m) {
      const Eigen::Vector2d xy = to_map(p.head<2>());
      result.canopy_m.points_m.emplace_back(xy.x(), xy.y(), p.z() - z0);
    }
  }
  for (const auto& p : survey.sample_m) result.cloud_sample_m.push_back(to_map(p));
  result.cloud_sample_height_m = std::move(survey.sample_height_m);
  return result;
}

MapBuildResult RunMapBuild(const MapBuildRequest& request) {
  const auto wall_start = Clock::now();
  if (const auto problem = ValidateMapBuildConfig(request.config)) {
    throw std::invalid_argument("configuration: " + *problem);
  }
  std::error_code ec;
  std::filesystem::create_directories(request.output_dir, ec);
  if (ec) throw std::system_error(ec, "cannot create " + request.output_dir.string());

  // Read the survey into tiles spilled to OUTDIR/.rowloc-tiles (a stale one from an interrupted run
  // is ours to remove); memory while reading: one chunk plus each tile's write buffer.
  auto start = Clock::now();
  const std::filesystem::path spill = request.output_dir / ".rowloc-tiles";
  std::filesystem::remove_all(spill, ec);
  TiledCloud tiled(request.config.tiles.size_m, request.config.tiles.overlap_m, spill);
  constexpr std::size_t kChunkPoints = std::size_t{1} << 18;
  std::size_t announced = 0;
  ForEachPointChunk(request.survey_path, kChunkPoints, [&](const std::vector<Eigen::Vector3d>& chunk) {
    tiled.Add(chunk);
    announced += chunk.size();
    if (request.progress) request.progress("read", announced, 0);
  });
  const double read_seconds = SecondsSince(start);
  MapBuildResult result = BuildRowMap(tiled, request.config, request.georeference,
                                      request.octomap_resolution_m.has_value(), request.progress);
  result.stages.insert(result.stages.begin(),
                       StageReport{"read and tile", tiled.point_count(),
                                   fmt::format("points, {} stored with overlaps", tiled.stored_count()), read_seconds});

  start = Clock::now();
  const std::filesystem::path map_path = request.output_dir / "row-map.geojson";
  if (result.map) {
    mapio::WriteRowMapGeoJson(*result.map, map_path);
  } else {
    std::filesystem::remove(map_path, ec);  // never leave a stale map next to a "no rows" report
  }

  // DTM, in the cloud's coordinates.
  const TerrainGrid& dtm = *result.terrain;
  nlohmann::ordered_json dtm_json;
  dtm_json["frame"] = request.georeference.kind == Georeference::Kind::kUtm
                          ? request.georeference.Describe()
                          : request.georeference.Describe() + " (the survey's coordinates)";
  dtm_json["origin_m"] = {dtm.origin_m().x() + result.offset_m.x(), dtm.origin_m().y() + result.offset_m.y()};
  dtm_json["cell_size_m"] = dtm.cell_size_m();
  dtm_json["nx"] = dtm.nx();
  dtm_json["ny"] = dtm.ny();
  dtm_json["layout"] = "heights_m[j * nx + i] at origin + ((i + 0.5), (j + 0.5)) * cell_size_m; bilinear between centres";
  nlohmann::ordered_json heights = nlohmann::ordered_json::array();
  for (double h : dtm.heights_m()) heights.push_back(Round(h, 0.001));
  dtm_json["heights_m"] = std::move(heights);
  std::string ground;
  for (bool g : dtm.ground()) ground.push_back(g ? '1' : '0');
  dtm_json["ground_cells"] = ground;
  WriteText(request.output_dir / "dtm.json", dtm_json.dump() + "\n");
  WriteText(request.output_dir / "map.svg", FormatMapSvg(result));
  result.stages.push_back({"write", result.map ? result.map->SegmentCount() : 0, "segments", SecondsSince(start)});
  const std::filesystem::path meshes_path = request.output_dir / "meshes.ply";
  if (!result.meshes.triangles.empty()) {
    WriteTriangleMeshPly(result.meshes.vertices_m, result.meshes.triangles, meshes_path);
  } else {
    std::filesystem::remove(meshes_path, ec);
  }
  const std::filesystem::path octomap_path = request.output_dir / "canopy.bt";
  if (request.octomap_resolution_m) {
    start = Clock::now();
    if (result.canopy_m.points_m.empty()) throw std::invalid_argument("no canopy points for the OctoMap");
    const OctoMapSummary octomap =
        WriteOctoMap(result.canopy_m, OctoMapOptions{*request.octomap_resolution_m}, octomap_path);
    result.stages.push_back({"octomap: canopy.bt", octomap.occupied_leaves, "voxels", SecondsSince(start)});
    PointCloud().points_m.swap(result.canopy_m.points_m);
  } else {
    std::filesystem::remove(octomap_path, ec);
  }

  // Report.
  std::error_code size_error;
  const auto cloud_bytes = std::filesystem::file_size(request.survey_path, size_error);
  const std::uintmax_t map_bytes = result.map ? std::filesystem::file_size(map_path) : 0;
  const std::uintmax_t mesh_bytes = result.meshes.triangles.empty() ? 0 : std::filesystem::file_size(meshes_path);
  result.wall_seconds = SecondsSince(wall_start);
  const double total_seconds = result.wall_seconds;
  nlohmann::ordered_json report;
  report["survey"] = request.survey_path.string();
  report["georeference"] = request.georeference.Describe();
  report["config"] = request.config_source;
  report["result"] = result.message;
  report["rows"] = result.rows;
  report["parts"] = result.parts.size();
  report["points_in"] = result.points_in;
  report["cloud_bytes"] = size_error ? 0 : cloud_bytes;
  report["map_bytes"] = map_bytes;
  report["data_reduction"] = map_bytes > 0 && !size_error ? static_cast<double>(cloud_bytes) / map_bytes : 0.0;
  report["mesh_bytes"] = mesh_bytes;
  report["data_reduction_with_meshes"] =
      map_bytes > 0 && !size_error ? static_cast<double>(cloud_bytes) / static_cast<double>(map_bytes + mesh_bytes) : 0.0;
  report["total_seconds"] = total_seconds;
  report["tiles"] = {{"size_m", request.config.tiles.size_m}, {"overlap_m", request.config.tiles.overlap_m},
                     {"count", result.tiles}, {"threads", result.tile_threads},
                     {"largest_tile_points", result.largest_tile_points}};
  nlohmann::ordered_json stages = nlohmann::ordered_json::array();
  for (const auto& s : result.stages) {
    stages.push_back({{"stage", s.name}, {"count", s.points}, {"unit", s.unit}, {"seconds", s.seconds}});
  }
  report["stages"] = std::move(stages);
  nlohmann::ordered_json parts = nlohmann::ordered_json::array();
  for (const auto& p : result.parts) {
    nlohmann::ordered_json part = {{"id", p.id}, {"points", p.points}, {"length_m", Round(p.length_m, 0.001)},
                                   {"traced_vertices", p.traced_vertices}, {"vertices", p.vertices},
                                   {"simplified", p.simplified}, {"one_sided", p.one_sided},
                                   {"width_m", Round(p.width_m, 1e-4)},
                                   {"width_spread_m", Round(p.width_spread_m, 1e-4)},
                                   {"outline_sigma_m", Round(p.outline_sigma_m, 1e-4)}, {"mesh_levels", p.mesh_levels},
                                   {"mesh_triangles", p.mesh_triangles}};
    part["mesh_slice_max_m"] = p.mesh_slice_max_m ? nlohmann::ordered_json(Round(*p.mesh_slice_max_m, 1e-4)) : nullptr;
    parts.push_back(std::move(part));
  }
  report["row_parts"] = std::move(parts);
  report["outlines_failed"] = result.outlines_failed;
  report["one_sided_parts"] = result.one_sided_parts;
  WriteText(request.output_dir / "report.json", report.dump(2) + "\n");

  std::string text = fmt::format("rowloc map build\n  survey: {} ({} points, {} bytes)\n  georeference: {}\n  config: {}\n"
                                 "  result: {}\n\n",
                                 request.survey_path.string(), result.points_in, size_error ? 0 : cloud_bytes,
                                 request.georeference.Describe(), request.config_source, result.message);
  text += "  stage                                        count  unit                                 time [s]\n";
  for (const auto& s : result.stages) {
    text += fmt::format("  {:<44} {:>7}  {:<36} {:8.3f}\n", s.name, s.points, s.unit, s.seconds);
  }
  text += fmt::format("  {:<44} {:>7}  {:<36} {:8.3f}\n\n", "total (wall clock)", "", "", total_seconds);
  text += fmt::format("  tiles: {} of {} m with {} m overlap, {} threads, largest {} points\n\n", result.tiles,
                      request.config.tiles.size_m, request.config.tiles.overlap_m, result.tile_threads,
                      result.largest_tile_points);
  if (!result.parts.empty()) {
    text += "  part                 points  length [m]  width [m]  sigma [m]  traced  vertices  simplified  mesh: levels "
            "triangles slice-max [m]\n";
    for (const auto& p : result.parts) {
      const std::string width = p.one_sided ? fmt::format("{:.3f}*", p.width_m) : fmt::format("{:.3f} ", p.width_m);
      text += fmt::format("  {:<18} {:>8}  {:>10.2f}  {:>9}  {:>9.4f}  {:>6}  {:>8}  {:<10}  {:>12} {:>9} {:>13}\n", p.id,
                          p.points, p.length_m, width, p.outline_sigma_m, p.traced_vertices, p.vertices, p.simplified ? "yes" : "no", p.mesh_levels,
                          p.mesh_triangles, p.mesh_slice_max_m ? fmt::format("{:.4f}", *p.mesh_slice_max_m) : "-");
    }
    if (result.one_sided_parts > 0) {
      text += "  * seen from one side: the width from the canopy top's footprint (vertical walls assumed)\n";
    }
    text += fmt::format("\n  map: {} ({} bytes); data reduction {:.0f} : 1\n", map_path.string(), map_bytes,
                        report["data_reduction"].get<double>());
    if (mesh_bytes > 0) {
      text += fmt::format("  meshes: {} ({} bytes, {} triangles); data reduction with the meshes {:.0f} : 1\n",
                          meshes_path.string(), mesh_bytes, result.meshes.triangles.size(),
                          report["data_reduction_with_meshes"].get<double>());
    }
  }
  WriteText(request.output_dir / "report.txt", text);
  return result;
}

}  // namespace rowloc::mapping
