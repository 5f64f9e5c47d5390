// The SVG top view of a map build (FormatMapSvg, declared in map_builder.hpp with the result it draws).
#include "rowloc/mapping/map_builder.hpp"

#include <fmt/format.h>

#include <algorithm>
#include <limits>
#include <string>
#include <utility>

namespace rowloc::mapping {

std::string FormatMapSvg(const MapBuildResult& result) {
  Eigen::Vector2d lo = Eigen::Vector2d::Constant(std::numeric_limits<double>::infinity());
  Eigen::Vector2d hi = -lo;
  for (const auto& p : result.cloud_sample_m) {
    lo = lo.cwiseMin(p);
    hi = hi.cwiseMax(p);
  }
  if (result.map) {
    for (const auto& row : result.map->rows) {
      for (const auto& p : row.points_m) {
        lo = lo.cwiseMin(p);
        hi = hi.cwiseMax(p);
      }
    }
  }
  if (!lo.allFinite()) {
    lo = Eigen::Vector2d::Zero();
    hi = Eigen::Vector2d::Ones();
  }
  const double margin = 1.0;
  lo.array() -= margin;
  hi.array() += margin;
  const double scale = 1000.0 / std::max(hi.x() - lo.x(), hi.y() - lo.y());  // pixels per metre
  const double width = (hi.x() - lo.x()) * scale;
  const double height = (hi.y() - lo.y()) * scale;
  const auto px = [&](const Eigen::Vector2d& p) {
    return fmt::format("{:.1f},{:.1f}", (p.x() - lo.x()) * scale, (hi.y() - p.y()) * scale);
  };
  std::string svg = fmt::format(
      "<svg xmlns=\"http://www.w3.org/2000/svg\" width=\"{:.0f}\" height=\"{:.0f}\" viewBox=\"0 0 {:.1f} {:.1f}\">\n"
      "<title>rowloc map build: {}</title>\n<rect width=\"100%\" height=\"100%\" fill=\"white\"/>\n",
      width, height + 40.0, width, height + 40.0, result.message);
  svg += "<g stroke=\"none\">\n";
  for (std::size_t i = 0; i < result.cloud_sample_m.size(); ++i) {
    const double h = std::clamp(result.cloud_sample_height_m[i] / 2.5, 0.0, 1.0);
    const int green = static_cast<int>(200 - 120 * h);
    const auto [x, y] = std::make_pair((result.cloud_sample_m[i].x() - lo.x()) * scale,
                                       (hi.y() - result.cloud_sample_m[i].y()) * scale);
    svg += fmt::format("<circle cx=\"{:.1f}\" cy=\"{:.1f}\" r=\"0.8\" fill=\"rgb({},{},{})\"/>\n", x, y,
                       static_cast<int>(150 - 100 * h), green, static_cast<int>(150 - 100 * h));
  }
  svg += "</g>\n<g fill=\"none\" stroke=\"#d62728\" stroke-width=\"1.2\">\n";
  if (result.map) {
    for (const auto& row : result.map->rows) {
      svg += "<polygon points=\"";
      for (const auto& p : row.points_m) svg += px(p) + " ";
      svg += fmt::format("\"><title>{}</title></polygon>\n", row.id);
    }
  }
  svg += "</g>\n";
  // Scale bar: 5 m.
  svg += fmt::format(
      "<g font-family=\"sans-serif\" font-size=\"14\"><line x1=\"10\" y1=\"{0:.1f}\" x2=\"{1:.1f}\" y2=\"{0:.1f}\" "
      "stroke=\"black\" stroke-width=\"2\"/><text x=\"{2:.1f}\" y=\"{3:.1f}\">5 m</text>"
      "<text x=\"10\" y=\"{4:.1f}\">{5} (outlines red; cloud green, darker = higher)</text></g>\n</svg>\n",
      height + 15.0, 10.0 + 5.0 * scale, 15.0 + 5.0 * scale, height + 20.0, height + 36.0, result.message);
  return svg;
}

}  // namespace rowloc::mapping
