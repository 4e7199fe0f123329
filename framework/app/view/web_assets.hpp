#pragma once
// The page of `hapsyn view` (web/), embedded into the program at build time (the generated
// web_assets.cpp, written by cmake/EmbedWebAssets.cmake): nothing is looked up at run time.
#include <string>
#include <string_view>
#include <vector>

namespace hapsyn_cli {

/// One embedded file and the route it is served at.
struct WebAsset {
  std::string_view route;         ///< "/", "/app.js", "/three.module.js", ...
  std::string_view content_type;  ///< "text/html" or "text/javascript" (the files are UTF-8)
  std::string_view body;
};

/// Every embedded file (empty when the page was not built).
const std::vector<WebAsset>& web_assets();

/// "" when the page's assets were built; otherwise why not and how to build them.
std::string_view web_assets_missing();

}  // namespace hapsyn_cli
