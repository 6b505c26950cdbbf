#pragma once

#include <span>
#include <string_view>

namespace photomat {

// A file of the web viewer (viewer/src/ in the source tree), compiled into photomat so that an
// export needs nothing but the binary.
struct ViewerAsset {
  std::string_view path;      // relative to the viewer folder, e.g. "index.html"
  std::string_view contents;  // the file's bytes
};

// Every file of viewer/src/, generated at build time by relight/embed_files.cmake.
std::span<const ViewerAsset> ViewerAssets();

}  // namespace photomat
