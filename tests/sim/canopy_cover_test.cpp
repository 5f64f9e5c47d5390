#include "rowloc/sim/canopy_cover.hpp"

#include "test_support.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <limits>
#include <numbers>

namespace rowloc::sim {
namespace {

class CanopyCoverTest : public ::testing::Test {
 protected:
  RowWorld world_{LoadRowWorldParams(test::SourceDir() / "config/worlds/vineyard-002.json")};
  CanopyCaster caster_{world_};
  CanopyCover cover_{caster_, world_};
};

TEST_F(CanopyCoverTest, MidLaneMatchesTheWallElevations) {
  // Straight rows along +x, centres at y = 0, 2.5, ...; lane 0 centre y = 1.25. Canopy half-width
  // 0.25 +- 0.03 m, so each wall is 1.0 +- 0.03 m away; top 1.8 m, antenna 1.2 m.
  const auto expected = [](double d) { return 2.0 * std::atan2(0.6, d) / std::numbers::pi; };
  for (double x : {10.0, 20.0, 31.0, 40.0}) {
    for (double heading : {0.0, std::numbers::pi}) {  // either driving direction
      const double c = cover_.At({x, 1.25}, 1.2, heading);
      EXPECT_GE(c, expected(1.031)) << x;
      EXPECT_LE(c, expected(0.969)) << x;
    }
  }
}

TEST_F(CanopyCoverTest, NothingHiddenInTheHeadlandOrAboveTheCanopy) {
  EXPECT_EQ(cover_.At({-4.0, 1.25}, 1.2, 0.0), 0.0);  // beyond the row ends, looking sideways
  EXPECT_EQ(cover_.At({25.0, 1.25}, 2.5, 0.0), 0.0);  // antenna above the canopy top
  EXPECT_GT(cover_.At({25.0, 1.25}, 0.3, 0.0), cover_.At({25.0, 1.25}, 1.2, 0.0));  // lower: more hidden
}

TEST_F(CanopyCoverTest, RejectsNonFiniteInput) {
  const double nan = std::numeric_limits<double>::quiet_NaN();
  EXPECT_THROW(cover_.At({nan, 1.0}, 1.2, 0.0), std::invalid_argument);
  EXPECT_THROW(cover_.At({1.0, 1.0}, nan, 0.0), std::invalid_argument);
  EXPECT_THROW(cover_.At({1.0, 1.0}, 1.2, std::numeric_limits<double>::infinity()), std::invalid_argument);
}

}  // namespace
}  // namespace rowloc::sim
