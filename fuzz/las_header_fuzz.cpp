// libFuzzer target over the LAS reader (rowloc/mapping/las_file.hpp; docs/building.md, "Fuzzing"):
// every input is read as a whole LAS file (public header block, then the point records). The reader
// may throw PointCloudError only (a refused header, a count the input cannot hold, LAZ): any other
// exception escapes and libFuzzer reports it as a crash, as it does sanitizer errors. Memory is
// bounded by the input, never by the header's claims, so a file that passes holds its records.
#include "rowloc/mapping/las_file.hpp"

#include <cmath>
#include <cstdint>
#include <sstream>
#include <string>

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  const std::string input(reinterpret_cast<const char*>(data), size);
  std::istringstream in(input);
  try {
    const rowloc::mapping::LasCloud cloud = rowloc::mapping::ReadLas(in, "fuzz.las");
    const rowloc::mapping::LasHeader& h = cloud.header;
    // A header that passed is backed by the input, and every point is finite.
    if (h.point_count > size || h.point_count * h.point_record_length + h.offset_to_point_data > size ||
        cloud.points_m.size() != h.point_count || cloud.intensity.size() != h.point_count ||
        cloud.classification.size() != h.point_count) {
      __builtin_trap();
    }
    for (const Eigen::Vector3d& p : cloud.points_m) {
      if (!p.allFinite()) __builtin_trap();
    }
  } catch (const rowloc::mapping::PointCloudError&) {
  }
  return 0;
}
