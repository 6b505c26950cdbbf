#include "core/image.h"

#include <fmt/format.h>

#include <algorithm>

#include "core/error.h"

namespace photomat {
namespace {

// 2^31 values keeps every index arithmetic in range and is far above any capture (a 100 MP
// RGB frame has 3e8 values); larger requests are corrupt headers, not images.
constexpr std::size_t kMaxValues = std::size_t{1} << 31;

void CheckShape(int width, int height, int channels) {
  if (width < 0 || height < 0 || channels < 0 ||
      static_cast<std::size_t>(width) * height * channels > kMaxValues) {
    throw Error(
        fmt::format("unsupported image shape {}x{} with {} channels", width, height, channels));
  }
}

}  // namespace

Image::Image(int width, int height, int channels)
    : width_(width), height_(height), channels_(channels) {
  CheckShape(width, height, channels);
  values_.assign(static_cast<std::size_t>(width) * height * channels, 0.0f);
}

Image::Image(int width, int height, std::vector<std::string> channel_names)
    : Image(width, height, static_cast<int>(channel_names.size())) {
  channel_names_ = std::move(channel_names);
}

void Image::set_channel_names(std::vector<std::string> names) {
  if (static_cast<int>(names.size()) != channels_) {
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
  if (first < 0 || count < 0 || first + count > channels_) {
    throw Error(fmt::format("channels [{}, {}) are outside an image of {} channels", first,
                            first + count, channels_));
  }
  Image out(width_, height_, count);
  for (std::size_t i = 0; i < pixel_count(); ++i) {
    std::copy_n(pixel(i).begin() + first, count, out.pixel(i).begin());
  }
  if (!channel_names_.empty()) {
    out.channel_names_.assign(channel_names_.begin() + first,
                              channel_names_.begin() + first + count);
  }
  return out;
}

Mask::Mask(int width, int height, bool value) : width_(width), height_(height) {
  CheckShape(width, height, 1);
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
