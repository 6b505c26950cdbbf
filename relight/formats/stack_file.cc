#include "relight/formats/stack_file.h"

#include <fmt/format.h>

#include <cctype>

#include "core/error.h"
#include "core/text_parsing.h"
#include "relight/formats/compact_stack.h"
#include "relight/formats/ptm_file.h"
#include "relight/formats/relight_web_format.h"
#include "relight/formats/rti_file.h"

namespace photomat {
namespace {

namespace fs = std::filesystem;

}  // namespace

bool IsInterchangeFile(const fs::path& path) {
  const std::string extension = LowerExtension(path);
  return extension == ".ptm" || extension == ".rti";
}

bool IsReadWholeStackInput(const fs::path& path) {
  std::error_code ec;
  return IsInterchangeFile(path) || IsCompactStackFolder(path) ||
         (IsRelightWebFolder(path) && !fs::exists(path / kFitManifestName, ec));
}

bool IsStackInput(const fs::path& path) {
  std::error_code ec;
  if (fs::is_directory(path, ec)) {
    return fs::exists(path / kFitManifestName, ec) || IsRelightWebFolder(path) ||
           IsCompactStackFolder(path);
  }
  return IsInterchangeFile(path) || LowerExtension(path) == ".exr";
}

namespace {

// A relight web folder (relight/formats/relight_web_format.h): sRGB-encoded values; its lights,
// when it lists them, are the capture's.
LoadedStack LoadRelightWebFolder(const fs::path& path, const std::optional<std::string>& method) {
  const RelightWebStack stack = ReadRelightWeb(path);
  Representation representation = RepresentationFromRelightWeb(stack);
  if (method && *method != representation.method()) {
    throw Error(path,
                fmt::format("holds a {} representation, not {}", representation.method(), *method));
  }
  StackProvenance provenance;
  provenance.colour_space =
      std::string(ToString(stack.linear ? ColourSpace::kLinear : ColourSpace::kSrgb));
  provenance.source = path.string();
  for (const auto& light : stack.lights) {
    provenance.capture_lights.push_back(LightDirection::FromVector(light));
  }
  return {std::move(representation), std::move(provenance)};
}

// A compact stack folder (relight/formats/compact_stack.h): read like the map stack it was.
LoadedStack LoadCompactStackFolder(const fs::path& path, const std::optional<std::string>& method) {
  LoadedStack stack = ReadCompactStack(path);
  if (method && *method != stack.representation.method()) {
    throw Error(path, fmt::format("holds a {} representation, not {}",
                                  stack.representation.method(), *method));
  }
  return stack;
}

}  // namespace

LoadedStack LoadStackFile(const fs::path& path, const std::optional<std::string>& method) {
  if (IsCompactStackFolder(path)) return LoadCompactStackFolder(path, method);
  if (IsReadWholeStackInput(path) && !IsInterchangeFile(path)) {
    return LoadRelightWebFolder(path, method);
  }
  if (!IsInterchangeFile(path)) return LoadRepresentation(ResolveStack(path, method));
  const bool ptm = LowerExtension(path) == ".ptm";
  Representation representation =
      ptm ? RepresentationFromPtm(ReadPtmFile(path)) : RepresentationFromRti(ReadRtiFile(path));
  if (method && *method != representation.method()) {
    throw Error(path,
                fmt::format("holds a {} representation, not {}", representation.method(), *method));
  }
  StackProvenance provenance;
  provenance.colour_space = std::string(ToString(ColourSpace::kSrgb));
  provenance.source = path.string();
  return {std::move(representation), std::move(provenance)};
}

ColourSpace StackValueEncoding(const StackProvenance& provenance) {
  const auto space = ParseColourSpace(provenance.colour_space);
  if (!space) {
    throw Error(fmt::format("unknown stack colour space \"{}\" (expected linear or srgb)",
                            provenance.colour_space));
  }
  return *space;
}

}  // namespace photomat
