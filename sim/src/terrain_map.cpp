#include "rowloc/sim/terrain_map.hpp"

#include "rowloc/mapio/detail/json_object_reader.hpp"

// GCC 12 reports a false "maybe-uninitialized" inside Boost 1.74's rescale policy (instantiated by
// is_valid); silenced for the Boost headers only. Boost 1.74's geometry still includes a deprecated
// Boost header that prints a note on every build; the macro only silences that note.
#ifndef BOOST_ALLOW_DEPRECATED_HEADERS
#define BOOST_ALLOW_DEPRECATED_HEADERS
#endif
#pragma GCC diagnostic push
#pragma GCC diagnostic ignored "-Wmaybe-uninitialized"
#include <boost/geometry/algorithms/correct.hpp>
#include <boost/geometry/algorithms/covered_by.hpp>
#include <boost/geometry/algorithms/envelope.hpp>
#include <boost/geometry/algorithms/is_valid.hpp>
#include <boost/geometry/geometries/box.hpp>
#include <boost/geometry/geometries/point_xy.hpp>
#include <boost/geometry/geometries/polygon.hpp>
#include <boost/geometry/strategies/strategies.hpp>
#pragma GCC diagnostic pop

#include <optional>
#include <stdexcept>
#include <string>
#include <utility>

