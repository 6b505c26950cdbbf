#pragma once

#include <filesystem>
#include <optional>
#include <string>

#include "core/colour.h"
#include "represent/stack/map_stack.h"

namespace photomat {

// Every file a representation can be read from: photomat's map stacks (a .exr or a fit folder)
// and the interchange files of other tools (.ptm, .rti), by extension.

// True for a .ptm or .rti path.
bool IsInterchangeFile(const std::filesystem::path& path);

// Inputs LoadStackFile reads whole, not as a map stack: a .ptm or .rti file, a compact stack
// folder (compact_stack.json, compact_stack.h) or a folder in relight's web format (info.json,
// without photomat's fit manifest). Streamed relighting and
// export take only map stacks.
bool IsReadWholeStackInput(const std::filesystem::path& path);
// True if `path` is something LoadStackFile reads: a .exr, .ptm or .rti file, a folder with a
// stacks.json, a compact stack folder (compact_stack.h) or a relight web folder (info.json +
// plane_N.jpg, relight_web_format.h). (Anything
// else is a photometric set or nothing.)
bool IsStackInput(const std::filesystem::path& path);

// Loads a map stack (`method` picks one from a fit folder), a compact stack folder (as the
// stack it was made from), a .ptm, an .rti or a relight web folder (colour space "srgb", its lights
// as capture lights). Interchange files load with colour space "srgb" and their path as source;
// `method` must then be empty or name what the file holds. Throws Error naming the file.
LoadedStack LoadStackFile(const std::filesystem::path& path,
                          const std::optional<std::string>& method = std::nullopt);

// How the stack's relit values encode light: kSrgb for .ptm/.rti files and stacks made from them
// (relit values are display codes / 255), kLinear otherwise. Throws Error for an unknown name.
ColourSpace StackValueEncoding(const StackProvenance& provenance);

}  // namespace photomat
