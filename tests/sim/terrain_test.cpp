#include "rowloc/sim/terrain.hpp"

#include "rowloc/sim/wheel_slip.hpp"
#include "test_support.hpp"

#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include <fstream>
#include <limits>
#include <string>

namespace rowloc::sim {
namespace {

using ::testing::AllOf;
using ::testing::HasSubstr;

std::string ValidJson() {
  return R"({"terrains": {
    "tiles":  {"traction_coefficient_max": 0.8, "shear_slip_constant": 0.1,
               "rolling_resistance_coefficient": 0.0197, "rolling_radius_factor": 1.0},
    "grass":  {"traction_coefficient_max": 0.55, "shear_slip_constant": 0.3,
               "rolling_resistance_coefficient": 0.1002, "rolling_radius_factor": 0.98},
    "gravel": {"traction_coefficient_max": 0.5, "shear_slip_constant": 0.25,
               "rolling_resistance_coefficient": 0.113, "rolling_radius_factor": 0.97},
    "mud":    {"traction_coefficient_max": 0.41, "shear_slip_constant": 0.25,
               "rolling_resistance_coefficient": 0.1508, "rolling_radius_factor": 0.95}}})";
}

// Replaces the first occurrence of `from` in the valid document.
std::string ValidJsonWith(const std::string& from, const std::string& to) {
  std::string text = ValidJson();
  const auto at = text.find(from);
  EXPECT_NE(at, std::string::npos) << from;
  return text.replace(at, from.size(), to);
}

std::string ErrorOf(const std::string& text) {
  try {
    ParseTerrainSlipTable(text, "test.json");
  } catch (const TerrainConfigError& error) {
    return error.what();
  }
  return "(no error)";
}

TEST(TerrainClassTest, NamesRoundTrip) {
  for (const auto terrain : kAllTerrainClasses) {
    EXPECT_EQ(TerrainClassFromName(TerrainClassName(terrain)), terrain);
  }
  EXPECT_EQ(TerrainClassFromName("sand"), std::nullopt);
  EXPECT_EQ(TerrainClassFromName("Tiles"), std::nullopt);
}

TEST(TerrainSlipTableTest, ShippedFileEqualsDefaults) {
  const auto loaded = LoadTerrainSlipTable(test::SourceDir() / "config" / "terrains.json");
  EXPECT_EQ(loaded, TerrainSlipTable::Defaults());
  EXPECT_EQ(ParseTerrainSlipTable(ValidJson(), "inline"), TerrainSlipTable::Defaults());
}

// Danzi 2026 ch. 7: steady slip at constant speed, tiles <= 0.01, grass 0.116-0.135,
// gravel 0.122-0.146; mud larger than both.
TEST(TerrainSlipTableTest, DefaultsReproduceAgriMaRoSteadySlip) {
  const auto table = TerrainSlipTable::Defaults();
  const auto steady = [&](TerrainClass terrain) {
    const auto& p = table.At(terrain);
    return JanosiHanamotoCurve(p).SlipFor(p.rolling_resistance_coefficient).slip;
  };
  EXPECT_GT(steady(TerrainClass::kTiles), 0.0);
  EXPECT_LE(steady(TerrainClass::kTiles), 0.01);
  EXPECT_NEAR(steady(TerrainClass::kGrass), 0.125, 0.005);
  EXPECT_NEAR(steady(TerrainClass::kGravel), 0.134, 0.005);
  EXPECT_NEAR(steady(TerrainClass::kMud), 0.25, 0.01);
}

TEST(TerrainSlipTableTest, DefaultsCanAccelerateAtOneMeterPerSecondSquared) {
  // 1 m/s^2 needs mu = c_rr + a/g at the wheel (point mass); it must be below mu(1).
  const auto table = TerrainSlipTable::Defaults();
  for (const auto terrain : kAllTerrainClasses) {
    const auto& p = table.At(terrain);
    EXPECT_LT(p.rolling_resistance_coefficient + 1.0 / 9.80665,
              JanosiHanamotoCurve(p).MaxTractionCoefficient())
        << TerrainClassName(terrain);
  }
}

TEST(TerrainSlipTableTest, SetRejectsBadParameters) {
  auto table = TerrainSlipTable::Defaults();
  auto params = table.At(TerrainClass::kGrass);
  params.shear_slip_constant = -0.1;
  EXPECT_THROW(table.Set(TerrainClass::kGrass, params), std::invalid_argument);
  EXPECT_EQ(table.At(TerrainClass::kGrass), TerrainSlipTable::Defaults().At(TerrainClass::kGrass));
}

