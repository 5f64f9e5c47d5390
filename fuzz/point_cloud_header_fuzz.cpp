// libFuzzer target over the PLY and PCD header checks (rowloc/mapping/point_cloud_header.hpp;
// docs/building.md, "Fuzzing"): every input is checked as a PCD file and as a PLY file. The checks
// may throw PointCloudError only (a claim the body does not back, a malformed header): any other
// exception escapes and libFuzzer reports it as a crash, as it does sanitizer errors. The checks
// read the input in constant memory, so a huge claim must never make them allocate.
#include "rowloc/mapping/point_cloud_header.hpp"

#include <cstdint>
#include <sstream>
#include <string>

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  const std::string input(reinterpret_cast<const char*>(data), size);
  for (const bool ply : {false, true}) {
    std::istringstream in(input);
    try {
      const rowloc::mapping::PointCloudFileSummary summary =
          ply ? rowloc::mapping::CheckPlyFile(in, "fuzz.ply") : rowloc::mapping::CheckPcdFile(in, "fuzz.pcd");
      // A header that passed is backed by the input: binary points fit in it.
      if (summary.encoding == rowloc::mapping::PointCloudEncoding::kBinary &&
          summary.points * summary.point_bytes > size) {
        __builtin_trap();
      }
    } catch (const rowloc::mapping::PointCloudError&) {
    }
  }
  return 0;
}
