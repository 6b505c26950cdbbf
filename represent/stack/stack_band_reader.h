#pragma once

#include <cstddef>
#include <filesystem>
#include <string>
#include <vector>

#include "core/image_band_io.h"
#include "represent/stack/map_stack.h"

namespace photomat {

// A map stack read band by band of rows in file order (README, "Streamed relighting and
// export"): what streamed relighting, export and evaluation hold of a stack instead of the whole
// of it. The description ("photomat:stack") is read and checked once, when the file is opened;
// each band is then the stack over those rows: a LoadedStack whose representation has the
// band's maps (the same method, light basis and shading: relighting a band gives the rows of the
// whole stack's relit image) and whose extra layers are the band's. Memory is the band plus one
// OpenEXR chunk. Bands equal the rows of LoadRepresentation bit for bit.
class StackBandReader {
 public:
  // Opens `path` (a photomat map stack .exr) and reads its description. Throws Error naming the
  // file as LoadRepresentation does.
  explicit StackBandReader(const std::filesystem::path& path);

  const std::filesystem::path& path() const { return path_; }
  int width() const { return reader_.width(); }
  int height() const { return reader_.height(); }
  int next_row() const { return reader_.next_row(); }
  // The stack's description as over its first row: method, layout, basis, shading, details
  // and the maps' channel names (representation), its provenance and the extra layers' names.
  const LoadedStack& header() const { return header_; }
  // Float channels the file holds (maps and extra layers): 4 bytes per pixel each.
  int stored_channels() const { return reader_.channels(); }

  // The next `rows` rows (fewer at the end of the file) as a stack. Throws Error naming the file
  // when no row is left or the file is truncated or corrupt there.
  LoadedStack ReadNext(int rows);
  // Back to row 0 (the file is opened again: EXR decoders read forward).
  void Rewind();

 private:
  std::filesystem::path path_;
  ImageBandReader reader_;
  LoadedStack header_;
  // The file channel of each map, and of each extra layer, in description order.
  std::vector<int> map_channels_;
  std::vector<int> extra_channels_;
};

// Whether `path` is a map stack StackBandReader reads (an .exr file; .ptm and .rti files and
// photometric sets are read whole).
bool IsStreamableStack(const std::filesystem::path& path);

}  // namespace photomat
