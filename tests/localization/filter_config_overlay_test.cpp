// Filter files as overlays on the in-code defaults (filter_config.hpp, issue 29): a file lists its
// name and what it changes; "extends" names a base file; a typo anywhere in the chain is refused
// with the file that has it.
#include "rowloc/localization/filter_config.hpp"

#include "test_support.hpp"

#include <gmock/gmock.h>
#include <gtest/gtest.h>
#include <nlohmann/json.hpp>

#include <fstream>
#include <functional>
#include <string>

namespace rowloc::localization {
namespace {

using ::testing::AllOf;
using ::testing::HasSubstr;
using ::testing::Not;
using json = nlohmann::json;

void Write(const std::filesystem::path& path, const json& document) {
  std::filesystem::create_directories(path.parent_path());
  std::ofstream(path) << document.dump(2);
}

std::string LoadError(const std::filesystem::path& path) {
  try {
    LoadFilterConfig(path);
  } catch (const FilterConfigError& e) {
    return e.what();
  }
  return "";
}

/// The complete document of `config` with the complete document of the defaults changed by `edit`.
json Expected(const std::function<void(json&)>& edit) {
  json document = json::parse(FilterConfigJson(FilterConfig{}));
  edit(document);
  return document;
}

json Shown(const FilterConfig& config) { return json::parse(FilterConfigJson(config)); }

TEST(FilterOverlay, AFileChangesOnlyTheKeysItLists) {
  const test::ScratchDir dir;
  Write(dir / "bias.json", {{"name", "bias"}, {"gps", {{"estimate_bias", true}, {"bias_sigma_m", 0.25}}},
                            {"max_time_jump_s", 60.0}});
  EXPECT_EQ(Shown(LoadFilterConfig(dir / "bias.json")), Expected([](json& d) {
              d["name"] = "bias";
              d["gps"]["estimate_bias"] = true;
              d["gps"]["bias_sigma_m"] = 0.25;
              d["max_time_jump_s"] = 60.0;
            }));
}

TEST(FilterOverlay, ANameAloneIsTheDefaults) {
  const test::ScratchDir dir;
  Write(dir / "plain.json", {{"name", "plain"}});
  EXPECT_EQ(Shown(LoadFilterConfig(dir / "plain.json")), Expected([](json& d) { d["name"] = "plain"; }));
}

TEST(FilterOverlay, ExtendsMergesTheBaseFirstAndTheFileWins) {
  const test::ScratchDir dir;
  Write(dir / "shared" / "canopy.json",
        {{"name", "canopy"}, {"gps", {{"estimate_bias", true}}}, {"wheels", {{"speed_update_iterations", 3}}}});
  Write(dir / "robot" / "flat.json", {{"name", "flat"}, {"extends", "../shared/canopy.json"},
                                      {"wheels", {{"speed_update_iterations", 1}, {"speed_sigma_radps", 0.05}}}});
  EXPECT_EQ(Shown(LoadFilterConfig(dir / "robot" / "flat.json")), Expected([](json& d) {
              d["name"] = "flat";
              d["gps"]["estimate_bias"] = true;
              d["wheels"]["speed_sigma_radps"] = 0.05;
            }));
  const std::vector<std::filesystem::path> files = FilterConfigFiles(dir / "robot" / "flat.json");
  ASSERT_EQ(files.size(), 2u);
  EXPECT_EQ(files[0].filename(), "canopy.json");
  EXPECT_EQ(files[1], dir / "robot" / "flat.json");
}

TEST(FilterOverlay, AnUnknownKeyIsRefusedWithItsFile) {
  const test::ScratchDir dir;
  Write(dir / "typo.json", {{"name", "typo"}, {"gps", {{"estimate_bais", true}}}});
  EXPECT_THAT(LoadError(dir / "typo.json"), HasSubstr((dir / "typo.json").string() + ": gps.estimate_bais: unknown key"));
  Write(dir / "section.json", {{"name", "section"}, {"gnss", {{"sigma_scale", 2.0}}}});
  EXPECT_THAT(LoadError(dir / "section.json"), HasSubstr("section.json: gnss: unknown key"));
}

TEST(FilterOverlay, AnUnknownKeyInABaseIsRefusedWithTheBase) {
  const test::ScratchDir dir;
  Write(dir / "base.json", {{"name", "base"}, {"wheels", {{"speed_sigma", 0.05}}}});
  Write(dir / "leaf.json", {{"name", "leaf"}, {"extends", "base.json"}, {"wheels", {{"speed_sigma_radps", 0.05}}}});
  EXPECT_THAT(LoadError(dir / "leaf.json"),
              AllOf(HasSubstr((dir / "base.json").string() + ": wheels.speed_sigma: unknown key"),
                    Not(HasSubstr("leaf.json"))));
}

TEST(FilterOverlay, AWrongTypeIsRefusedWithItsFile) {
  const test::ScratchDir dir;
  Write(dir / "base.json", {{"name", "base"}, {"imu", {{"estimate_accel_bias", "yes"}}}});
  Write(dir / "leaf.json", {{"name", "leaf"}, {"extends", "base.json"}});
  EXPECT_THAT(LoadError(dir / "leaf.json"),
              HasSubstr("base.json: imu.estimate_accel_bias: must be true or false, got string"));
  Write(dir / "null.json", {{"name", "null"}, {"gps", nullptr}});
  EXPECT_THAT(LoadError(dir / "null.json"), HasSubstr("null.json: gps: must be an object, got null"));
}

TEST(FilterOverlay, EveryFileOfAChainNamesItself) {
  const test::ScratchDir dir;
  Write(dir / "base.json", {{"name", "base"}});
  Write(dir / "leaf.json", {{"extends", "base.json"}, {"gps", {{"estimate_bias", true}}}});
  EXPECT_THAT(LoadError(dir / "leaf.json"), HasSubstr("leaf.json: name: missing key"));
}

TEST(FilterOverlay, ValueRulesApplyToTheMergedValuesAndNameTheFileAskedFor) {
  const test::ScratchDir dir;
  // Each file alone is valid; merged, the time jump is below the prediction gap.
  Write(dir / "base.json", {{"name", "base"}, {"max_prediction_gap_s", 100.0}, {"max_time_jump_s", 200.0}});
  Write(dir / "leaf.json", {{"name", "leaf"}, {"extends", "base.json"}, {"max_time_jump_s", 50.0}});
  EXPECT_THAT(LoadError(dir / "leaf.json"),
              HasSubstr((dir / "leaf.json").string() + ": max_time_jump_s must be >= max_prediction_gap_s"));
  Write(dir / "range.json", {{"name", "range"}, {"gps", {{"gate_probability", 1.5}}}});
  EXPECT_THAT(LoadError(dir / "range.json"), HasSubstr("range.json: gps.gate_probability must be in"));
}

TEST(FilterOverlay, ExtendsErrorsNameTheFile) {
  const test::ScratchDir dir;
  Write(dir / "a.json", {{"name", "a"}, {"extends", "b.json"}});
  Write(dir / "b.json", {{"name", "b"}, {"extends", "a.json"}});
  EXPECT_THAT(LoadError(dir / "a.json"), AllOf(HasSubstr("b.json: extends: a cycle: "), HasSubstr("a.json -> ")));
  Write(dir / "lost.json", {{"name", "lost"}, {"extends", "no-such-filter.json"}});
  EXPECT_THAT(LoadError(dir / "lost.json"),
              AllOf(HasSubstr("lost.json: extends: "), HasSubstr("no-such-filter.json: cannot open filter file")));
  Write(dir / "number.json", {{"name", "number"}, {"extends", 3}});
  EXPECT_THAT(LoadError(dir / "number.json"), HasSubstr("number.json: extends: must name a file"));
}

TEST(FilterOverlay, TextWithoutAFileCannotExtend) {
  try {
    ParseFilterConfig(R"({"name": "inline", "extends": "default.json"})", "filter_config");
    FAIL() << "extends accepted without a file";
  } catch (const FilterConfigError& e) {
    EXPECT_THAT(e.what(), HasSubstr("filter_config: extends: only a file can extend another"));
  }
}

TEST(FilterOverlay, TextReadByTheCallerResolvesExtendsAgainstItsPath) {
  const test::ScratchDir dir;
  Write(dir / "base.json", {{"name", "base"}, {"steering", {{"angle_sigma_rad", 0.002}}}});
  const FilterConfig config =
      ParseFilterConfigFile(R"({"name": "leaf", "extends": "base.json"})", dir / "leaf.json");
  EXPECT_EQ(config.name, "leaf");
  EXPECT_EQ(config.steering.angle_sigma_rad, 0.002);
}

TEST(FilterOverlay, AMissingFileIsAFilterConfigErrorNamingIt) {
  const test::ScratchDir dir;
  EXPECT_THAT(LoadError(dir / "absent.json"), HasSubstr("absent.json: cannot open filter file"));
}

}  // namespace
}  // namespace rowloc::localization
