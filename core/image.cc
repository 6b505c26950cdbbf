#include "core/image.h"

#include <fmt/format.h>

#include <algorithm>

#include "core/error.h"

namespace photomat {
namespace {

// 2^31 values keeps every index arithmetic in range and is far above any capture (a 100 MP
// RGB frame has 3e8 values); larger requests are corrupt headers, not images.
constexpr std::size_t kMaxValues = std::size_t{1} << 31;

void CheckShape(const ImageExtent& extent, int channels) {
  if (extent.width < 0 || extent.height < 0 || extent.depth < 0 || channels < 0 ||
      extent.pixel_count() * static_cast<std::size_t>(channels) > kMaxValues) {
    throw Error(
        fmt::format("unsupported image shape {} with {} channels", ToString(extent), channels));
  }
}

}  // namespace

std::string ToString(const ImageExtent& extent) {
  return fmt::format("{}x{}x{}", extent.width, extent.height, extent.depth);
}

void CheckRange(int first, int count, int size, const char* what) {
  if (first < 0 || count < 0 || first + count > size) {
    throw Error(
        fmt::format("{} [{}, {}) are outside an image of {}", what, first, first + count, size));
  }
}

Image::Image(int width, int height, int channels) : extent_{width, height, 1}, channels_(channels) {
  CheckShape(extent_, channels);
  values_.assign(pixel_count() * static_cast<std::size_t>(channels), 0.0f);
}

Image::Image(int width, int height, std::vector<std::string> channel_names)
    : Image(width, height, static_cast<int>(channel_names.size())) {
  channel_names_ = std::move(channel_names);
}

Image::Image(ImageExtent extent, int channels) : extent_(extent), channels_(channels) {
  if (extent.width <= 0 || extent.height <= 0 || extent.depth <= 0 || channels <= 0) {
    throw Error(fmt::format("invalid image size {} with {} channels", ToString(extent), channels));
  }
  CheckShape(extent, channels);
  values_.assign(pixel_count() * static_cast<std::size_t>(channels), 0.0f);
}

Image::Image(ImageExtent extent, std::vector<std::string> channel_names)
    : Image(extent, static_cast<int>(channel_names.size())) {
  channel_names_ = std::move(channel_names);
}

Image::Image(ConstImageView view) : Image(view.width(), view.height(), view.channels()) {
  CopyPixels(view, View());
}

ImageView Image::SliceXY(int z) {
  CheckRange(z, 1, depth(), "slices");
  return {values_.data() + Index(0, 0, z), width(), height(), channels_, width(), PlaneStride()};
}

// The read-only slices are the writable ones seen through const: one computation of each
// view's geometry (the const_cast never writes).
ConstImageView Image::SliceXY(int z) const { return const_cast<Image*>(this)->SliceXY(z); }

ImageView Image::SliceXZ(int y) {
  CheckRange(y, 1, height(), "rows");
  return {values_.data() + Index(0, y, 0),
          width(),
          depth(),
          channels_,
          static_cast<std::ptrdiff_t>(width()) * height(),
          PlaneStride()};
}

ConstImageView Image::SliceXZ(int y) const { return const_cast<Image*>(this)->SliceXZ(y); }

void Image::set_channel_names(std::vector<std::string> names) {
  if (!names.empty() && static_cast<int>(names.size()) != channels_) {
    throw Error(
        fmt::format("{} channel names given for an image of {} channels", names.size(), channels_));
  }
  channel_names_ = std::move(names);
}

int Image::FindChannel(const std::string& name) const {
  const auto it = std::find(channel_names_.begin(), channel_names_.end(), name);
  return it == channel_names_.end() ? -1 : static_cast<int>(it - channel_names_.begin());
}

Image Image::Channels(int first, int count) const {
  CheckRange(first, count, channels_, "channels");
  Image out(extent_.depth == 1 ? Image(width(), height(), count) : Image(extent_, count));
  std::copy_n(values_.begin() + static_cast<std::ptrdiff_t>(PlaneOffset(first)), PlaneOffset(count),
              out.values_.begin());
  if (!channel_names_.empty()) {
    out.channel_names_.assign(channel_names_.begin() + first,
                              channel_names_.begin() + first + count);
  }
  return out;
}

void CopyPixels(ConstImageView from, ImageView to) {
  if (from.width() != to.width() || from.height() != to.height() ||
      from.channels() != to.channels()) {
    throw Error(fmt::format("cannot copy {}x{} pixels of {} channels into {}x{} of {}",
                            from.width(), from.height(), from.channels(), to.width(), to.height(),
                            to.channels()));
  }
  for (int c = 0; c < from.channels(); ++c) {
    for (int y = 0; y < from.height(); ++y) {
      const auto source = from.row(c, y);
      std::copy(source.begin(), source.end(), to.row(c, y).begin());
    }
  }
}

Mask::Mask(int width, int height, bool value) : width_(width), height_(height) {
  CheckShape({width, height, 1}, 1);
  bits_.assign(static_cast<std::size_t>(width) * height, value ? 1 : 0);
}

std::size_t Mask::CountSet() const {
  return static_cast<std::size_t>(std::count(bits_.begin(), bits_.end(), 1));
}

std::vector<std::size_t> Mask::SetIndices() const {
  std::vector<std::size_t> indices;
  indices.reserve(CountSet());
  for (std::size_t i = 0; i < bits_.size(); ++i) {
    if (bits_[i]) indices.push_back(i);
  }
  return indices;
}

}  // namespace photomat
