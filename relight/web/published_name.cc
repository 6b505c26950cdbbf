#include "relight/web/published_name.h"

namespace photomat {

std::string PublishedName(const std::filesystem::path& input) {
  std::filesystem::path path = input.lexically_normal();
  // "cat/" normalises to "cat/", whose filename is empty: drop the trailing separator.
  if (path.has_relative_path() && !path.has_filename()) path = path.parent_path();
  const std::string name = path.filename().string();
  return name.empty() ? path.string() : name;
}

}  // namespace photomat
