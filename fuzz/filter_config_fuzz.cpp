// libFuzzer target over the filter configuration reader (localization/filter_config.hpp, owned by
// the localization library; docs/building.md, "Fuzzing"): the input is the text of a filter file,
// given to ParseFilterConfig, which may throw FilterConfigError only. Any other exception, a
// sanitizer report or a timeout is a finding.
#include "rowloc/localization/filter_config.hpp"

#include <cstdint>
#include <string_view>

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  const std::string_view input(reinterpret_cast<const char*>(data), size);
  try {
    (void)rowloc::localization::ParseFilterConfig(input, "fuzz");
  } catch (const rowloc::localization::FilterConfigError&) {
  }
  return 0;
}
