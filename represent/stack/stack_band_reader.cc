#include "represent/stack/stack_band_reader.h"

#include <fmt/format.h>

#include <algorithm>
#include <cctype>

#include "core/error.h"

namespace photomat {
namespace {

namespace fs = std::filesystem;

ImageReadOptions StackReadOptions() {
  ImageReadOptions options;
  options.keep_alpha = true;  // a stack's every channel is a map
  return options;
}

// The file channel of each of `names` (all present: StackFromDescription checked them).
std::vector<int> FileChannels(const std::vector<std::string>& file_names,
                              const std::vector<std::string>& names) {
  std::vector<int> channels;
  for (const std::string& name : names) {
    const auto it = std::find(file_names.begin(), file_names.end(), name);
    channels.push_back(static_cast<int>(it - file_names.begin()));
  }
  return channels;
}

Image Gather(const Image& stored, const std::vector<int>& channels,
             const std::vector<std::string>& names) {
  Image out(stored.width(), stored.height(), names);
  for (std::size_t c = 0; c < channels.size(); ++c) {
    const std::span<const float> in = stored.plane(channels[c]);
    std::copy(in.begin(), in.end(), out.plane(static_cast<int>(c)).begin());
  }
  return out;
}

// The description is checked against the file's channel names once, on one row of zeros: the
// representation it gives is the template every band's maps are put into.
LoadedStack ReadHeader(const ImageBandReader& reader) {
  const auto attribute = reader.info().attributes.find(kStackAttribute);
  if (attribute == reader.info().attributes.end()) {
    throw Error(reader.path(), fmt::format("not a photomat map stack (no \"{}\" header attribute)",
                                           kStackAttribute));
  }
  return StackFromDescription(attribute->second, Image(reader.width(), 1, reader.channel_names()),
                              reader.path());
}

}  // namespace

StackBandReader::StackBandReader(const fs::path& path)
    : path_(path),
      reader_(path, StackReadOptions()),
      header_(ReadHeader(reader_)),
      map_channels_(
          FileChannels(reader_.channel_names(), header_.representation.maps().channel_names())) {
  if (!header_.extra_layers.empty()) {
    extra_channels_ = FileChannels(reader_.channel_names(), header_.extra_layers.channel_names());
  }
}

void StackBandReader::Rewind() { reader_ = ImageBandReader(path_, StackReadOptions()); }

LoadedStack StackBandReader::ReadNext(int rows) {
  const int count = std::min(rows, height() - next_row());
  if (count < 1) throw Error(path_, "read past the last row of the stack");
  Image stored(width(), count, stored_channels());
  reader_.ReadNext(stored.View());
  Image extra_layers;
  if (!extra_channels_.empty()) {
    extra_layers = Gather(stored, extra_channels_, header_.extra_layers.channel_names());
  }
  return {header_.representation.WithMaps(
              Gather(stored, map_channels_, header_.representation.maps().channel_names())),
          header_.provenance, std::move(extra_layers)};
}

bool IsStreamableStack(const fs::path& path) {
  std::string extension = path.extension().string();
  std::transform(extension.begin(), extension.end(), extension.begin(),
                 [](unsigned char c) { return static_cast<char>(std::tolower(c)); });
  return extension == ".exr";
}

}  // namespace photomat
