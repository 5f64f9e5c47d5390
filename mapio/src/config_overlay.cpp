// Configuration overlays and "extends" chains (config_overlay.hpp).
#include "rowloc/mapio/config_overlay.hpp"

#include "rowloc/mapio/detail/json_object_reader.hpp"
#include "rowloc/mapio/input_file.hpp"

#include <algorithm>
#include <system_error>

namespace rowloc::mapio {
namespace {

using json = nlohmann::json;

constexpr std::string_view kExtendsKey = "extends";

/// The identity of a file for cycle detection: its canonical path where it exists, else its
/// normalized absolute path.
std::filesystem::path Identity(const std::filesystem::path& path) {
  std::error_code error;
  std::filesystem::path canonical = std::filesystem::weakly_canonical(path, error);
  if (!error) return canonical;
  return std::filesystem::absolute(path, error).lexically_normal();
}

/// "a.json -> b.json -> a.json": the files of a chain as reached, and the file that closes it.
std::string ChainText(const std::vector<ConfigLayer>& chain, const std::filesystem::path& next) {
  std::string text;
  for (const ConfigLayer& layer : chain) text += layer.file.string() + " -> ";
  return text + next.string();
}

/// The document of `text`, which must be an object; its "extends" (if any) is removed and returned.
json ParseLayer(std::string_view text, const std::string& source, std::string& extends) {
  if (JsonNestedDeeperThan(text, kMaxConfigNestingDepth)) {
    throw ConfigOverlayError(source + ": arrays and objects nested deeper than " +
                             std::to_string(kMaxConfigNestingDepth) + " levels");
  }
  json document = detail::ParseJsonText<ConfigOverlayError>(text, source);
  if (!document.is_object()) {
    throw ConfigOverlayError(source + ": <root>: must be an object, got " + document.type_name());
  }
  extends.clear();
  if (const auto it = document.find(kExtendsKey); it != document.end()) {
    if (!it->is_string() || it->get<std::string>().empty()) {
      throw ConfigOverlayError(source + ": extends: must name a file (a path relative to this file), got " +
                               it->dump());
    }
    extends = it->get<std::string>();
    document.erase(it);
  }
  return document;
}

std::string ReadLayerText(const std::filesystem::path& path, std::string_view what) {
  try {
    return ReadInputFile(path, kMaxConfigFileBytes, std::string(what));
  } catch (const InputFileError& e) {
    throw ConfigOverlayError(e.what());
  }
}

}  // namespace

void MergeOverlay(json& base, const json& overlay) {
  if (!base.is_object() || !overlay.is_object()) {
    base = overlay;
    return;
  }
  for (const auto& item : overlay.items()) {
    const auto it = base.find(item.key());
    if (it != base.end() && it->is_object() && item.value().is_object()) {
      MergeOverlay(*it, item.value());
    } else {
      base[item.key()] = item.value();
    }
  }
}

std::vector<ConfigLayer> ParseConfigLayers(std::string_view text, const std::string& source,
                                           const std::filesystem::path& directory, std::string_view what) {
  std::vector<ConfigLayer> chain;  // the text's own layer first, then its bases
  std::vector<std::filesystem::path> identities{Identity(directory / std::filesystem::path(source).filename())};
  std::string extends;
  chain.push_back({std::filesystem::path(source), ParseLayer(text, source, extends)});
  std::filesystem::path from_directory = directory;
  while (!extends.empty()) {
    const std::string from = chain.back().file.string();
    const std::filesystem::path named(extends);
    const std::filesystem::path next = named.is_absolute() ? named : from_directory / named;
    const std::filesystem::path identity = Identity(next);
    if (std::find(identities.begin(), identities.end(), identity) != identities.end()) {
      throw ConfigOverlayError(from + ": extends: a cycle: " + ChainText(chain, next));
    }
    if (chain.size() >= kMaxExtendsDepth) {
      throw ConfigOverlayError(from + ": extends: more than " + std::to_string(kMaxExtendsDepth) +
                               " files in the chain: " + ChainText(chain, next));
    }
    std::string base_text;
    try {
      base_text = ReadLayerText(next, what);
    } catch (const ConfigOverlayError& e) {
      throw ConfigOverlayError(from + ": extends: " + e.what());
    }
    identities.push_back(identity);
    chain.push_back({next, ParseLayer(base_text, next.string(), extends)});
    from_directory = next.parent_path();
  }
  std::reverse(chain.begin(), chain.end());
  return chain;
}

std::vector<ConfigLayer> ReadConfigLayers(const std::filesystem::path& path, std::string_view what) {
  return ParseConfigLayers(ReadLayerText(path, what), path.string(), path.parent_path(), what);
}

ConfigLayer ParseStandaloneLayer(std::string_view text, const std::string& source) {
  std::string extends;
  ConfigLayer layer{std::filesystem::path(source), ParseLayer(text, source, extends)};
  if (!extends.empty()) {
    throw ConfigOverlayError(source + ": extends: only a file can extend another (this text has no directory "
                                      "to resolve \"" + extends + "\" against)");
  }
  return layer;
}

json MergeLayers(json start, const std::vector<ConfigLayer>& layers) {
  for (const ConfigLayer& layer : layers) MergeOverlay(start, layer.document);
  return start;
}

bool JsonNestedDeeperThan(std::string_view text, std::size_t limit) {
  std::size_t depth = 0;
  bool in_string = false, escaped = false;
  for (const char c : text) {
    if (in_string) {
      if (escaped) {
        escaped = false;
      } else if (c == '\\') {
        escaped = true;
      } else if (c == '"') {
        in_string = false;
      }
    } else if (c == '"') {
      in_string = true;
    } else if (c == '[' || c == '{') {
      if (++depth > limit) return true;
    } else if ((c == ']' || c == '}') && depth > 0) {
      --depth;
    }
  }
  return false;
}

}  // namespace rowloc::mapio
