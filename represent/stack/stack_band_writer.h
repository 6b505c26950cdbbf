#pragma once

#include <cstddef>
#include <filesystem>
#include <nlohmann/json.hpp>
#include <string>
#include <vector>

#include "core/image_band_io.h"
#include "core/image_io.h"
#include "represent/model/representation.h"
#include "represent/stack/map_stack.h"

namespace photomat {

// The "photomat:stack" description of `representation` (map_stack.h; implemented in map_stack.cc,
// beside SaveRepresentation, which writes the same description).
nlohmann::json StackDescription(const Representation& representation,
                                const StackProvenance& provenance = {});

// A map stack written band by band in row order (streamed fits, README "Streamed fitting"):
// the same file SaveRepresentation writes, its description known before the first band (each
// band's maps are rows of the whole stack). Written to a temporary name; Commit() renames it into
// place, and a writer destroyed without Commit() leaves nothing.
//
// Late details: entries of the description's "details" that only the last band decides (a
// streamed fit's summaries over all its bands). The header precedes the data, so each is written
// first as a placeholder string of kLateDetailBytes; Commit(values) overwrites it in the closed
// temporary file with the value's JSON, padded with spaces (JSON whitespace) to the same length,
// before the rename. IMPLEMENTER CHOICE: a patch in place rather than a second file beside the
// stack, so that the stack stays one self-describing file, committed whole or not at all.
class StackBandWriter {
 public:
  static constexpr std::size_t kLateDetailBytes = 1024;

  StackBandWriter(const std::filesystem::path& path, const nlohmann::json& description,
                  std::vector<std::string> channel_names, int width, int height,
                  ExrCompression compression = kDefaultExrCompression,
                  std::vector<std::string> late_details = {});
  const std::filesystem::path& path() const { return writer_.path(); }
  // The next band of maps (the stack's width and channels, in description order).
  void Write(ConstImageView maps) { writer_.WriteNext(maps); }
  // `late_values` holds a value for every late detail named at construction. Throws Error naming
  // path() when one is missing or its JSON is longer than kLateDetailBytes.
  void Commit(const nlohmann::json& late_values = nlohmann::json::object());

 private:
  ImageBandWriter writer_;
  std::vector<std::string> late_details_;
  std::size_t description_bytes_ = 0;
};

}  // namespace photomat
