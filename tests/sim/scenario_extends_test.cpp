// Scenarios that extend another (scenario.hpp, "extends"; issue 29): every shipped scenario still
// reads to the document it was before the variants became overlays (tests/data/config-expanded/
// scenarios: copies of the files as they were), the merge rule, paths of bases in other
// directories, and the errors of a chain.
#include "rowloc/sim/scenario.hpp"

#include "test_support.hpp"

#include <gmock/gmock.h>
#include <gtest/gtest.h>
#include <nlohmann/json.hpp>

#include <filesystem>
#include <fstream>
#include <set>
#include <string>

namespace rowloc::sim {
namespace {

using ::testing::AllOf;
using ::testing::HasSubstr;
using json = nlohmann::json;

std::filesystem::path ScenarioDir() { return test::SourceDir() / "config" / "scenarios"; }
std::filesystem::path FixtureDir() { return test::SourceDir() / "tests" / "data" / "config-expanded" / "scenarios"; }

json Read(const std::filesystem::path& path) {
  std::ifstream in(path);
  return json::parse(in);
}

void Write(const std::filesystem::path& path, const json& document) {
  std::filesystem::create_directories(path.parent_path());
  std::ofstream(path) << document.dump(2);
}

std::string LoadError(const std::filesystem::path& path) {
  try {
    LoadScenario(path);
  } catch (const ScenarioError& e) {
    return e.what();
  }
  return "";
}

std::set<std::string> JsonStems(const std::filesystem::path& dir) {
  std::set<std::string> stems;
  for (const auto& entry : std::filesystem::directory_iterator(dir)) {
    if (entry.path().extension() == ".json") stems.insert(entry.path().stem().string());
  }
  return stems;
}

TEST(ShippedScenarioFiles, EveryScenarioReadsToItsRecordedDocument) {
  EXPECT_EQ(JsonStems(ScenarioDir()), JsonStems(FixtureDir()));
  for (const std::string& name : JsonStems(ScenarioDir())) {
    SCOPED_TRACE(name);
    EXPECT_EQ(json::parse(ExpandedScenarioJson(ScenarioDir() / (name + ".json"))),
              Read(FixtureDir() / (name + ".json")));
  }
}

// The expanded document is what the loader reads: a fixture parsed as the scenario's own text
// (in its directory) gives the same scenario, down to the simulated wheel encoder and the filters.
TEST(ShippedScenarioFiles, TheWhiteEncoderOverlaysLoadAsTheirRecordedDocuments) {
  for (const std::string base :
       {"agrimaro-tiles", "agrimaro-grass", "agrimaro-gravel", "slip-odometry-loops", "slip-odometry-turns"}) {
    const std::string name = base + "-white-encoder";
    SCOPED_TRACE(name);
    const Scenario overlay = LoadScenario(ScenarioDir() / (name + ".json"));
    const Scenario recorded = ParseScenario(Read(FixtureDir() / (name + ".json")).dump(), name, ScenarioDir());
    EXPECT_EQ(overlay.name, recorded.name);
    EXPECT_EQ(overlay.description, recorded.description);
    EXPECT_EQ(overlay.seed, recorded.seed);
    EXPECT_EQ(overlay.vehicle, recorded.vehicle);
    EXPECT_EQ(overlay.wheel_encoder, recorded.wheel_encoder);
    EXPECT_EQ(overlay.filter_files, recorded.filter_files);
    EXPECT_EQ(overlay.truth_rate_hz, recorded.truth_rate_hz);
  }
}

TEST(ScenarioExtends, TheFileIsMergedOntoItsBase) {
  const test::ScratchDir dir;
  json base = Read(ScenarioDir() / "agrimaro-tiles.json");
  for (const char* key : {"vehicle", "sensor_profiles", "terrains"}) {  // absolute: the base moved
    base[key] = std::filesystem::absolute(ScenarioDir() / base[key].get<std::string>()).lexically_normal().string();
  }
  Write(dir / "tiles.json", base);
  Write(dir / "mine" / "variant.json",
        {{"name", "variant"}, {"extends", "../tiles.json"}, {"seed", 7}, {"sensors", {{"gnss", nullptr}}}});
  const json expanded = json::parse(ExpandedScenarioJson(dir / "mine" / "variant.json"));
  EXPECT_EQ(expanded["seed"], 7);
  EXPECT_TRUE(expanded["sensors"].contains("gnss"));  // null is a value: "no receiver"
  EXPECT_TRUE(expanded["sensors"]["gnss"].is_null());
  EXPECT_EQ(expanded["sensors"]["imu"], base["sensors"]["imu"]);
  const Scenario variant = LoadScenario(dir / "mine" / "variant.json");
  EXPECT_EQ(variant.name, "variant");
  EXPECT_FALSE(variant.gnss.has_value());
  EXPECT_EQ(variant.vehicle.name, "agrimaro-swerve");
}

TEST(ScenarioExtends, BasePathsInAnotherDirectoryAreRebased) {
  const test::ScratchDir dir;
  json base = Read(ScenarioDir() / "agrimaro-tiles.json");
  for (const char* key : {"vehicle", "sensor_profiles", "terrains"}) {
    base[key] = std::filesystem::relative(ScenarioDir() / base[key].get<std::string>(), dir / "a").string();
  }
  base["filters"] = {std::filesystem::relative(test::SourceDir() / "config/filters/differential.json", dir / "a")};
  Write(dir / "a" / "base.json", base);
  Write(dir / "b" / "c" / "variant.json", {{"name", "variant"}, {"extends", "../../a/base.json"}});
  const Scenario variant = LoadScenario(dir / "b" / "c" / "variant.json");
  EXPECT_EQ(variant.vehicle.name, "agrimaro-swerve");
  ASSERT_EQ(variant.filter_files.size(), 1u);
  EXPECT_TRUE(std::filesystem::equivalent(variant.filter_files[0], test::SourceDir() / "config/filters/differential.json"));
}

TEST(ScenarioExtends, UnknownKeysOfAnOverlayAreRefused) {
  const test::ScratchDir dir;
  Write(dir / "variant.json", {{"name", "variant"}, {"extends", (ScenarioDir() / "agrimaro-tiles.json").string()},
                               {"sensors", {{"wheel_encoder", {{"profil", "wheel_encoder_white"}}}}}});
  EXPECT_THAT(LoadError(dir / "variant.json"),
              HasSubstr((dir / "variant.json").string() + ": sensors.wheel_encoder.profil: unknown key"));
}

TEST(ScenarioExtends, ChainErrorsNameTheFiles) {
  const test::ScratchDir dir;
  Write(dir / "a.json", {{"name", "a"}, {"extends", "b.json"}});
  Write(dir / "b.json", {{"name", "b"}, {"extends", "a.json"}});
  EXPECT_THAT(LoadError(dir / "a.json"), AllOf(HasSubstr("b.json: extends: a cycle: "), HasSubstr("a.json -> ")));
  Write(dir / "lost.json", {{"name", "lost"}, {"extends", "gone.json"}});
  EXPECT_THAT(LoadError(dir / "lost.json"),
              AllOf(HasSubstr("lost.json: extends: "), HasSubstr("gone.json: cannot open scenario file")));
  EXPECT_THAT([] { ExpandedScenarioJson("no-such-scenario.json"); },
              ::testing::ThrowsMessage<ScenarioError>(HasSubstr("no-such-scenario.json: cannot open scenario file")));
}

TEST(ScenarioExtends, TextResolvesItsBaseAgainstTheGivenDirectory) {
  const Scenario scenario = ParseScenario(
      R"({"name": "text", "extends": "agrimaro-tiles.json", "seed": 3})", "text.json", ScenarioDir());
  EXPECT_EQ(scenario.name, "text");
  EXPECT_EQ(scenario.seed, 3u);
  EXPECT_EQ(scenario.vehicle.name, "agrimaro-swerve");
}

}  // namespace
}  // namespace rowloc::sim