TEST(TerrainSlipParamsProblemTest, NamesEachField) {
  const TerrainSlipParams good = TerrainSlipTable::Defaults().At(TerrainClass::kGravel);
  EXPECT_EQ(TerrainSlipParamsProblem(good), std::nullopt);
  const double nan = std::numeric_limits<double>::quiet_NaN();
  struct Case {
    double TerrainSlipParams::*field;
    double value;
    const char* name;
  };
  const Case cases[] = {
      {&TerrainSlipParams::traction_coefficient_max, 0.0, "traction_coefficient_max"},
      {&TerrainSlipParams::traction_coefficient_max, nan, "traction_coefficient_max"},
      {&TerrainSlipParams::shear_slip_constant, -0.2, "shear_slip_constant"},
      {&TerrainSlipParams::shear_slip_constant, nan, "shear_slip_constant"},
      {&TerrainSlipParams::rolling_resistance_coefficient, -0.01, "rolling_resistance_coefficient"},
      {&TerrainSlipParams::rolling_resistance_coefficient, 0.45, "full slip"},
      {&TerrainSlipParams::rolling_radius_factor, 0.4, "rolling_radius_factor"},
      {&TerrainSlipParams::rolling_radius_factor, nan, "rolling_radius_factor"},
  };
  for (const auto& c : cases) {
    TerrainSlipParams bad = good;
    bad.*(c.field) = c.value;
    const auto problem = TerrainSlipParamsProblem(bad);
    ASSERT_TRUE(problem.has_value()) << c.name;
    EXPECT_THAT(*problem, HasSubstr(c.name));
  }
}

TEST(TerrainSlipTableParseTest, MissingFieldNamesFileAndKey) {
  const auto text = ValidJsonWith(R"("rolling_radius_factor": 0.98)", R"("unused_padding_is_not_allowed": 1)");
  EXPECT_THAT(ErrorOf(text), AllOf(HasSubstr("test.json"), HasSubstr("terrains.grass.unused_padding_is_not_allowed"),
                                   HasSubstr("unknown key")));
  std::string missing = ValidJsonWith(R"(, "rolling_radius_factor": 0.98)", "");
  EXPECT_THAT(ErrorOf(missing), AllOf(HasSubstr("test.json"), HasSubstr("terrains.grass.rolling_radius_factor"),
                                      HasSubstr("missing")));
}

TEST(TerrainSlipTableParseTest, MissingTerrainClass) {
  const auto text = ValidJsonWith(R"("mud":)", R"("swamp":)");
  EXPECT_THAT(ErrorOf(text), AllOf(HasSubstr("terrains.swamp"), HasSubstr("unknown terrain class")));
  const auto without_terrains = R"({"terrain": {}})";
  EXPECT_THAT(ErrorOf(without_terrains), AllOf(HasSubstr("terrain"), HasSubstr("unknown key")));
  EXPECT_THAT(ErrorOf("{}"), AllOf(HasSubstr("terrains"), HasSubstr("missing")));
}

TEST(TerrainSlipTableParseTest, WrongTypeNaNAndNegative) {
  EXPECT_THAT(ErrorOf(ValidJsonWith(R"("shear_slip_constant": 0.1)", R"("shear_slip_constant": "0.1")")),
              AllOf(HasSubstr("terrains.tiles.shear_slip_constant"), HasSubstr("must be a number, got string")));
  EXPECT_THAT(ErrorOf(ValidJsonWith(R"("shear_slip_constant": 0.1)", R"("shear_slip_constant": -0.1)")),
              AllOf(HasSubstr("terrains.tiles"), HasSubstr("shear_slip_constant must be finite and > 0")));
  // JSON has no NaN literal: "NaN" is a parse error; a number too large for a double is infinite.
  EXPECT_THAT(ErrorOf(ValidJsonWith(R"("shear_slip_constant": 0.1)", R"("shear_slip_constant": NaN)")),
              HasSubstr("invalid JSON"));
  EXPECT_THAT(ErrorOf(ValidJsonWith(R"("shear_slip_constant": 0.1)", R"("shear_slip_constant": 1e999)")),
              HasSubstr("test.json"));
  EXPECT_THAT(ErrorOf(R"({"terrains": 5})"), AllOf(HasSubstr("terrains"), HasSubstr("must be an object, got number")));
  EXPECT_THAT(ErrorOf("[1, 2]"), AllOf(HasSubstr("test.json"), HasSubstr("must be an object, got array")));
}

TEST(TerrainSlipTableParseTest, MissingFileIsReported) {
  const test::ScratchDir scratch;
  const auto path = scratch.path() / "absent.json";
  try {
    LoadTerrainSlipTable(path);
    FAIL() << "expected TerrainConfigError";
  } catch (const TerrainConfigError& error) {
    EXPECT_THAT(error.what(), AllOf(HasSubstr("absent.json"), HasSubstr("cannot open")));
  }
}

TEST(TerrainSlipTableParseTest, LoadsAWrittenFile) {
  const test::ScratchDir scratch;
  const auto path = scratch.path() / "terrains.json";
  std::ofstream(path) << ValidJsonWith(R"("traction_coefficient_max": 0.41)", R"("traction_coefficient_max": 0.5)");
  const auto table = LoadTerrainSlipTable(path);
  EXPECT_DOUBLE_EQ(table.At(TerrainClass::kMud).traction_coefficient_max, 0.5);
  EXPECT_EQ(table.At(TerrainClass::kTiles), TerrainSlipTable::Defaults().At(TerrainClass::kTiles));
}

}  // namespace
}  // namespace rowloc::sim
