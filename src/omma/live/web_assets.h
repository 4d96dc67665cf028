// The live view's web files (web/: the page, its script, the Pannellum viewer from npm), embedded
// in the binary at build time by cmake/embed_web.cmake, so that `omma run --sink http:PORT` serves
// them (from 127.0.0.1, or the --bind address) with no network access and no install folder to find:
// the program alone is enough, and the page always matches the server that serves it. The viewer's
// files (/viewer/...) are the same in every omma and need no token; the page (/) does (sinks.h).
#pragma once

#include <string_view>

namespace omma::live {

struct WebAsset {
  std::string_view path;  // "/live.html", "/pannellum.js", ...
  std::string_view type;  // MIME type
  std::string_view data;
};

// The asset at `path`, or nullptr.
const WebAsset* find_web_asset(std::string_view path);
// Whether the Pannellum viewer was embedded (web/node_modules present at build time; without it the
// page shows the flat panorama).
bool viewer_embedded();

}  // namespace omma::live