namespace rowloc::sim {
namespace {

namespace bg = boost::geometry;
using BgPoint = bg::model::d2::point_xy<double>;
using BgPolygon = bg::model::polygon<BgPoint>;
using BgBox = bg::model::box<BgPoint>;

constexpr std::size_t kMaxPatches = 100000;
constexpr std::size_t kMaxVertices = 1000000;

bool IsKnown(TerrainClass terrain) {
  for (const TerrainClass known : kAllTerrainClasses)
    if (terrain == known) return true;
  return false;
}

/// Drops a repeated closing vertex.
std::vector<Eigen::Vector2d> Opened(std::vector<Eigen::Vector2d> polygon_m) {
  if (polygon_m.size() >= 2 && polygon_m.front() == polygon_m.back()) polygon_m.pop_back();
  return polygon_m;
}

/// The corrected (closed, clockwise) Boost polygon, or the reason it is unusable.
std::pair<BgPolygon, std::optional<std::string>> ToPolygon(const std::vector<Eigen::Vector2d>& polygon_m) {
  BgPolygon polygon;
  if (polygon_m.size() < 3) {
    return {polygon, "needs at least 3 distinct vertices, got " + std::to_string(polygon_m.size())};
  }
  if (polygon_m.size() > kMaxVertices) return {polygon, "more than 1000000 vertices"};
  for (std::size_t i = 0; i < polygon_m.size(); ++i) {
    if (!polygon_m[i].allFinite()) return {polygon, "vertex " + std::to_string(i) + " is not finite"};
    polygon.outer().emplace_back(polygon_m[i].x(), polygon_m[i].y());
  }
  bg::correct(polygon);
  std::string reason;
  if (!bg::is_valid(polygon, reason)) return {polygon, "not a simple polygon: " + reason};
  return {polygon, std::nullopt};
}

}  // namespace

struct TerrainMap::Index {
  std::vector<BgPolygon> polygons;
  std::vector<BgBox> boxes;
};

TerrainMap::TerrainMap() : TerrainMap(TerrainClass::kTiles) {}

TerrainMap::TerrainMap(TerrainClass default_terrain, std::vector<TerrainPatch> patches)
    : default_terrain_(default_terrain), patches_(std::move(patches)) {
  if (!IsKnown(default_terrain_))
    throw std::invalid_argument("TerrainMap: default terrain is not a known class");
  if (patches_.size() > kMaxPatches) throw std::invalid_argument("TerrainMap: more than 100000 patches");
  auto index = std::make_shared<Index>();
  for (std::size_t i = 0; i < patches_.size(); ++i) {
    const std::string where = "TerrainMap: patches[" + std::to_string(i) + "]";
    if (!IsKnown(patches_[i].terrain))
      throw std::invalid_argument(where + ".terrain is not a known class");
    patches_[i].polygon_m = Opened(std::move(patches_[i].polygon_m));
    auto [polygon, problem] = ToPolygon(patches_[i].polygon_m);
    if (problem) throw std::invalid_argument(where + ".polygon: " + *problem);
    index->boxes.push_back(bg::return_envelope<BgBox>(polygon));
    index->polygons.push_back(std::move(polygon));
  }
  index_ = std::move(index);
}

TerrainClass TerrainMap::ClassAt(const Eigen::Vector2d& point_m) const {
  if (!point_m.allFinite()) throw std::invalid_argument("TerrainMap::ClassAt: the point must be finite");
  const BgPoint point(point_m.x(), point_m.y());
  for (std::size_t i = patches_.size(); i-- > 0;) {
    if (bg::covered_by(point, index_->boxes[i]) && bg::covered_by(point, index_->polygons[i])) {
      return patches_[i].terrain;
    }
  }
  return default_terrain_;
}

// ---------------------------------------------------------------------------------------------
// JSON

namespace {

using Reader = mapio::detail::JsonObjectReader<TerrainConfigError>;

TerrainClass ReadTerrain(Reader& reader, const std::string& key) {
  const std::string name = reader.String(key);
  const auto terrain = TerrainClassFromName(name);
  if (!terrain) reader.Fail(reader.Key(key), "unknown terrain \"" + name + "\" (tiles, grass, gravel, mud)");
  return *terrain;
}

std::vector<Eigen::Vector2d> ReadPolygon(Reader& reader) {
  const nlohmann::json& value = reader.Value("polygon");
  const std::string key = reader.Key("polygon");
  if (!value.is_array()) reader.Fail(key, "must be an array of [x, y] points");
  std::vector<Eigen::Vector2d> polygon;
  for (std::size_t i = 0; i < value.size(); ++i) {
    const nlohmann::json& item = value[i];
    const std::string item_key = key + "[" + std::to_string(i) + "]";
    if (!item.is_array() || item.size() != 2 || !item[0].is_number() || !item[1].is_number())
      reader.Fail(item_key, "must be an array of 2 numbers");
    polygon.emplace_back(item[0].get<double>(), item[1].get<double>());
  }
  return polygon;
}

std::vector<Eigen::Vector2d> ReadRectangle(Reader& reader) {
  Reader rectangle = reader.Object("rectangle");
  const Eigen::Vector2d low = rectangle.Vector<2>("min");
  const Eigen::Vector2d high = rectangle.Vector<2>("max");
  rectangle.RejectUnknownKeys();
  if (!(low.array() < high.array()).all()) reader.Fail(rectangle.path(), "min must be below max in x and in y");
  return {low, {high.x(), low.y()}, high, {low.x(), high.y()}};
}

TerrainPatch ReadPatch(Reader& reader) {
  TerrainPatch patch;
  patch.terrain = ReadTerrain(reader, "terrain");
  const bool has_polygon = reader.Has("polygon");
  if (has_polygon == reader.Has("rectangle")) {
    reader.Fail(reader.path(), "needs exactly one of \"polygon\" and \"rectangle\"");
  }
  patch.polygon_m = has_polygon ? ReadPolygon(reader) : ReadRectangle(reader);
  reader.RejectUnknownKeys();
  if (const auto problem = ToPolygon(Opened(patch.polygon_m)).second) {
    reader.Fail(reader.Key(has_polygon ? "polygon" : "rectangle"), *problem);
  }
  return patch;
}

}  // namespace

TerrainMap ParseTerrainMap(std::string_view json_object_text, std::string_view source_name) {
  return ParseTerrainMap(json_object_text, source_name, "");
}

TerrainMap ParseTerrainMap(std::string_view json_object_text, std::string_view source_name,
                           std::string_view key_path_prefix) {
  const std::string source(source_name);
  const nlohmann::json json = mapio::detail::ParseJsonText<TerrainConfigError>(json_object_text, source);
  Reader reader(json, source, std::string(key_path_prefix));
  const TerrainClass default_terrain = ReadTerrain(reader, "default");
  std::vector<TerrainPatch> patches = reader.ObjectArray("patches", ReadPatch, 0, kMaxPatches);
  reader.RejectUnknownKeys();
  return TerrainMap(default_terrain, std::move(patches));
}

}  // namespace rowloc::sim
