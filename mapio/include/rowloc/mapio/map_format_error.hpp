// The error thrown when a row map file cannot be read: which file, where in it, and why.
// The message (what()) follows the GNU convention for diagnostics
// (https://www.gnu.org/prep/standards/html_node/Errors.html):
//   "<source>:<line>:<column>: <reason>"   for a location "line:column" (JSON syntax errors),
//   "<source>: <location>: <reason>"       for any other location ("top level", "feature 3 (id 'r4')"),
//   "<source>: <reason>"                   when there is no location (e.g. the file cannot be opened).
#pragma once

#include <stdexcept>
#include <string>

namespace rowloc::mapio {

class MapFormatError : public std::runtime_error {
 public:
  MapFormatError(std::string source, std::string location, std::string reason);

  /// File name (or the name given for an in-memory text, "<string>" by default).
  const std::string& source() const { return source_; }
  /// "line:column" (1-based) for JSON syntax errors, "top level", "feature N" or
  /// "feature N (id 'x')" (N is the 0-based index in "features") for content errors; may be empty.
  const std::string& location() const { return location_; }
  /// What is wrong, in words.
  const std::string& reason() const { return reason_; }

 private:
  std::string source_;
  std::string location_;
  std::string reason_;
};

}  // namespace rowloc::mapio
