#pragma once

#include <filesystem>
#include <string>

namespace photomat {

// The name of an input as published outputs show it (the viewer's title, the evaluation report):
// the last component of the path, never the folders above it, so that a page made on one machine
// carries no absolute local path of it ("/home/me/captures/cat/" -> "cat", "stacks/ptm.exr" ->
// "ptm.exr"); a capture's manifest.json is published as its folder's name. An empty path stays
// empty; "." and ".." resolve to nothing better than themselves.
std::string PublishedName(const std::filesystem::path& input);

}  // namespace photomat
