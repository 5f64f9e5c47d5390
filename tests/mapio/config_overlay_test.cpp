// Configuration overlays (config_overlay.hpp): the merge rule and "extends" chains with their
// errors (cycles, missing bases, depth, wrong values).
#include "rowloc/mapio/config_overlay.hpp"

#include "test_support.hpp"

#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include <fstream>
#include <string>

namespace rowloc::mapio {
namespace {

using ::testing::AllOf;
using ::testing::HasSubstr;
using json = nlohmann::json;

void Write(const std::filesystem::path& path, const std::string& text) {
  std::filesystem::create_directories(path.parent_path());
  std::ofstream(path) << text;
}

/// The message of the ConfigOverlayError thrown by `read` ("" when nothing is thrown).
template <typename Read>
std::string ErrorOf(Read&& read) {
  try {
    read();
  } catch (const ConfigOverlayError& e) {
    return e.what();
  }
  return "";
}

TEST(MergeOverlay, ObjectsMergeKeyByKeyAndEverythingElseReplaces) {
  json base = json::parse(R"({"a": {"x": 1, "y": 2, "deep": {"p": 1, "q": 2}}, "list": [1, 2, 3],
                              "gnss": {"profile": "sbas"}, "keep": "me", "n": 1})");
  const json overlay = json::parse(R"({"a": {"y": 20, "deep": {"q": 3}, "new": true}, "list": [9],
                                       "gnss": null, "n": {"now": "an object"}})");
  MergeOverlay(base, overlay);
  EXPECT_EQ(base, json::parse(R"({"a": {"x": 1, "y": 20, "deep": {"p": 1, "q": 3}, "new": true}, "list": [9],
                                  "gnss": null, "keep": "me", "n": {"now": "an object"}})"));
}

TEST(MergeOverlay, NullIsAValueNotADeletion) {  // unlike RFC 7386: "gnss": null means "no receiver"
  json base = json::parse(R"({"gnss": {"profile": "sbas"}})");
  MergeOverlay(base, json::parse(R"({"gnss": null})"));
  ASSERT_TRUE(base.contains("gnss"));
  EXPECT_TRUE(base["gnss"].is_null());
}

TEST(MergeOverlay, AnObjectReplacesAScalarAndAScalarAnObject) {
  json base = json::parse(R"({"a": 1, "b": {"c": 2}})");
  MergeOverlay(base, json::parse(R"({"a": {"x": 1}, "b": 5})"));
  EXPECT_EQ(base, json::parse(R"({"a": {"x": 1}, "b": 5})"));
}

TEST(ReadConfigLayers, AFileWithoutExtendsIsOneLayer) {
  const test::ScratchDir dir;
  Write(dir / "a.json", R"({"name": "a", "v": 1})");
  const std::vector<ConfigLayer> layers = ReadConfigLayers(dir / "a.json", "test file");
  ASSERT_EQ(layers.size(), 1u);
  EXPECT_EQ(layers[0].file, dir / "a.json");
  EXPECT_EQ(layers[0].document, json::parse(R"({"name": "a", "v": 1})"));
}

TEST(ReadConfigLayers, ExtendsResolvesAgainstEachFilesOwnDirectoryBaseFirst) {
  const test::ScratchDir dir;
  Write(dir / "top" / "leaf.json", R"({"extends": "../mid/mid.json", "v": 3, "leaf": true})");
  Write(dir / "mid" / "mid.json", R"({"extends": "base/base.json", "v": 2, "mid": true})");
  Write(dir / "mid" / "base" / "base.json", R"({"v": 1, "base": true, "o": {"x": 1, "y": 1}})");
  const std::vector<ConfigLayer> layers = ReadConfigLayers(dir / "top" / "leaf.json", "test file");
  ASSERT_EQ(layers.size(), 3u);
  EXPECT_EQ(layers[0].file, dir / "top" / "../mid/base/base.json");
  EXPECT_EQ(layers[2].file, dir / "top" / "leaf.json");
  EXPECT_FALSE(layers[2].document.contains("extends"));
  EXPECT_EQ(MergeLayers(json::object(), layers),
            json::parse(R"({"v": 3, "base": true, "mid": true, "leaf": true, "o": {"x": 1, "y": 1}})"));
  EXPECT_EQ(MergeLayers(json::parse(R"({"o": {"z": 0}, "d": 0})"), layers),
            json::parse(R"({"v": 3, "base": true, "mid": true, "leaf": true, "o": {"x": 1, "y": 1, "z": 0}, "d": 0})"));
}

TEST(ReadConfigLayers, AbsoluteExtendsIsTakenAsIs) {
  const test::ScratchDir dir;
  Write(dir / "base.json", R"({"v": 1})");
  Write(dir / "sub" / "leaf.json", json{{"extends", (dir / "base.json").string()}}.dump());
  EXPECT_EQ(MergeLayers(json::object(), ReadConfigLayers(dir / "sub" / "leaf.json", "test file")),
            json::parse(R"({"v": 1})"));
}

TEST(ReadConfigLayers, ACycleIsRefusedWithItsFiles) {
  const test::ScratchDir dir;
  Write(dir / "a.json", R"({"extends": "b.json"})");
  Write(dir / "b.json", R"({"extends": "./a.json"})");
  EXPECT_THAT(ErrorOf([&] { ReadConfigLayers(dir / "a.json", "test file"); }),
              AllOf(HasSubstr((dir / "b.json").string() + ": extends: a cycle: "),
                    HasSubstr("a.json -> " + (dir / "b.json").string() + " -> " + (dir / "./a.json").string())));
  Write(dir / "self.json", R"({"extends": "self.json"})");
  EXPECT_THAT(ErrorOf([&] { ReadConfigLayers(dir / "self.json", "test file"); }),
              HasSubstr("self.json: extends: a cycle: "));
}

