// Canopy occupancy map through OctoMap (see canopy_occupancy_map.hpp).
#include "rowloc/mapping/canopy_occupancy_map.hpp"

#include "rowloc/mapio/input_file.hpp"
#include "rowloc/mapio/output_file.hpp"
#define OCTOMAP_NODEBUGOUT  // no debug prints on stderr from OctoMap's headers in Debug builds either
#include <octomap/OcTree.h>

#include <cctype>
#include <cmath>
#include <limits>
#include <istream>
#include <sstream>
#include <string>
#include <utility>

namespace rowloc::mapping {
namespace {

/// Per-axis half-extent of the octree (keys are 16-bit, centred on 32768), in voxels.
constexpr double kHalfExtentVoxels = 32768.0;

std::string Describe(const Eigen::Vector3d& p) {
  std::ostringstream out;
  out.precision(17);
  out << "(" << p.x() << ", " << p.y() << ", " << p.z() << ")";
  return out.str();
}

void ValidateResolution(double resolution_m) {
  if (!(resolution_m >= kMinResolutionM && resolution_m <= kMaxResolutionM)) {
    std::ostringstream out;
    out << "OctoMap resolution_m must be in [" << kMinResolutionM << ", " << kMaxResolutionM
        << "] m, got " << resolution_m;
    throw std::invalid_argument(out.str());
  }
}

/// True if every coordinate of p maps to a valid 16-bit key at this resolution. Checked in double
/// before OctoMap converts to int, so that far-away points never overflow that conversion.
bool InOctreeRange(const Eigen::Vector3d& p, double resolution_m) {
  const double half_extent_m = kHalfExtentVoxels * resolution_m;
  return (p.array() >= -half_extent_m).all() && (p.array() < half_extent_m).all();
}

/// Occupied voxels at the finest depth, and the box they cover.
struct OccupiedExtent {
  std::size_t voxels = 0;
  Eigen::Vector3d min_m = Eigen::Vector3d::Constant(std::numeric_limits<double>::infinity());
  Eigen::Vector3d max_m = Eigen::Vector3d::Constant(-std::numeric_limits<double>::infinity());
};

OccupiedExtent MeasureOccupied(const octomap::OcTree& tree) {
  OccupiedExtent extent;
  const unsigned max_depth = tree.getTreeDepth();
  for (auto it = tree.begin_leafs(), end = tree.end_leafs(); it != end; ++it) {
    if (!tree.isNodeOccupied(*it)) continue;
    extent.voxels += std::size_t{1} << (3 * (max_depth - it.getDepth()));
    const Eigen::Vector3d centre(it.getX(), it.getY(), it.getZ());
    const double half = it.getSize() / 2.0;
    extent.min_m = extent.min_m.cwiseMin((centre.array() - half).matrix());
    extent.max_m = extent.max_m.cwiseMax((centre.array() + half).matrix());
  }
  return extent;
}

}  // namespace

OccupancyMapError::OccupancyMapError(const std::filesystem::path& path, const std::string& reason)
    : std::runtime_error("occupancy map '" + path.string() + "': " + reason) {}

OctoMapSummary WriteOctoMap(const PointCloud& cloud, const OctoMapOptions& options,
                            const std::filesystem::path& bt_path) {
  ValidateResolution(options.resolution_m);
  if (cloud.points_m.empty()) throw std::invalid_argument("WriteOctoMap: the cloud has no points");
  octomap::OcTree tree(options.resolution_m);
  for (std::size_t i = 0; i < cloud.points_m.size(); ++i) {
    const Eigen::Vector3d& p = cloud.points_m[i];
    if (!p.allFinite()) {
      throw std::invalid_argument("WriteOctoMap: point " + std::to_string(i) + " is not finite");
    }
    octomap::OcTreeKey key;
    if (!InOctreeRange(p, options.resolution_m) || !tree.coordToKeyChecked(p.x(), p.y(), p.z(), key)) {
      throw std::invalid_argument("WriteOctoMap: point " + std::to_string(i) + " " + Describe(p) +
                                  " is outside the octree range (+-32768 voxels per axis)");
    }
    tree.updateNode(key, /*occupied=*/true);
  }
  tree.toMaxLikelihood(); tree.prune();  // as writeBinary() does before writing (it is not called: see below)
  try {  // writeBinary()'s bytes, without the " done." its writeBinaryConst() prints on stderr (OctoMap debug output)
    mapio::OutputFile file(bt_path);  // a temporary next to the target, renamed over it on success
    file.stream() << "# Octomap OcTree binary file\n# (feel free to add / change comments, but leave the first line as"
                  << " it is!)\n#\nid OcTree\nsize " << tree.size() << "\nres " << tree.getResolution() << "\ndata\n";
    tree.writeBinaryData(file.stream());  // a failed write fails Commit(), which checks the stream
    file.Commit();
  } catch (const mapio::OutputFileError& e) {
    throw OccupancyMapError(bt_path, e.what());
  }
  const OccupiedExtent extent = MeasureOccupied(tree);
  return OctoMapSummary{extent.voxels, tree.getResolution(), extent.min_m, extent.max_m};
}

struct CanopyOccupancyMap::Impl {
  explicit Impl(double resolution_m) : tree(resolution_m) {}
  octomap::OcTree tree;
  std::size_t occupied_voxels = 0;
};

namespace {

struct BinaryHeader {
  std::size_t size = 0;       ///< nodes of the tree
  double resolution_m = 0.0;
};

/// The header of a binary OctoMap file (OctoMap's AbstractOccupancyOcTree::binaryFileHeader line,
/// then "id OcTree", "size N", "res R", "data", comment lines starting with '#' allowed).
/// At most 40 characters of a header line, non-printable bytes as '?' (the tree's binary data).
std::string Shown(const std::string& line) {
  std::string shown = line.substr(0, 40);
  for (char& ch : shown) {
    if (!std::isprint(static_cast<unsigned char>(ch))) ch = '?';
  }
  return shown;
}

BinaryHeader ReadBinaryHeader(std::istream& in, const std::filesystem::path& path) {
  const auto bad = [&path](const std::string& why) {
    return OccupancyMapError(path, "not a valid binary OctoMap (.bt) file: " + why);
  };
  std::string line;
  if (!std::getline(in, line) || line.rfind("# Octomap OcTree binary file", 0) != 0) {
    throw bad("the first line is not '# Octomap OcTree binary file'");
  }
  BinaryHeader header;
  bool have_id = false;
  bool have_size = false;
  bool have_res = false;
  while (std::getline(in, line)) {
    if (line.empty() || line[0] == '#') continue;
    std::istringstream fields(line);
    std::string key;
    fields >> key;
    if (key == "data") {
      if (!have_id || !have_size || !have_res) throw bad("'data' before 'id', 'size' and 'res'");
      return header;
    }
    if (key == "id") {
      std::string id;
      fields >> id;
      if (id != "OcTree") throw bad("the tree type is '" + id + "', not OcTree");
      have_id = true;
    } else if (key == "size") {
      have_size = static_cast<bool>(fields >> header.size);
    } else if (key == "res") {
      have_res = static_cast<bool>(fields >> header.resolution_m);
    } else {
      throw bad("unknown header line '" + Shown(line) + "'");
    }
    if (!fields) throw bad("malformed header line '" + Shown(line) + "'");
  }
  throw bad("no 'data' line");
}

}  // namespace

CanopyOccupancyMap::CanopyOccupancyMap(std::unique_ptr<Impl> impl) : impl_(std::move(impl)) {}
CanopyOccupancyMap::~CanopyOccupancyMap() = default;
CanopyOccupancyMap::CanopyOccupancyMap(CanopyOccupancyMap&&) noexcept = default;
CanopyOccupancyMap& CanopyOccupancyMap::operator=(CanopyOccupancyMap&&) noexcept = default;

CanopyOccupancyMap CanopyOccupancyMap::Load(const std::filesystem::path& bt_path) {
  // Through mapio::ReadInputFile: a regular file of at most kMaxOctoMapFileBytes, checked on the
  // opened file before OctoMap sees a byte (OctoMap reads its first line whole, however long).
  std::string bytes;
  try {
    bytes = mapio::ReadInputFile(bt_path, kMaxOctoMapFileBytes, "OctoMap file");
  } catch (const mapio::InputFileError& e) {
    throw OccupancyMapError(bt_path, e.reason());
  }
  std::istringstream in(std::move(bytes), std::ios::binary);
  // The header is read here and the tree by OcTree::readBinaryData: OcTree::readBinary does the
  // same, but the Debian build of OctoMap prints "Reading binary octree type OcTree" on stderr.
  const BinaryHeader header = ReadBinaryHeader(in, bt_path);
  if (!(header.resolution_m >= kMinResolutionM && header.resolution_m <= kMaxResolutionM)) {
    throw OccupancyMapError(bt_path, "resolution out of range");
  }
  auto impl = std::make_unique<Impl>(header.resolution_m);
  if (header.size > 0) impl->tree.readBinaryData(in);
  if (!in || impl->tree.size() != header.size) {
    throw OccupancyMapError(bt_path, "not a valid binary OctoMap (.bt) file: the tree's data do not match its header (" +
                                         std::to_string(header.size) + " nodes)");
  }
  impl->occupied_voxels = MeasureOccupied(impl->tree).voxels;
  return CanopyOccupancyMap(std::move(impl));
}

const CanopyOccupancyMap::Impl& CanopyOccupancyMap::impl() const {
  if (!impl_) throw std::logic_error("CanopyOccupancyMap used after being moved from");
  return *impl_;
}

bool CanopyOccupancyMap::IsOccupied(const Eigen::Vector3d& point_m) const {
  const octomap::OcTree& tree = impl().tree;
  if (!point_m.allFinite()) {
    throw std::invalid_argument("CanopyOccupancyMap::IsOccupied: non-finite point " +
                                Describe(point_m));
  }
  octomap::OcTreeKey key;
  if (!InOctreeRange(point_m, tree.getResolution()) ||
      !tree.coordToKeyChecked(point_m.x(), point_m.y(), point_m.z(), key)) {
    return false;
  }
  const octomap::OcTreeNode* node = tree.search(key);
  return node != nullptr && tree.isNodeOccupied(node);
}

double CanopyOccupancyMap::resolution_m() const { return impl().tree.getResolution(); }

std::size_t CanopyOccupancyMap::occupied_leaves() const { return impl().occupied_voxels; }

}  // namespace rowloc::mapping
