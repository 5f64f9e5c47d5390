// Configuration files as overlays (issue 29): a file lists only what it changes relative to a base,
// which is the code's defaults (filter files) and/or another file it names with "extends"
// (filter files, scenarios). docs/localization-filter.md §3 and docs/simulation-scenarios.md state
// the rules for users; this header implements the two mechanisms they share.
//
// Merge rule (MergeOverlay): key by key. Where the base and the overlay both hold an object at a
// key, the two objects are merged by the same rule; anywhere else the overlay's value replaces the
// base's: numbers, strings, booleans, arrays (whole: an array is never merged element by element)
// and null. This is RFC 7386 (JSON merge patch) except for null: in a merge patch null deletes the
// key, here it is a value, because null means something in rowloc's files (a scenario's
// "gnss": null is "no GNSS receiver"). A key cannot be removed by an overlay, only given a value.
//
// "extends": a file may name one base file, a path relative to the file's own directory (or
// absolute). The base is read (with its own "extends", recursively), then the file is merged onto
// it. Refused, naming the file and the key "extends": a value that is not a non-empty string, a
// base that cannot be read (the reader's reason: no such file, a directory, a FIFO, too large),
// a cycle (the files of the cycle are listed), and chains deeper than kMaxExtendsDepth.
#pragma once

#include <nlohmann/json.hpp>

#include <cstddef>
#include <filesystem>
#include <stdexcept>
#include <string>
#include <string_view>
#include <vector>

namespace rowloc::mapio {

/// An overlay or an "extends" chain that cannot be read: what() names the file, the key and why.
class ConfigOverlayError : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

/// Files in one "extends" chain, the file itself included.
inline constexpr std::size_t kMaxExtendsDepth = 16;
/// Arrays and objects nested in one configuration document (the shipped ones have at most 5):
/// copying a value recurses once per level.
inline constexpr std::size_t kMaxConfigNestingDepth = 64;

/// True when arrays and objects nest deeper than `limit` in the JSON `text` (brackets inside
/// strings do not count), found without parsing: a parser's recursion is bounded before it starts.
/// Exact for valid JSON; malformed text may be refused by this instead of by the parser.
bool JsonNestedDeeperThan(std::string_view text, std::size_t limit);

/// Merges `overlay` onto `base` by the rule above. Both are usually objects; a non-object overlay
/// replaces the base.
void MergeOverlay(nlohmann::json& base, const nlohmann::json& overlay);

/// One file of an "extends" chain: where it was read (the first one as named by the caller, a
/// base as the directory of the file that names it joined with the name) and its document without
/// "extends".
struct ConfigLayer {
  std::filesystem::path file;
  nlohmann::json document;
};

/// Parses `text` (named `source` in messages; its "extends" resolves against `directory`) and
/// reads the files it extends. Returns the chain base first, `text`'s own layer last. Every
/// document must be a JSON object nested at most kMaxConfigNestingDepth levels. `what` names the
/// kind of file in the messages ("filter file", "scenario file"). Throws ConfigOverlayError.
std::vector<ConfigLayer> ParseConfigLayers(std::string_view text, const std::string& source,
                                           const std::filesystem::path& directory, std::string_view what);
/// As ParseConfigLayers for the file at `path` (read by mapio::ReadInputFile: a regular file of at
/// most kMaxConfigFileBytes). Throws ConfigOverlayError, also when `path` itself cannot be read.
std::vector<ConfigLayer> ReadConfigLayers(const std::filesystem::path& path, std::string_view what);

/// One document that cannot extend another (a configuration sent inline, which has no directory):
/// the checks of ParseConfigLayers, and "extends" is refused. Throws ConfigOverlayError.
ConfigLayer ParseStandaloneLayer(std::string_view text, const std::string& source);

/// The layers merged in order (base first) onto `start` (e.g. the defaults, or an empty object).
nlohmann::json MergeLayers(nlohmann::json start, const std::vector<ConfigLayer>& layers);

}  // namespace rowloc::mapio