TEST(ReadConfigLayers, AMissingBaseNamesTheFileThatExtendsIt) {
  const test::ScratchDir dir;
  Write(dir / "a.json", R"({"extends": "no-such.json"})");
  EXPECT_THAT(ErrorOf([&] { ReadConfigLayers(dir / "a.json", "test file"); }),
              AllOf(HasSubstr((dir / "a.json").string() + ": extends: " + (dir / "no-such.json").string()),
                    HasSubstr("cannot open test file")));
  Write(dir / "dir.json", R"({"extends": "."})");
  EXPECT_THAT(ErrorOf([&] { ReadConfigLayers(dir / "dir.json", "test file"); }), HasSubstr("is a directory"));
}

TEST(ReadConfigLayers, ABrokenBaseIsNamed) {
  const test::ScratchDir dir;
  Write(dir / "a.json", R"({"extends": "b.json"})");
  Write(dir / "b.json", R"({"v": )");
  EXPECT_THAT(ErrorOf([&] { ReadConfigLayers(dir / "a.json", "test file"); }),
              HasSubstr((dir / "b.json").string() + ": invalid JSON"));
  Write(dir / "b.json", R"([1, 2])");
  EXPECT_THAT(ErrorOf([&] { ReadConfigLayers(dir / "a.json", "test file"); }),
              HasSubstr((dir / "b.json").string() + ": <root>: must be an object, got array"));
}

TEST(ReadConfigLayers, ExtendsMustNameAFile) {
  const test::ScratchDir dir;
  for (const char* value : {"1", "\"\"", "null", "[\"b.json\"]"}) {
    Write(dir / "a.json", std::string(R"({"extends": )") + value + "}");
    EXPECT_THAT(ErrorOf([&] { ReadConfigLayers(dir / "a.json", "test file"); }),
                HasSubstr("a.json: extends: must name a file")) << value;
  }
}

TEST(ReadConfigLayers, ChainsAreBounded) {
  const test::ScratchDir dir;
  const auto name = [](std::size_t i) { return std::string("f").append(std::to_string(i)).append(".json"); };
  for (std::size_t i = 0; i <= kMaxExtendsDepth; ++i) Write(dir / name(i), json{{"extends", name(i + 1)}}.dump());
  Write(dir / name(kMaxExtendsDepth + 1), "{}");
  EXPECT_THAT(ErrorOf([&] { ReadConfigLayers(dir / "f0.json", "test file"); }),
              HasSubstr("extends: more than 16 files in the chain"));
  EXPECT_EQ(ReadConfigLayers(dir / "f2.json", "test file").size(), kMaxExtendsDepth);  // f2 ... f17: just right
}

TEST(ReadConfigLayers, DeepNestingIsRefusedBeforeParsing) {
  const test::ScratchDir dir;
  Write(dir / "deep.json", "{\"a\": " + std::string(100, '[') + std::string(100, ']') + "}");
  EXPECT_THAT(ErrorOf([&] { ReadConfigLayers(dir / "deep.json", "test file"); }),
              HasSubstr("nested deeper than 64 levels"));
}

TEST(ParseConfigLayers, TextResolvesItsBaseAgainstTheGivenDirectory) {
  const test::ScratchDir dir;
  Write(dir / "base.json", R"({"v": 1, "w": 1})");
  const std::vector<ConfigLayer> layers = ParseConfigLayers(R"({"extends": "base.json", "w": 2})", "inline",
                                                            dir.path(), "test file");
  EXPECT_EQ(MergeLayers(json::object(), layers), json::parse(R"({"v": 1, "w": 2})"));
  EXPECT_EQ(layers.back().file, "inline");
}

TEST(ParseStandaloneLayer, RefusesExtends) {
  EXPECT_THAT(ErrorOf([] { ParseStandaloneLayer(R"({"extends": "x.json"})", "filter_config"); }),
              HasSubstr("filter_config: extends: only a file can extend another"));
  EXPECT_EQ(ParseStandaloneLayer(R"({"v": 1})", "x").document, json::parse(R"({"v": 1})"));
  EXPECT_THAT(ErrorOf([] { ParseStandaloneLayer("3", "x"); }), HasSubstr("x: <root>: must be an object"));
}


TEST(JsonNesting, CountsArraysAndObjectsButNotBracketsInStrings) {
  EXPECT_FALSE(JsonNestedDeeperThan(R"({"a": [1, {"b": 2}]})", 3));
  EXPECT_TRUE(JsonNestedDeeperThan(R"({"a": [1, {"b": 2}]})", 2));
  EXPECT_FALSE(JsonNestedDeeperThan(R"({"a": "[[[[{{{{", "b": "\"[["})", 1));
  EXPECT_FALSE(JsonNestedDeeperThan("", 0));
  EXPECT_TRUE(JsonNestedDeeperThan(std::string(65, '[') + std::string(65, ']'), kMaxConfigNestingDepth));
  EXPECT_FALSE(JsonNestedDeeperThan(std::string(64, '[') + std::string(64, ']'), kMaxConfigNestingDepth));
  EXPECT_FALSE(JsonNestedDeeperThan("]]]}[", 1));  // unbalanced closers do not go below zero
}

}  // namespace
}  // namespace rowloc::mapio
