#include "synthesize/volume/volume.h"

#include <fmt/format.h>

#include <charconv>

#include "core/error.h"

namespace photomat {
namespace {

// 2^31 values at most: keeps every index computation in range and refuses sizes that are typos.
constexpr std::size_t kMaxValues = std::size_t{1} << 31;

std::optional<int> ParsePositive(std::string_view text) {
  int value = 0;
  const auto [end, error] = std::from_chars(text.data(), text.data() + text.size(), value);
  if (error != std::errc() || end != text.data() + text.size() || value <= 0) return std::nullopt;
  return value;
}

}  // namespace

std::optional<VolumeSize> ParseVolumeSize(std::string_view text) {
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
  if (parts.size() == 1) return VolumeSize::Cube(parts[0]);
  if (parts.size() == 3) return VolumeSize{parts[0], parts[1], parts[2]};
  return std::nullopt;
}

std::string ToString(const VolumeSize& size) {
  return fmt::format("{}x{}x{}", size.x, size.y, size.z);
}

std::string_view ToString(SlicePlane plane) {
  switch (plane) {
    case SlicePlane::kXY:
      return "xy";
    case SlicePlane::kXZ:
      return "xz";
    case SlicePlane::kYZ:
      return "yz";
  }
  return "?";
}

std::optional<SlicePlane> ParseSlicePlane(std::string_view text) {
  for (SlicePlane plane : kAllSlicePlanes) {
    if (text == ToString(plane)) return plane;
  }
  return std::nullopt;
}

Volume::Volume(VolumeSize size, int channels) : size_(size), channels_(channels) {
  if (size.x <= 0 || size.y <= 0 || size.z <= 0 || channels <= 0) {
    throw Error(fmt::format("invalid volume size {} with {} channels", ToString(size), channels));
  }
  const std::size_t values = size.voxel_count() * static_cast<std::size_t>(channels);
  if (values / static_cast<std::size_t>(channels) != size.voxel_count() || values > kMaxValues) {
    throw Error(
        fmt::format("volume of {} with {} channels is too large", ToString(size), channels));
  }
  values_.assign(values, 0.0f);
}

Volume::Volume(VolumeSize size, std::vector<std::string> channel_names)
    : Volume(size, static_cast<int>(channel_names.size())) {
  channel_names_ = std::move(channel_names);
}

void Volume::set_channel_names(std::vector<std::string> names) {
  if (!names.empty() && static_cast<int>(names.size()) != channels_) {
    throw Error(
        fmt::format("{} channel names for a volume of {} channels", names.size(), channels_));
  }
  channel_names_ = std::move(names);
}

int Volume::FindChannel(const std::string& name) const {
  for (std::size_t c = 0; c < channel_names_.size(); ++c) {
    if (channel_names_[c] == name) return static_cast<int>(c);
  }
  return -1;
}

std::vector<std::string> Volume::ChannelNamesOrDefault() const {
  if (!channel_names_.empty()) return channel_names_;
  std::vector<std::string> names;
  for (int c = 0; c < channels_; ++c) names.push_back(fmt::format("channel{}", c));
  return names;
}

std::pair<int, int> SliceDimensions(const VolumeSize& size, SlicePlane plane) {
  switch (plane) {
    case SlicePlane::kXY:
      return {size.x, size.y};
    case SlicePlane::kXZ:
      return {size.x, size.z};
    case SlicePlane::kYZ:
      return {size.y, size.z};
  }
  return {0, 0};
}

int SliceCount(const VolumeSize& size, SlicePlane plane) {
  switch (plane) {
    case SlicePlane::kXY:
      return size.z;
    case SlicePlane::kXZ:
      return size.y;
    case SlicePlane::kYZ:
      return size.x;
  }
  return 0;
}

namespace {

// Calls visit(column, row, voxel index) for every pixel of the slice.
template <typename Visit>
void ForEachSlicePixel(const VolumeSize& size, SlicePlane plane, int index, Visit visit) {
  if (index < 0 || index >= SliceCount(size, plane)) {
    throw Error(fmt::format("slice {} of plane {} outside a volume of {}", index, ToString(plane),
                            ToString(size)));
  }
  const auto [width, height] = SliceDimensions(size, plane);
  for (int row = 0; row < height; ++row) {
    for (int column = 0; column < width; ++column) {
      int x = 0, y = 0, z = 0;
      switch (plane) {
        case SlicePlane::kXY:
          x = column, y = row, z = index;
          break;
        case SlicePlane::kXZ:
          x = column, y = index, z = row;
          break;
        case SlicePlane::kYZ:
          x = index, y = column, z = row;
          break;
      }
      visit(column, row, (static_cast<std::size_t>(z) * size.y + y) * size.x + x);
    }
  }
}

}  // namespace

Image ExtractSlice(const Volume& volume, SlicePlane plane, int index) {
  const auto [width, height] = SliceDimensions(volume.size(), plane);
  Image slice(width, height, volume.channels());
  if (!volume.channel_names().empty()) slice.set_channel_names(volume.channel_names());
  ForEachSlicePixel(volume.size(), plane, index, [&](int column, int row, std::size_t voxel) {
    const auto source = volume.voxel(voxel);
    std::copy(source.begin(), source.end(), slice.pixel(column, row).begin());
  });
  return slice;
}

void InsertSlice(Volume& volume, SlicePlane plane, int index, const Image& slice) {
  const auto [width, height] = SliceDimensions(volume.size(), plane);
  if (slice.width() != width || slice.height() != height || slice.channels() != volume.channels()) {
    throw Error(fmt::format("a {}x{}x{} image does not fit slice {} of plane {} of a {} volume",
                            slice.width(), slice.height(), slice.channels(), index, ToString(plane),
                            ToString(volume.size())));
  }
  ForEachSlicePixel(volume.size(), plane, index, [&](int column, int row, std::size_t voxel) {
    const auto source = slice.pixel(column, row);
    std::copy(source.begin(), source.end(), volume.voxel(voxel).begin());
  });
}

std::vector<float> ChannelMean(const Volume& volume) {
  std::vector<float> mean(volume.voxel_count());
  const float scale = 1.0f / static_cast<float>(volume.channels());
  for (std::size_t i = 0; i < mean.size(); ++i) {
    float sum = 0.0f;
    for (float value : volume.voxel(i)) sum += value;
    mean[i] = sum * scale;
  }
  return mean;
}

}  // namespace photomat
