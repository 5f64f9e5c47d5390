// libFuzzer target over the row map GeoJSON reader (docs/map-format.md; docs/building.md,
// "Fuzzing"): the input is the text of a map file, given to ParseRowMapGeoJson. The reader may
// throw MapFormatError only; a map it returns must pass geometry::ValidateRowMap and have no
// outline defect (its contract); anything else (another exception, a sanitizer report, a timeout,
// a map that breaks the contract) is a finding.
#include "rowloc/geometry/row_outline_validity.hpp"
#include "rowloc/mapio/row_map_geojson.hpp"

#include <cstdint>
#include <cstdlib>
#include <string_view>

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  const std::string_view input(reinterpret_cast<const char*>(data), size);
  try {
    const rowloc::geometry::RowMap map = rowloc::mapio::ParseRowMapGeoJson(input, "fuzz");
    if (rowloc::geometry::ValidateRowMap(map)) std::abort();  // the reader returned an invalid map
    for (const rowloc::geometry::Row& row : map.rows) {
      if (rowloc::geometry::RowOutlineDefect(row)) std::abort();
    }
  } catch (const rowloc::mapio::MapFormatError&) {
  }
  return 0;
}
