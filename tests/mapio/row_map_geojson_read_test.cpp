// Reading row map GeoJSON: a valid file, then every rejected input, each checking that the
// MapFormatError names the file (source), the location and the reason.
#include "rowloc/mapio/row_map_geojson.hpp"

#include "test_support.hpp"

#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include <unistd.h>

#include <cstdio>
#include <fstream>
#include <string>

namespace rowloc::mapio {
namespace {

using ::testing::HasSubstr;

const std::string kHeader =
    R"({"type": "FeatureCollection", "rowloc": {"format_version": 1, "origin": )"
    R"({"latitude_deg": 45.0, "longitude_deg": 7.0, "altitude_m": 200.0}}, "features": [)";

/// A FeatureCollection with the standard origin and the given features.
std::string Collection(const std::string& features) { return kHeader + features + "]}"; }

/// A Feature with id and geometry given as JSON text.
std::string Feature(const std::string& id_json, const std::string& geometry_json) {
  return R"({"type": "Feature", "properties": {"id": )" + id_json + R"(}, "geometry": )" + geometry_json + "}";
}
std::string Line(const std::string& id, const std::string& coordinates) {
  return Feature("\"" + id + "\"", R"({"type": "LineString", "coordinates": )" + coordinates + "}");
}
const std::string kGoodLine = Line("ok", "[[7.0, 45.0], [7.0, 45.001]]");

std::filesystem::path Fixture(const std::string& name) { return test::SourceDir() / "tests/data/maps" / name; }

/// The error thrown by parsing text as "test.geojson"; fails the test if nothing is thrown.
MapFormatError ErrorOf(const std::string& text) {
  try {
    const geometry::RowMap map = ParseRowMapGeoJson(text, "test.geojson");
    ADD_FAILURE() << "accepted a map with " << map.rows.size() << " rows:\n" << text;
  } catch (const MapFormatError& e) {
    return e;
  }
  return MapFormatError("", "", "");
}

/// Expects the error to name test.geojson, exactly this location, and a reason containing `reason`.
void ExpectError(const std::string& text, const std::string& location, const std::string& reason) {
  const MapFormatError e = ErrorOf(text);
  EXPECT_EQ(e.source(), "test.geojson");
  EXPECT_EQ(e.location(), location) << e.what();
  EXPECT_THAT(e.reason(), HasSubstr(reason)) << e.what();
  EXPECT_THAT(std::string(e.what()), HasSubstr("test.geojson")) << e.what();
  EXPECT_THAT(std::string(e.what()), HasSubstr(location)) << e.what();
}

TEST(RowMapGeoJsonRead, ValidFixture) {
  const geometry::RowMap map = ReadRowMapGeoJson(Fixture("valid_two_rows.geojson"));
  EXPECT_EQ(map.origin.latitude_deg, 45.0);
  EXPECT_EQ(map.origin.longitude_deg, 7.0);
  EXPECT_EQ(map.origin.altitude_m, 200.0);
  ASSERT_EQ(map.rows.size(), 2u);
  const geometry::Row& a = map.rows[0];
  EXPECT_EQ(a.id, "a");
  EXPECT_FALSE(a.closed);
  ASSERT_EQ(a.points_m.size(), 2u);
  EXPECT_NEAR(a.points_m[0].norm(), 0.0, 1e-9);  // 2-element position at the origin altitude
  EXPECT_NEAR(a.points_m[1].x(), 0.0, 1e-9);
  EXPECT_NEAR(a.points_m[1].y(), 111.13, 0.01);  // 1e-3 deg north
  const geometry::Row& b = map.rows[1];
  EXPECT_EQ(b.id, "b");
  EXPECT_TRUE(b.closed);
  ASSERT_EQ(b.points_m.size(), 3u);  // the closing position is not stored
  EXPECT_NEAR(b.points_m[1].x() - b.points_m[0].x(), 78.8, 0.1);  // 1e-3 deg east at 45 deg
  EXPECT_NEAR(b.points_m[2].y() - b.points_m[1].y(), 55.6, 0.1);
  EXPECT_FALSE(geometry::ValidateRowMap(map).has_value());
}

TEST(RowMapGeoJsonRead, BadJsonSyntaxGivesLineAndColumn) {
  const std::filesystem::path path = Fixture("syntax_error.geojson");
  try {
    ReadRowMapGeoJson(path);
    FAIL() << "accepted a trailing comma";
  } catch (const MapFormatError& e) {
    EXPECT_EQ(e.source(), path.string());
    EXPECT_EQ(e.location(), "6:84");  // the ']' after the trailing comma
    EXPECT_THAT(e.reason(), HasSubstr("syntax error"));
    EXPECT_THAT(std::string(e.what()), HasSubstr(path.string() + ":6:84: JSON syntax error"));
  }
}

TEST(RowMapGeoJsonRead, BadJsonSyntaxOnFirstAndLastByte) {
  ExpectError("", "1:1", "unexpected end of input");
  ExpectError("{\"type\": \"FeatureCollection\"\n", "2:1", "unexpected end of input");
  ExpectError("\n\n  x", "3:3", "syntax error");
}

TEST(RowMapGeoJsonRead, DuplicateJsonKey) {
  ExpectError(Collection(Feature("\"a\"", R"({"type": "LineString", "coordinates": [[7, 45], [7, 46]], )"
                                          R"("coordinates": [[7, 45], [7, 45.1]]})")),
              "JSON value /features/0/geometry/coordinates", "duplicate key 'coordinates'");
}

TEST(RowMapGeoJsonRead, NotAFeatureCollection) {
  ExpectError(kGoodLine, "top level", "expected a GeoJSON \"FeatureCollection\", got \"type\": 'Feature'");
  ExpectError("[1, 2]", "top level", "got array");
  ExpectError(R"({"features": []})", "top level", "\"type\" is missing");
}

TEST(RowMapGeoJsonRead, FeatureWithoutFeatureType) {
  ExpectError(Collection(R"({"type": "Row", "properties": {"id": "a"}})"), "feature 0", "expected \"type\": \"Feature\"");
  ExpectError(Collection("42"), "feature 0", "must be an object, got number");
}

TEST(RowMapGeoJsonRead, WrongGeometryTypePoint) {
  ExpectError(Collection(kGoodLine + "," + Feature("\"p\"", R"({"type": "Point", "coordinates": [7, 45]})")),
              "feature 1 (id 'p')", "geometry type 'Point' is not supported");
}

TEST(RowMapGeoJsonRead, WrongGeometryTypeMultiLineString) {
  ExpectError(Collection(Feature("\"m\"", R"({"type": "MultiLineString", "coordinates": [[[7, 45], [7, 46]]]})")),
              "feature 0 (id 'm')", "geometry type 'MultiLineString' is not supported");
}

TEST(RowMapGeoJsonRead, MissingGeometry) {
  ExpectError(Collection(R"({"type": "Feature", "properties": {"id": "g"}})"), "feature 0 (id 'g')", "no geometry");
  ExpectError(Collection(Feature("\"g\"", "null")), "feature 0 (id 'g')", "no geometry");
}

TEST(RowMapGeoJsonRead, MissingCoordinates) {
  ExpectError(Collection(Feature("\"c\"", R"({"type": "LineString"})")), "feature 0 (id 'c')",
              "the LineString has no \"coordinates\"");
  ExpectError(Collection(Feature("\"c\"", R"({"type": "Polygon", "coordinates": "none"})")), "feature 0 (id 'c')",
              "\"coordinates\" must be an array, got string");
}

TEST(RowMapGeoJsonRead, NaNLiteralIsASyntaxErrorWithAHint) {
  const std::filesystem::path path = Fixture("nan_coordinate.geojson");
  try {
    ReadRowMapGeoJson(path);
    FAIL() << "accepted NaN";
  } catch (const MapFormatError& e) {
    EXPECT_EQ(e.source(), path.string());
    EXPECT_EQ(e.location(), "6:76");  // the 'N' of NaN
    EXPECT_THAT(e.reason(), HasSubstr("JSON has no NaN or Infinity"));
  }
}

TEST(RowMapGeoJsonRead, InfinityLiteralIsASyntaxErrorWithAHint) {
  const std::string text = Collection(Line("i", "[[7.0, 45.0], [-Infinity, 45.0]]"));
  const std::size_t column = text.find("-Infinity") + 2;  // the parser stops on the 'I'
  ExpectError(text, "1:" + std::to_string(column), "JSON has no NaN or Infinity");
}

TEST(RowMapGeoJsonRead, NullCoordinate) {
  ExpectError(Collection(Line("n", "[[7.0, 45.0], [7.0, null]]")), "feature 0 (id 'n')",
              "coordinates[1][1] (latitude) must be a number, got null");
}

TEST(RowMapGeoJsonRead, StringCoordinate) {
  ExpectError(Collection(Line("s", R"([["7.0", 45.0], [7.0, 45.1]])")), "feature 0 (id 's')",
              "coordinates[0][0] (longitude) must be a number, got string");
}

TEST(RowMapGeoJsonRead, NumberTooLargeForADouble) {
  ExpectError(Collection(Line("big", "[[7.0, 45.0], [7.0, 45.1, 1e999]]")),
              "JSON value /features/0/geometry/coordinates/1/2", "number overflow");
}

TEST(RowMapGeoJsonRead, PositionWithWrongElementCount) {
  ExpectError(Collection(Line("e", "[[7.0, 45.0, 1.0, 2.0], [7.0, 45.1]]")), "feature 0 (id 'e')",
              "coordinates[0] has 4 elements");
  ExpectError(Collection(Line("e", "[[7.0], [7.0, 45.1]]")), "feature 0 (id 'e')", "coordinates[0] has 1 elements");
  ExpectError(Collection(Line("e", "[7.0, 45.1]")), "feature 0 (id 'e')", "coordinates[0] must be a position");
}

TEST(RowMapGeoJsonRead, LatitudeOutOfRange) {
  ExpectError(Collection(Line("lat", "[[7.0, 45.0], [7.0, 90.5]]")), "feature 0 (id 'lat')",
              "coordinates[1]: latitude 90.5 deg is not in [-90, 90]");
}

TEST(RowMapGeoJsonRead, LongitudeOutOfRange) {
  ExpectError(Collection(Line("lon", "[[-180.25, 45.0], [7.0, 45.0]]")), "feature 0 (id 'lon')",
              "coordinates[0]: longitude -180.25 deg is not in [-180, 180]");
}

TEST(RowMapGeoJsonRead, LineStringWithFewerThanTwoPoints) {
  ExpectError(Collection(Line("one", "[[7.0, 45.0]]")), "feature 0 (id 'one')",
              "a LineString row needs at least 2 positions, has 1");
  ExpectError(Collection(Line("none", "[]")), "feature 0 (id 'none')", "has 0");
}

TEST(RowMapGeoJsonRead, PolygonWithFewerThanThreePoints) {
  ExpectError(Collection(Feature("\"tri\"", R"({"type": "Polygon", "coordinates": [[[7, 45], [7.1, 45], [7, 45]]]})")),
              "feature 0 (id 'tri')", "a Polygon ring needs at least 4 positions");
  ExpectError(Collection(Feature("\"no\"", R"({"type": "Polygon", "coordinates": []})")), "feature 0 (id 'no')",
              "the Polygon has no ring");
}

TEST(RowMapGeoJsonRead, PolygonWithHoles) {
  const std::filesystem::path path = Fixture("polygon_with_hole.geojson");
  try {
    ReadRowMapGeoJson(path);
    FAIL() << "accepted a hole";
  } catch (const MapFormatError& e) {
    EXPECT_EQ(e.source(), path.string());
    EXPECT_EQ(e.location(), "feature 0 (id 'outline-with-hole')");
    EXPECT_THAT(e.reason(), HasSubstr("has 1 hole(s)"));
  }
}

TEST(RowMapGeoJsonRead, UnclosedRing) {
  ExpectError(Collection(Feature("\"open\"", R"({"type": "Polygon", "coordinates": )"
                                             R"([[[7, 45], [7.1, 45], [7.1, 45.1], [7, 45.1]]]})")),
              "feature 0 (id 'open')", "the Polygon ring is not closed");
  // Closing in latitude and longitude but not in altitude is not closed either.
  ExpectError(Collection(Feature("\"alt\"", R"({"type": "Polygon", "coordinates": )"
                                            R"([[[7, 45, 1], [7.1, 45], [7.1, 45.1], [7, 45, 2]]]})")),
              "feature 0 (id 'alt')", "not closed");
}

TEST(RowMapGeoJsonRead, MissingOrigin) {
  ExpectError(R"({"type": "FeatureCollection", "features": [)" + kGoodLine + "]}", "top level",
              "missing the \"rowloc\" member");
  ExpectError(R"({"type": "FeatureCollection", "rowloc": {"format_version": 1}, "features": [)" + kGoodLine + "]}",
              "top level", "missing the local origin");
  ExpectError(R"({"type": "FeatureCollection", "rowloc": {"format_version": 1, "origin": )"
              R"({"latitude_deg": 45, "longitude_deg": 7}}, "features": [)" + kGoodLine + "]}",
              "top level", "\"altitude_m\" is missing");
}

TEST(RowMapGeoJsonRead, InvalidOrigin) {
  ExpectError(R"({"type": "FeatureCollection", "rowloc": {"format_version": 1, "origin": )"
              R"({"latitude_deg": 145, "longitude_deg": 7, "altitude_m": 0}}, "features": [)" + kGoodLine + "]}",
              "top level", "\"rowloc\".\"origin\": latitude 145 deg");
  ExpectError(R"({"type": "FeatureCollection", "rowloc": {"format_version": 1, "origin": )"
              R"({"latitude_deg": "45", "longitude_deg": 7, "altitude_m": 0}}, "features": [)" + kGoodLine + "]}",
              "top level", "\"latitude_deg\" must be a number, got string");
}

TEST(RowMapGeoJsonRead, UnsupportedFormatVersion) {
  ExpectError(R"({"type": "FeatureCollection", "rowloc": {"format_version": 2, "origin": )"
              R"({"latitude_deg": 45, "longitude_deg": 7, "altitude_m": 0}}, "features": [)" + kGoodLine + "]}",
              "top level", "unsupported \"rowloc\".\"format_version\" 2");
  ExpectError(R"({"type": "FeatureCollection", "rowloc": {"origin": )"
              R"({"latitude_deg": 45, "longitude_deg": 7, "altitude_m": 0}}, "features": [)" + kGoodLine + "]}",
              "top level", "\"format_version\" is missing");
}

TEST(RowMapGeoJsonRead, MissingId) {
  ExpectError(Collection(R"({"type": "Feature", "properties": {"name": "r"}, "geometry": )"
                         R"({"type": "LineString", "coordinates": [[7, 45], [7, 46]]}})"),
              "feature 0", "\"properties\".\"id\" is missing");
  ExpectError(Collection(R"({"type": "Feature", "geometry": {"type": "LineString", "coordinates": [[7, 45], [7, 46]]}})"),
              "feature 0", "no \"properties\"");
}

TEST(RowMapGeoJsonRead, OutlineSigmaIsOptionalFiniteAndNonNegative) {
  const auto with_sigma = [](const std::string& sigma_json) {
    return Collection(R"({"type": "Feature", "properties": {"id": "r", "outline_sigma_m": )" + sigma_json +
                      R"(}, "geometry": {"type": "LineString", "coordinates": [[7, 45], [7, 46]]}})");
  };
  EXPECT_DOUBLE_EQ(ParseRowMapGeoJson(with_sigma("0.004"), "test.geojson").rows[0].outline_sigma_m, 0.004);
  EXPECT_DOUBLE_EQ(ParseRowMapGeoJson(Collection(kGoodLine), "test.geojson").rows[0].outline_sigma_m, 0.0);
  ExpectError(with_sigma("-0.01"), "feature 0 (id 'r')", "\"outline_sigma_m\" must be >= 0, got -0.01");
  ExpectError(with_sigma("\"1 cm\""), "feature 0 (id 'r')", "\"outline_sigma_m\" must be a number, got string");
  ExpectError(with_sigma("null"), "feature 0 (id 'r')", "\"outline_sigma_m\" must be a number");
  ExpectError(with_sigma("1e400"), "JSON value /features/0/properties/outline_sigma_m", "number overflow");
}

TEST(RowMapGeoJsonRead, NonStringId) {
  ExpectError(Collection(Feature("12", R"({"type": "LineString", "coordinates": [[7, 45], [7, 46]]})")), "feature 0",
              "\"properties\".\"id\" must be a string, got number 12");
}

TEST(RowMapGeoJsonRead, EmptyId) {
  ExpectError(Collection(kGoodLine + "," + Line("", "[[7, 45], [7, 46]]")), "feature 1", "\"properties\".\"id\" is empty");
}

TEST(RowMapGeoJsonRead, DuplicateId) {
  ExpectError(Collection(Line("r1", "[[7, 45], [7, 46]]") + "," + Line("r2", "[[7.1, 45], [7.1, 46]]") + "," +
                         Line("r1", "[[7.2, 45], [7.2, 46]]")),
              "feature 2 (id 'r1')", "duplicate id 'r1' (also used by feature 0)");
}

TEST(RowMapGeoJsonRead, EmptyFeatureCollection) {
  ExpectError(Collection(""), "top level", "the FeatureCollection has no features");
  ExpectError(kHeader.substr(0, kHeader.rfind(", \"features\"")) + "}", "top level",
              "\"features\" must be an array, got nothing (missing)");
}

TEST(RowMapGeoJsonRead, ZeroLengthSegment) {
  ExpectError(Collection(Line("dup", "[[7, 45], [7.1, 45], [7.1, 45], [7.2, 45]]")), "feature 0 (id 'dup')",
              "coordinates[1] and coordinates[2] are the same point (zero-length segment)");
  ExpectError(Collection(Feature("\"ring\"", R"({"type": "Polygon", "coordinates": )"
                                             R"([[[7, 45], [7.1, 45], [7.1, 45.1], [7.1, 45.1], [7, 45]]]})")),
              "feature 0 (id 'ring')", "coordinates[0][2] and coordinates[0][3] are the same point");
}

std::string Polygon(const std::string& id, const std::string& coordinates) {
  return Feature("\"" + id + "\"", R"({"type": "Polygon", "coordinates": )" + coordinates + "}");
}

TEST(RowMapGeoJsonRead, SelfIntersectingPolygonIsRefusedWithTheDefect) {
  // Issue 26: a bow-tie outline was accepted; with --map the NEES reached 8.9e5. Boost.Geometry's
  // is_valid names the defect and the point.
  const std::string bow_tie = "[[[7.0, 45.0], [7.001, 45.001], [7.001, 45.0], [7.0, 45.001], [7.0, 45.0]]]";
  ExpectError(Collection(kGoodLine + ", " + Polygon("bow", bow_tie)), "feature 1 (id 'bow')",
              "the Polygon outline is not a valid ring: Geometry has invalid self-intersections");
  // A spike: an edge that goes out and comes straight back.
  const std::string spike =
      "[[[7.0, 45.0], [7.001, 45.0], [7.002, 45.0], [7.001, 45.0], [7.001, 45.001], [7.0, 45.0]]]";
  ExpectError(Collection(Polygon("spike", spike)), "feature 0 (id 'spike')", "the Polygon outline is not a valid ring");
  // Zero area: all vertices on one line (the origin's meridian, a straight line in the local frame).
  ExpectError(Collection(Polygon("flat", "[[[7.0, 45.0], [7.0, 45.001], [7.0, 45.002], [7.0, 45.0]]]")),
              "feature 0 (id 'flat')", "the Polygon outline encloses no area");
  // Both vertex orders of a valid ring are accepted.
  EXPECT_NO_THROW(ParseRowMapGeoJson(Collection(Polygon("ccw", "[[[7, 45], [7.001, 45], [7.001, 45.001], [7, 45]]]"))));
  EXPECT_NO_THROW(ParseRowMapGeoJson(Collection(Polygon("cw", "[[[7, 45], [7.001, 45.001], [7.001, 45], [7, 45]]]"))));
}

TEST(RowMapGeoJsonRead, FlatPolygonCoordinatesAreNamedAsSuch) {
  // Issue 26: a ring written without its enclosing array was reported as "has 3 hole(s)".
  ExpectError(Collection(Polygon("flat", "[[7.0, 45.0], [7.001, 45.0], [7.001, 45.001], [7.0, 45.0]]")),
              "feature 0 (id 'flat')",
              "\"coordinates\" of a Polygon must be an array of rings (arrays of [longitude, latitude] positions), "
              "got an array of positions");
  ExpectError(Collection(Polygon("numbers", "[7.0, 45.0]")), "feature 0 (id 'numbers')",
              "must be an array of rings (arrays of [longitude, latitude] positions), got coordinates[0] = number");
}

TEST(RowMapGeoJsonRead, LineStringThatRetracesItselfIsRefused) {
  // Issue 26: 10^6 vertices alternating between two points were accepted (one segment drawn 10^6 times).
  std::string coordinates = "[";
  for (int i = 0; i < 1000; ++i) coordinates += std::string(i ? ", " : "") + (i % 2 ? "[7.0, 45.001]" : "[7.0, 45.0]");
  ExpectError(Collection(Line("zigzag", coordinates + "]")), "feature 0 (id 'zigzag')",
              "the LineString turns back on itself at vertex 1");
}

TEST(RowMapGeoJsonRead, VertexCountsHaveALimit) {
  // Refused before the positions are read; the limits are documented in docs/map-format.md.
  std::string coordinates = "[";
  for (std::size_t i = 0; i <= kMaxRowVertices; ++i) {
    char latitude[32];  // 45 + i * 1e-7 degrees, exactly as text: distinct, collinear
    std::snprintf(latitude, sizeof latitude, "45.%07zu", i);
    coordinates += (i ? ", [7.0, " : "[7.0, ") + std::string(latitude) + "]";
  }
  coordinates += "]";
  ExpectError(Collection(Line("dense", coordinates)), "feature 0 (id 'dense')",
              "the row has 100001 vertices, more than the limit of 100000 per row");
  // Eleven rows of 10^5 vertices: more than 10^6 in all.
  std::string rows;
  const std::string row_coordinates = coordinates.substr(0, coordinates.rfind(", [")) + "]";  // 10^5 vertices
  for (int r = 0; r < 11; ++r) {
    std::string id = "r";  // (not "r" + std::to_string(r): GCC 12's false -Wrestrict)
    id += std::to_string(r);
    rows += (r ? ", " : "") + Line(id, row_coordinates);
  }
  ExpectError(Collection(rows), "feature 10 (id 'r10')", "the map has more than the limit of 1000000 vertices in all");
}

TEST(RowMapGeoJsonRead, MissingFile) {
  const std::filesystem::path path = Fixture("does_not_exist.geojson");
  try {
    ReadRowMapGeoJson(path);
    FAIL() << "read a missing file";
  } catch (const MapFormatError& e) {
    EXPECT_EQ(e.source(), path.string());
    EXPECT_EQ(e.location(), "");
    EXPECT_THAT(e.reason(), HasSubstr("cannot open row map file: No such file or directory"));
    EXPECT_EQ(std::string(e.what()), path.string() + ": " + e.reason());
  }
}

TEST(RowMapGeoJsonRead, DirectoryIsNotAFile) {
  const test::ScratchDir dir;
  try {
    ReadRowMapGeoJson(dir.path());
    FAIL() << "read a directory";
  } catch (const MapFormatError& e) {
    EXPECT_EQ(e.source(), dir.path().string());
    EXPECT_THAT(e.reason(), HasSubstr("is a directory"));
  }
}

TEST(RowMapGeoJsonRead, PathBelowARegularFileIsUnreadable) {
  const test::ScratchDir dir;
  const std::filesystem::path path = dir / "map.geojson";
  std::ofstream(path) << Collection(kGoodLine);
  try {
    ReadRowMapGeoJson(path / "child.geojson");  // a regular file used as a directory
    FAIL() << "read below a regular file";
  } catch (const MapFormatError& e) {
    EXPECT_EQ(e.source(), (path / "child.geojson").string());
    EXPECT_THAT(e.reason(), HasSubstr("cannot open row map file: Not a directory"));
  }
}

TEST(RowMapGeoJsonRead, FileWithoutReadPermissionIsUnreadable) {
  if (::geteuid() == 0) GTEST_SKIP() << "root reads files without read permission";
  const test::ScratchDir dir;
  const std::filesystem::path path = dir / "locked.geojson";
  std::ofstream(path) << Collection(kGoodLine);
  std::filesystem::permissions(path, std::filesystem::perms::none);
  try {
    ReadRowMapGeoJson(path);
    FAIL() << "read a file without permission";
  } catch (const MapFormatError& e) {
    EXPECT_EQ(e.source(), path.string());
    EXPECT_THAT(e.reason(), HasSubstr("Permission denied"));
  }
}

TEST(RowMapGeoJsonRead, Utf8ByteOrderMarkIsAccepted) {
  const geometry::RowMap map = ParseRowMapGeoJson("\xEF\xBB\xBF" + Collection(kGoodLine));
  ASSERT_EQ(map.rows.size(), 1u);
  EXPECT_EQ(map.rows[0].id, "ok");
}

TEST(RowMapGeoJsonRead, InvalidUtf8IsASyntaxError) {
  const std::string text = Collection(Line("bad\xFF", "[[7, 45], [7, 46]]"));
  ExpectError(text, "1:" + std::to_string(text.find('\xFF') + 1), "ill-formed UTF-8 byte; last read: '\"bad\\xFF'");
}

TEST(RowMapGeoJsonRead, DeeplyNestedJsonIsAnErrorNotACrash) {
  const std::string deep = std::string(100000, '[') + std::string(100000, ']');
  ExpectError(deep, "top level", "got array");
  ExpectError(std::string(100000, '['), "1:100001", "unexpected end of input");
}

TEST(RowMapGeoJsonRead, JsonPointerEscapesKeys) {
  ExpectError(kHeader + kGoodLine + R"(], "a/b~c": {"x": 1, "x": 2}})", "JSON value /a~1b~0c/x", "duplicate key 'x'");
}

TEST(MapFormatError, MessageFollowsTheGnuConvention) {
  EXPECT_STREQ(MapFormatError("f.geojson", "3:7", "bad").what(), "f.geojson:3:7: bad");
  EXPECT_STREQ(MapFormatError("f.geojson", "feature 2 (id 'x')", "bad").what(), "f.geojson: feature 2 (id 'x'): bad");
  EXPECT_STREQ(MapFormatError("f.geojson", "", "bad").what(), "f.geojson: bad");
  const MapFormatError e("s", "l", "r");
  EXPECT_EQ(e.source(), "s");
  EXPECT_EQ(e.location(), "l");
  EXPECT_EQ(e.reason(), "r");
}

}  // namespace
}  // namespace rowloc::mapio
