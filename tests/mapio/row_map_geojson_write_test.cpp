// Writing row map GeoJSON: the text follows RFC 7946, write -> read reproduces the map (local
// coordinates to 1e-6 m, origin to 1e-9 deg) and the file is replaced atomically.
#include "rowloc/mapio/row_map_geojson.hpp"

#include "test_support.hpp"

#include <gmock/gmock.h>
#include <gtest/gtest.h>
#include <nlohmann/json.hpp>

#include <cmath>
#include <fstream>
#include <limits>
#include <random>
#include <sstream>
#include <system_error>

namespace rowloc::mapio {
namespace {

using geometry::GeoOrigin;
using geometry::Row;
using geometry::RowMap;
using ::testing::HasSubstr;

/// Expects read to be map up to the file's precision.
void ExpectSameMap(const RowMap& map, const RowMap& read) {
  EXPECT_NEAR(read.origin.latitude_deg, map.origin.latitude_deg, 1e-9);
  EXPECT_NEAR(read.origin.longitude_deg, map.origin.longitude_deg, 1e-9);
  EXPECT_NEAR(read.origin.altitude_m, map.origin.altitude_m, 1e-9);
  ASSERT_EQ(read.rows.size(), map.rows.size());
  for (std::size_t r = 0; r < map.rows.size(); ++r) {
    const Row& a = map.rows[r];
    const Row& b = read.rows[r];
    EXPECT_EQ(b.id, a.id);
    EXPECT_EQ(b.closed, a.closed) << a.id;
    ASSERT_EQ(b.points_m.size(), a.points_m.size()) << a.id;
    for (std::size_t i = 0; i < a.points_m.size(); ++i) {
      EXPECT_LT((b.points_m[i] - a.points_m[i]).norm(), 1e-6) << a.id << " vertex " << i;
    }
  }
}

RowMap WriteAndRead(const RowMap& map) {
  const test::ScratchDir dir;
  const std::filesystem::path path = dir / "map.geojson";
  WriteRowMapGeoJson(map, path);
  return ReadRowMapGeoJson(path);
}

RowMap AxisAlignedMap() {
  RowMap map;
  map.origin = GeoOrigin{-33.9, 18.4, 60.0};
  map.rows.push_back(Row{"along-x", {{0.0, 0.0}, {50.0, 0.0}, {100.0, 0.0}}, false, 0.0});
  map.rows.push_back(Row{"along-y", {{2.5, 0.0}, {2.5, 50.0}, {2.5, 100.0}}, false, 0.0});
  map.rows.push_back(Row{"square", {{5.0, 0.0}, {6.0, 0.0}, {6.0, 1.0}, {5.0, 1.0}}, true, 0.0});
  return map;
}

TEST(RowMapGeoJsonWrite, SampleMapRoundTrip) {
  const RowMap map = geometry::MakeSampleRowMap(geometry::SampleRowMapParams{});
  ExpectSameMap(map, WriteAndRead(map));
}

TEST(RowMapGeoJsonWrite, OutlineSigmaRoundTripsAndIsOnlyWrittenWhenSet) {
  RowMap map = AxisAlignedMap();
  map.rows[2].outline_sigma_m = 0.0042;
  const RowMap read = WriteAndRead(map);
  EXPECT_EQ(read.rows[0].outline_sigma_m, 0.0);
  EXPECT_EQ(read.rows[2].outline_sigma_m, 0.0042);
  const std::string text = FormatRowMapGeoJson(map);
  EXPECT_EQ(text.find("outline_sigma_m"), text.rfind("outline_sigma_m"));  // once: the square's
  EXPECT_NE(text.find(R"("outline_sigma_m":0.0042)"), std::string::npos) << text;
  map.rows[0].outline_sigma_m = -1.0;
  EXPECT_THROW(FormatRowMapGeoJson(map), std::invalid_argument);
  map.rows[0].outline_sigma_m = std::numeric_limits<double>::quiet_NaN();
  EXPECT_THROW(FormatRowMapGeoJson(map), std::invalid_argument);
}

TEST(RowMapGeoJsonWrite, AxisAlignedRowsRoundTrip) {
  const RowMap map = AxisAlignedMap();
  const RowMap read = WriteAndRead(map);
  ExpectSameMap(map, read);
  for (const Eigen::Vector2d& p : read.rows[0].points_m) EXPECT_NEAR(p.y(), 0.0, 1e-6);
  for (const Eigen::Vector2d& p : read.rows[1].points_m) EXPECT_NEAR(p.x(), 2.5, 1e-6);
}

// Property: random maps at origins all over the globe (both hemispheres, high latitude, across
// the antimeridian) survive Format -> Parse, over distances up to 5 km.
TEST(RowMapGeoJsonWrite, RandomMapsRoundTrip) {
  const GeoOrigin origins[] = {{45.0703, 7.6869, 240.0}, {-37.8, 144.9, 30.0}, {64.1, -21.9, -5.0},
                               {10.0, 179.999, 0.0},     {0.0, 0.0, 0.0},      {-70.0, -60.0, 1500.0}};
  std::mt19937 rng(7946);
  std::uniform_real_distribution<double> coordinate_m(-5000.0, 5000.0);
  std::uniform_int_distribution<int> vertex_count(2, 12);
  for (const GeoOrigin& origin : origins) {
    RowMap map;
    map.origin = origin;
    for (int r = 0; r < 8; ++r) {
      Row row;
      row.id = "r";
      row.id += std::to_string(r);  // not "r" + std::to_string(r): GCC 12 -Wrestrict false positive
      row.closed = r % 2 == 1;
      const int n = vertex_count(rng) + (row.closed ? 1 : 0);
      if (row.closed) {  // a star-shaped ring (vertices by angle around a centre): a valid outline (a
                         // ring of random vertices crosses itself, which the reader refuses)
        const Eigen::Vector2d centre(coordinate_m(rng), coordinate_m(rng));
        std::uniform_real_distribution<double> radius_m(10.0, 2500.0);
        for (int i = 0; i < n; ++i) {
          const double angle = 2.0 * 3.141592653589793 * (i + 0.5 * std::uniform_real_distribution<double>()(rng)) / n;
          row.points_m.push_back(centre + radius_m(rng) * Eigen::Vector2d(std::cos(angle), std::sin(angle)));
        }
      } else {
        for (int i = 0; i < n; ++i) row.points_m.emplace_back(coordinate_m(rng), coordinate_m(rng));
      }
      map.rows.push_back(std::move(row));
    }
    SCOPED_TRACE(origin.longitude_deg);
    ExpectSameMap(map, ParseRowMapGeoJson(FormatRowMapGeoJson(map)));
  }
}

TEST(RowMapGeoJsonWrite, TextIsRfc7946) {
  const nlohmann::json doc = nlohmann::json::parse(FormatRowMapGeoJson(AxisAlignedMap()));
  EXPECT_EQ(doc.at("type"), "FeatureCollection");
  EXPECT_EQ(doc.at("rowloc").at("format_version"), kRowMapFormatVersion);
  EXPECT_EQ(doc.at("rowloc").at("origin").at("latitude_deg"), -33.9);
  EXPECT_EQ(doc.at("rowloc").at("origin").at("longitude_deg"), 18.4);
  EXPECT_EQ(doc.at("rowloc").at("origin").at("altitude_m"), 60.0);
  const nlohmann::json& features = doc.at("features");
  ASSERT_EQ(features.size(), 3u);
  EXPECT_EQ(features[0].at("type"), "Feature");
  EXPECT_EQ(features[0].at("properties").at("id"), "along-x");
  EXPECT_EQ(features[0].at("geometry").at("type"), "LineString");
  const nlohmann::json& first = features[0].at("geometry").at("coordinates")[0];
  ASSERT_EQ(first.size(), 3u);
  EXPECT_NEAR(first[0].get<double>(), 18.4, 1e-12);   // longitude first (RFC 7946 §3.1.1)
  EXPECT_NEAR(first[1].get<double>(), -33.9, 1e-12);
  EXPECT_NEAR(first[2].get<double>(), 60.0, 1e-9);
  // 100 m east: the tangent plane rises above the ellipsoid by d^2 / (2 R) = 0.8 mm.
  const nlohmann::json& last = features[0].at("geometry").at("coordinates")[2];
  EXPECT_NEAR(last[2].get<double>() - 60.0, 100.0 * 100.0 / (2.0 * 6.38e6), 1e-4);
  const nlohmann::json& square = features[2].at("geometry");
  EXPECT_EQ(square.at("type"), "Polygon");
  ASSERT_EQ(square.at("coordinates").size(), 1u);              // one ring, no holes
  const nlohmann::json& ring = square.at("coordinates")[0];
  ASSERT_EQ(ring.size(), 5u);                                   // 4 vertices + the closing one
  EXPECT_EQ(ring.front(), ring.back());                         // identical values (§3.1.6)
}

TEST(RowMapGeoJsonWrite, UnusualIdsRoundTrip) {
  RowMap map = AxisAlignedMap();
  map.rows[0].id = "row \"7\" \\ Nebbiolo / vigna Ü 葡萄";
  map.rows[1].id = " ";
  ExpectSameMap(map, ParseRowMapGeoJson(FormatRowMapGeoJson(map)));
}

TEST(RowMapGeoJsonWrite, RejectsInvalidMaps) {
  RowMap empty = AxisAlignedMap();
  empty.rows.clear();
  EXPECT_THROW(FormatRowMapGeoJson(empty), std::invalid_argument);
  RowMap duplicate = AxisAlignedMap();
  duplicate.rows[1].id = duplicate.rows[0].id;
  EXPECT_THROW(FormatRowMapGeoJson(duplicate), std::invalid_argument);
  RowMap bad_origin = AxisAlignedMap();
  bad_origin.origin.latitude_deg = 91.0;
  EXPECT_THROW(FormatRowMapGeoJson(bad_origin), std::invalid_argument);
  RowMap repeated_vertex = AxisAlignedMap();
  repeated_vertex.rows[2].points_m.push_back(repeated_vertex.rows[2].points_m.front());  // ring stored closed
  try {
    FormatRowMapGeoJson(repeated_vertex);
    FAIL() << "accepted a zero-length segment";
  } catch (const std::invalid_argument& e) {
    EXPECT_THAT(std::string(e.what()), HasSubstr("zero length"));
  }
}

TEST(RowMapGeoJsonWrite, RejectsIdThatIsNotUtf8) {
  RowMap map = AxisAlignedMap();
  map.rows[0].id = "row\xff";
  try {
    FormatRowMapGeoJson(map);
    FAIL() << "wrote invalid UTF-8";
  } catch (const std::invalid_argument& e) {
    EXPECT_THAT(std::string(e.what()), HasSubstr("row 0: id is not valid UTF-8"));
  }
}

TEST(RowMapGeoJsonWrite, RejectsVerticesCloserThanTheFilePrecision) {
  RowMap map = AxisAlignedMap();
  map.rows[0].points_m[1] = map.rows[0].points_m[0] + Eigen::Vector2d(1e-9, 0.0);  // valid, but not writable
  ASSERT_EQ(geometry::ValidateRowMap(map), std::nullopt);
  try {
    FormatRowMapGeoJson(map);
    FAIL() << "wrote two vertices that the reader would merge";
  } catch (const std::invalid_argument& e) {
    EXPECT_THAT(std::string(e.what()), HasSubstr("row 'along-x': vertex 1 is too close"));
  }
  RowMap ring = AxisAlignedMap();
  ring.rows[2].points_m.back() = ring.rows[2].points_m.front() + Eigen::Vector2d(0.0, 1e-9);  // closing segment
  EXPECT_THROW(FormatRowMapGeoJson(ring), std::invalid_argument);
}

std::string Slurp(const std::filesystem::path& path) {
  std::ifstream in(path, std::ios::binary);
  std::ostringstream bytes;
  bytes << in.rdbuf();
  return bytes.str();
}

TEST(RowMapGeoJsonWrite, ReplacesAnExistingFileAndLeavesNoTemporary) {
  const test::ScratchDir dir;
  const std::filesystem::path path = dir / "map.geojson";
  std::ofstream(path) << "old content";
  const RowMap map = AxisAlignedMap();
  WriteRowMapGeoJson(map, path);
  EXPECT_EQ(Slurp(path), FormatRowMapGeoJson(map));
  std::size_t files = 0;
  for (const auto& entry : std::filesystem::directory_iterator(dir.path())) {
    ++files;
    EXPECT_EQ(entry.path().filename(), "map.geojson");
  }
  EXPECT_EQ(files, 1u);
}

TEST(RowMapGeoJsonWrite, InvalidMapLeavesTheFileUntouched) {
  const test::ScratchDir dir;
  const std::filesystem::path path = dir / "map.geojson";
  std::ofstream(path) << "old content";
  RowMap map = AxisAlignedMap();
  map.rows[0].points_m.resize(1);
  EXPECT_THROW(WriteRowMapGeoJson(map, path), std::invalid_argument);
  EXPECT_EQ(Slurp(path), "old content");
}

TEST(RowMapGeoJsonWrite, MissingDirectoryIsASystemError) {
  const test::ScratchDir dir;
  const std::filesystem::path path = dir / "no" / "such" / "map.geojson";
  try {
    WriteRowMapGeoJson(AxisAlignedMap(), path);
    FAIL() << "wrote into a missing directory";
  } catch (const std::system_error& e) {
    EXPECT_EQ(e.code(), std::errc::no_such_file_or_directory);
    EXPECT_THAT(std::string(e.what()), HasSubstr(path.string()));
  }
}

}  // namespace
}  // namespace rowloc::mapio
