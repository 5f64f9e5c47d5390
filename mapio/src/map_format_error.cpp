#include "rowloc/mapio/map_format_error.hpp"

#include <cctype>
#include <utility>

namespace rowloc::mapio {
namespace {

std::string Compose(const std::string& source, const std::string& location, const std::string& reason) {
  if (location.empty()) return source + ": " + reason;
  const bool line_column = std::isdigit(static_cast<unsigned char>(location.front())) != 0;
  return source + (line_column ? ":" : ": ") + location + ": " + reason;
}

}  // namespace

MapFormatError::MapFormatError(std::string source, std::string location, std::string reason)
    : std::runtime_error(Compose(source, location, reason)),
      source_(std::move(source)),
      location_(std::move(location)),
      reason_(std::move(reason)) {}

}  // namespace rowloc::mapio
