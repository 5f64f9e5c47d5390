// `rowloc cloud info` and `rowloc cloud octomap`: the first steps of the survey pipeline
// (docs/mapping.md) on a PLY or PCD point cloud.
#include "commands.hpp"
#include "option_checks.hpp"

#include "rowloc/mapping/canopy_occupancy_map.hpp"
#include "rowloc/mapping/point_cloud.hpp"

#include <fmt/format.h>
#include <spdlog/spdlog.h>

#include <limits>
#include <memory>
#include <string>

namespace rowloc::apps {
namespace {

struct OctoMapCommandOptions {
  std::string input_path;
  std::string output_path;
  double resolution_m = 0.05;
};

void RunCloudInfo(const std::string& path) {
  CheckCommandFiles({{"file", path}}, {});
  const mapping::PointCloud cloud = mapping::ReadPointCloud(path);
  Eigen::Vector3d lo = Eigen::Vector3d::Constant(std::numeric_limits<double>::infinity());
  Eigen::Vector3d hi = -lo;
  for (const auto& p : cloud.points_m) {
    lo = lo.cwiseMin(p);
    hi = hi.cwiseMax(p);
  }
  fmt::print("{}: {} points, x [{:.3f}, {:.3f}] y [{:.3f}, {:.3f}] z [{:.3f}, {:.3f}] m\n", path,
             cloud.points_m.size(), lo.x(), hi.x(), lo.y(), hi.y(), lo.z(), hi.z());
}

void RunOctoMap(const OctoMapCommandOptions& o) {
  CheckCommandFiles({{"input", o.input_path}}, {{"output", o.output_path}});
  const mapping::PointCloud cloud = mapping::ReadPointCloud(o.input_path);
  const mapping::OctoMapSummary summary =
      mapping::WriteOctoMap(cloud, mapping::OctoMapOptions{o.resolution_m}, o.output_path);
  spdlog::info("{} points -> {} occupied voxels of {:.3f} m in {}", cloud.points_m.size(),
               summary.occupied_leaves, summary.resolution_m, o.output_path);
}

}  // namespace

void RegisterMappingCommands(CLI::App& app) {
  CLI::App* cloud = app.add_subcommand("cloud", "Survey point clouds (PLY, PCD, LAS)");
  cloud->require_subcommand(1);

  auto info_path = std::make_shared<std::string>();
  CLI::App* info = cloud->add_subcommand("info", "Read a point cloud and print its size and extent");
  info->add_option("file", *info_path, "Point cloud (.ply, .pcd or .las)")->required();
  info->callback([info_path] { RunReportingInputErrors("cloud info", [&info_path] { RunCloudInfo(*info_path); }); });

  auto opts = std::make_shared<OctoMapCommandOptions>();
  CLI::App* octo = cloud->add_subcommand("octomap", "Write an OctoMap (.bt) of a point cloud");
  octo->add_option("input", opts->input_path, "Point cloud (.ply, .pcd or .las)")->required();
  octo->add_option("output", opts->output_path, "OctoMap file (.bt)")->required();
  octo->add_option("--resolution", opts->resolution_m, "Voxel size [m]")
      ->check(FiniteInRange(mapping::kMinResolutionM, mapping::kMaxResolutionM, "RANGE"));
  octo->callback([opts] { RunReportingInputErrors("cloud octomap", [&opts] { RunOctoMap(*opts); }); });
}

}  // namespace rowloc::apps
