#include "synthesize/volume/volume.h"

#include <fmt/format.h>

#include <charconv>

#include "core/enum_names.h"
#include "core/error.h"

namespace photomat {
namespace {

std::optional<int> ParsePositive(std::string_view text) {
  int value = 0;
  const auto [end, error] = std::from_chars(text.data(), text.data() + text.size(), value);
  if (error != std::errc() || end != text.data() + text.size() || value <= 0) return std::nullopt;
  return value;
}

constexpr std::array<NamedValue<SlicePlane>, 3> kSlicePlaneNames = {
    {{SlicePlane::kXY, "xy"}, {SlicePlane::kXZ, "xz"}, {SlicePlane::kYZ, "yz"}}};

}  // namespace

std::optional<ImageExtent> ParseVolumeSize(std::string_view text) {
  std::vector<int> parts;
  std::size_t start = 0;
  while (true) {
    const std::size_t end = text.find('x', start);
    const auto value = ParsePositive(text.substr(start, end - start));
    if (!value) return std::nullopt;
    parts.push_back(*value);
    if (end == std::string_view::npos) break;
    start = end + 1;
  }
  if (parts.size() == 1) return ImageExtent::Cube(parts[0]);
  if (parts.size() == 3) return ImageExtent{parts[0], parts[1], parts[2]};
  return std::nullopt;
}

std::string_view ToString(SlicePlane plane) { return NameOf(plane, kSlicePlaneNames); }

std::optional<SlicePlane> ParseSlicePlane(std::string_view text) {
  return FindValueNamed(text, kSlicePlaneNames);
}

std::pair<int, int> SliceDimensions(const ImageExtent& size, SlicePlane plane) {
  switch (plane) {
    case SlicePlane::kXY:
      return {size.width, size.height};
    case SlicePlane::kXZ:
      return {size.width, size.depth};
    case SlicePlane::kYZ:
      return {size.height, size.depth};
  }
  return {0, 0};
}

int SliceCount(const ImageExtent& size, SlicePlane plane) {
  switch (plane) {
    case SlicePlane::kXY:
      return size.depth;
    case SlicePlane::kXZ:
      return size.height;
    case SlicePlane::kYZ:
      return size.width;
  }
  return 0;
}

namespace {

void CheckSliceIndex(const Image& volume, SlicePlane plane, int index) {
  if (index < 0 || index >= SliceCount(volume.extent(), plane)) {
    throw Error(fmt::format("slice {} of plane {} outside a volume of {}", index, ToString(plane),
                            ToString(volume.extent())));
  }
}

}  // namespace

Image ExtractSlice(const Image& volume, SlicePlane plane, int index) {
  CheckSliceIndex(volume, plane, index);
  Image slice;
  if (plane == SlicePlane::kXY) {
    slice = Image(volume.SliceXY(index));
  } else if (plane == SlicePlane::kXZ) {
    slice = Image(volume.SliceXZ(index));
  } else {
    // Column y of row z is voxel (index, y, z): a gather with stride width.
    slice = Image(volume.height(), volume.depth(), volume.channels());
    for (int c = 0; c < volume.channels(); ++c) {
      for (int z = 0; z < volume.depth(); ++z) {
        float* row = slice.row(c, z).data();
        for (int y = 0; y < volume.height(); ++y) row[y] = volume.at(index, y, z, c);
      }
    }
  }
  slice.set_channel_names(volume.channel_names());
  return slice;
}

void InsertSlice(Image& volume, SlicePlane plane, int index, ConstImageView slice) {
  const auto [width, height] = SliceDimensions(volume.extent(), plane);
  if (slice.width() != width || slice.height() != height || slice.channels() != volume.channels()) {
    throw Error(fmt::format("a {}x{}x{} image does not fit slice {} of plane {} of a {} volume",
                            slice.width(), slice.height(), slice.channels(), index, ToString(plane),
                            ToString(volume.extent())));
  }
  CheckSliceIndex(volume, plane, index);
  if (plane == SlicePlane::kXY) {
    CopyPixels(slice, volume.SliceXY(index));
  } else if (plane == SlicePlane::kXZ) {
    CopyPixels(slice, volume.SliceXZ(index));
  } else {
    for (int c = 0; c < volume.channels(); ++c) {
      for (int z = 0; z < volume.depth(); ++z) {
        const float* row = slice.row(c, z).data();
        for (int y = 0; y < volume.height(); ++y) volume.at(index, y, z, c) = row[y];
      }
    }
  }
}

std::vector<std::string> ChannelNamesOrDefault(const Image& volume) {
  if (!volume.channel_names().empty()) return volume.channel_names();
  std::vector<std::string> names;
  for (int c = 0; c < volume.channels(); ++c) names.push_back(fmt::format("channel{}", c));
  return names;
}

std::vector<float> ChannelMean(const Image& volume) {
  std::vector<float> mean(volume.pixel_count(), 0.0f);
  for (int c = 0; c < volume.channels(); ++c) {
    const std::span<const float> plane = volume.plane(c);
    for (std::size_t i = 0; i < mean.size(); ++i) mean[i] += plane[i];
  }
  const float scale = 1.0f / static_cast<float>(volume.channels());
  for (float& m : mean) m *= scale;
  return mean;
}

}  // namespace photomat
