#include "relight/web/published_name.h"

namespace photomat {

std::string PublishedName(const std::filesystem::path& input) {
  std::filesystem::path path = input.lexically_normal();
  // "cat/" normalises to "cat/", whose filename is empty: drop the trailing separator.
  if (path.has_relative_path() && !path.has_filename()) path = path.parent_path();
  // A capture folder is loaded from its manifest: publish the folder's name, which is the
  // capture's, not the descriptor's ("cat/manifest.json" -> "cat").
  if (path.filename() == "manifest.json" && path.has_parent_path()) path = path.parent_path();
  const std::string name = path.filename().string();
  return name.empty() ? path.string() : name;
}

}  // namespace photomat
