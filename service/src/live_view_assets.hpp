// The files of the live view's page (service/web/), embedded in the binary at build time by
// service/embed_web_assets.cmake, so that `rowloc serve` serves them from any directory.
#pragma once

#include <span>
#include <string_view>

namespace rowloc::service {

struct LiveViewAsset {
  std::string_view path;          ///< URL path, e.g. "/index.html"
  std::string_view content_type;  ///< e.g. "text/html; charset=utf-8"
  std::string_view body;
};

/// Every file of service/web/ (generated source: live_view_assets.cpp in the build tree).
std::span<const LiveViewAsset> LiveViewAssets();

}  // namespace rowloc::service
