#pragma once

#include <filesystem>
#include <nlohmann/json.hpp>
#include <string>
#include <vector>

#include "core/image_band_io.h"
#include "core/image_io.h"
#include "represent/model/representation.h"
#include "represent/stack/map_stack.h"

namespace photomat {

// (Implemented in map_stack.cc, beside SaveRepresentation, which writes the same description.)
// The "photomat:stack" description of `representation` (the JSON above).
nlohmann::json StackDescription(const Representation& representation,
                                const StackProvenance& provenance = {});

// A map stack written band by band in row order (streamed fits, README "Streamed fitting"):
// the same file SaveRepresentation writes, its description known before the first band (each
// band's maps are rows of the whole stack). Written to a temporary name; Commit() renames it into
// place, and a writer destroyed without Commit() leaves nothing.
class StackBandWriter {
 public:
  StackBandWriter(const std::filesystem::path& path, const nlohmann::json& description,
                  std::vector<std::string> channel_names, int width, int height,
                  ExrCompression compression = kDefaultExrCompression);
  const std::filesystem::path& path() const { return writer_.path(); }
  // The next band of maps (the stack's width and channels, in description order).
  void Write(ConstImageView maps) { writer_.WriteNext(maps); }
  void Commit() { writer_.Commit(); }

 private:
  ImageBandWriter writer_;
};

}  // namespace photomat
