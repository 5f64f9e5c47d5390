// CompareRowMaps: identical maps, a shift, a missed and an invented row, different origins.
#include "rowloc/mapping/map_comparison.hpp"

#include "rowloc/mapio/local_frame.hpp"

#include <gmock/gmock.h>
#include <gtest/gtest.h>
#include <nlohmann/json.hpp>

#include <stdexcept>

namespace rowloc::mapping {
namespace {

geometry::Row Box(const std::string& id, double x0, double x1, double y, double w = 0.25) {
  return geometry::Row{id, {{x0, y - w}, {x1, y - w}, {x1, y + w}, {x0, y + w}}, true, 0.0};
}

geometry::RowMap Map(std::vector<geometry::Row> rows) {
  geometry::RowMap map;
  map.origin = {45.0, 7.0, 200.0};
  map.rows = std::move(rows);
  return map;
}

TEST(MapComparisonTest, IdenticalMapsAreAtZero) {
  const auto map = Map({Box("row-1", 0, 10, 0), Box("row-2.part-1", 0, 4, 2.5), Box("row-2.part-2", 5, 10, 2.5)});
  const MapComparison c = CompareRowMaps(map, map);
  EXPECT_EQ(c.truth_rows, 2U);
  EXPECT_EQ(c.truth_parts, 3U);
  EXPECT_EQ(c.truth_parts_found, 3U);
  EXPECT_EQ(c.truth_rows_found, 2U);
  EXPECT_TRUE(c.missed.empty());
  EXPECT_TRUE(c.invented.empty());
  EXPECT_NEAR(c.p95_m, 0.0, 1e-12);
  EXPECT_NEAR(c.max_m, 0.0, 1e-12);
  ASSERT_EQ(c.matches.size(), 3U);
  EXPECT_EQ(c.matches[1].truth_id, "row-2.part-1");
}

TEST(MapComparisonTest, AShiftAcrossTheRowsIsMeasured) {
  // Built 1 cm north of the truth: long faces are 1 cm away, the caps' samples near 0 .. 1 cm.
  const auto truth = Map({Box("a", 0, 20, 0)});
  const auto built = Map({Box("a", 0, 20, 0.01)});
  const MapComparison c = CompareRowMaps(built, truth);
  EXPECT_NEAR(c.p95_m, 0.01, 1e-9);
  EXPECT_NEAR(c.max_m, 0.01, 1e-9);
}

TEST(MapComparisonTest, TheRmsErrorIsSetBesideTheMapsOwnStatedSigma) {
  // Long faces 1 cm off, the caps mostly on the truth: the RMS is below 1 cm and above 0.9 cm
  // (caps are 0.5 m of each 41 m of outline). The stated sigma is the parts' outline_sigma_m,
  // weighted by their samples: 2 mm on a 20 m part and 4 mm on a 2 m part is nearer to 2 mm.
  const auto truth = Map({Box("a", 0, 20, 0), Box("b", 0, 2, 3)});
  auto built = Map({Box("a", 0, 20, 0.01), Box("b", 0, 2, 3.01)});
  built.rows[0].outline_sigma_m = 0.002;
  built.rows[1].outline_sigma_m = 0.004;
  const MapComparison c = CompareRowMaps(built, truth);
  EXPECT_GT(c.built_to_truth_rms_m, 0.009);
  EXPECT_LT(c.built_to_truth_rms_m, 0.01);
  ASSERT_EQ(c.matches.size(), 2U);
  EXPECT_EQ(c.matches[0].stated_sigma_m, 0.002);
  EXPECT_EQ(c.matches[1].stated_sigma_m, 0.004);
  EXPECT_GT(c.matches[1].rms_m, 0.008);
  EXPECT_GT(c.stated_sigma_rms_m, 0.002);
  EXPECT_LT(c.stated_sigma_rms_m, 0.0025);
  const std::string text = FormatMapComparison(c);
  EXPECT_NE(text.find("(stated 0.0040 m)"), std::string::npos) << text;
  const auto json = nlohmann::json::parse(FormatMapComparisonJson(c));
  EXPECT_NEAR(json.at("stated_sigma_rms_m").get<double>(), c.stated_sigma_rms_m, 1e-12);
  EXPECT_EQ(json.at("parts").at(1).at("stated_sigma_m").get<double>(), 0.004);
  // Identical maps: zero error whatever they state.
  EXPECT_NEAR(CompareRowMaps(built, built).built_to_truth_rms_m, 0.0, 1e-12);
}

TEST(MapComparisonTest, LargestDistanceToOutlinesIsTheDirectedHausdorffDistance) {
  // A box 3 cm wider on one side: its far face is 3 cm from the truth's outline, the rest on it.
  const auto truth = Map({Box("a", 0, 10, 0)});
  const auto wider = Map({geometry::Row{"b", {{0, -0.25}, {10, -0.25}, {10, 0.28}, {0, 0.28}}, true, 0.0}});
  EXPECT_NEAR(LargestDistanceToOutlines(wider, truth, 0.01), 0.03, 1e-9);
  EXPECT_NEAR(LargestDistanceToOutlines(truth, truth, 0.01), 0.0, 1e-12);
  // An open cut (a polyline) is sampled to its last point; a repeated vertex in `to` is harmless.
  const auto open = Map({geometry::Row{"c", {{0, 0.35}, {10, 0.35}}, false, 0.0}});
  EXPECT_NEAR(LargestDistanceToOutlines(open, truth, 0.01), 0.10, 1e-9);
  const auto repeated = Map({geometry::Row{"d", {{0, -0.25}, {10, -0.25}, {10, -0.25}, {10, 0.25}, {0, 0.25}}, true, 0.0}});
  EXPECT_NEAR(LargestDistanceToOutlines(truth, repeated, 0.01), 0.0, 1e-12);
  EXPECT_EQ(LargestDistanceToOutlines(Map({}), truth, 0.01), 0.0);
  EXPECT_TRUE(std::isinf(LargestDistanceToOutlines(truth, Map({}), 0.01)));
  EXPECT_THROW(LargestDistanceToOutlines(truth, truth, 0.0), std::invalid_argument);
}

TEST(MapComparisonTest, MissedAndInventedRowsAreNamed) {
  const auto truth = Map({Box("row-1", 0, 10, 0), Box("row-2", 0, 10, 2.5)});
  const auto built = Map({Box("row-1", 0, 10, 0), Box("row-9", 0, 10, 6.0)});
  const MapComparison c = CompareRowMaps(built, truth);
  EXPECT_EQ(c.missed, std::vector<std::string>{"row-2"});
  EXPECT_EQ(c.invented, std::vector<std::string>{"row-9"});
  EXPECT_EQ(c.truth_rows_found, 1U);
  EXPECT_NEAR(c.max_m, 2.5 + 0.0, 1.0);  // an unmatched row is far from everything
  EXPECT_THAT(FormatMapComparison(c), ::testing::HasSubstr("missed: row-2"));
  EXPECT_THAT(FormatMapComparisonJson(c), ::testing::HasSubstr("\"invented\": [\n    \"row-9\""));
}

TEST(MapComparisonTest, DifferentOriginsAreComparedThroughWgs84) {
  const auto truth = Map({Box("a", 0, 20, 0)});
  // The same rectangle expressed around an origin 100 m east and 50 m north.
  const mapio::LocalFrame frame(truth.origin);
  const geometry::GeoOrigin moved = frame.ToGeodetic({100.0, 50.0, 0.0});
  const mapio::LocalFrame other(moved);
  geometry::RowMap built = truth;
  built.origin = moved;
  for (auto& p : built.rows[0].points_m) {
    const auto g = frame.ToGeodetic({p.x(), p.y(), 0.0});
    p = other.ToEnu(g.latitude_deg, g.longitude_deg, g.altitude_m).head<2>();
  }
  const MapComparison c = CompareRowMaps(built, truth);
  EXPECT_LT(c.max_m, 1e-3);
  EXPECT_THROW(CompareRowMaps(built, truth, MapComparisonParams{0.0, 0.3}), std::invalid_argument);
  EXPECT_THROW(CompareRowMaps(Map({}), truth), std::invalid_argument);
}

}  // namespace
}  // namespace rowloc::mapping
