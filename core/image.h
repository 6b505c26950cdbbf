#pragma once

#include <cstddef>
#include <cstdint>
#include <span>
#include <string>
#include <vector>

namespace photomat {

// A width x height image of `channels` float values per pixel, interleaved (the values of one
// pixel are contiguous) with row 0 at the top. Interleaving keeps a pixel's n-vector in one span,
// which is what synthesis copies and what relighting reads. Channel names are optional; map stacks
// name them by meaning ("normal.X", "ptm.a0.R").
class Image {
 public:
  Image() = default;
  // Zero-filled. Throws Error for negative or absurd sizes.
  Image(int width, int height, int channels);
  Image(int width, int height, std::vector<std::string> channel_names);

  int width() const { return width_; }
  int height() const { return height_; }
  int channels() const { return channels_; }
  std::size_t pixel_count() const { return static_cast<std::size_t>(width_) * height_; }
  bool empty() const { return values_.empty(); }
  bool SameShape(const Image& other) const {
    return width_ == other.width_ && height_ == other.height_ && channels_ == other.channels_;
  }

  float& at(int x, int y, int c) { return values_[Offset(x, y) + c]; }
  float at(int x, int y, int c) const { return values_[Offset(x, y) + c]; }
  std::span<float> pixel(int x, int y) { return {values_.data() + Offset(x, y), Channels()}; }
  std::span<const float> pixel(int x, int y) const {
    return {values_.data() + Offset(x, y), Channels()};
  }
  // Pixel by linear index y * width + x.
  std::span<float> pixel(std::size_t index) {
    return {values_.data() + index * Channels(), Channels()};
  }
  std::span<const float> pixel(std::size_t index) const {
    return {values_.data() + index * Channels(), Channels()};
  }
  std::span<float> values() { return values_; }
  std::span<const float> values() const { return values_; }

  const std::vector<std::string>& channel_names() const { return channel_names_; }
  // Throws Error unless there is one name per channel.
  void set_channel_names(std::vector<std::string> names);
  // Index of the channel with this name, or -1.
  int FindChannel(const std::string& name) const;

  // The channels [first, first + count) as a new image (names kept).
  Image Channels(int first, int count) const;

 private:
  std::size_t Channels() const { return static_cast<std::size_t>(channels_); }
  std::size_t Offset(int x, int y) const {
    return (static_cast<std::size_t>(y) * width_ + x) * Channels();
  }

  int width_ = 0;
  int height_ = 0;
  int channels_ = 0;
  std::vector<float> values_;
  std::vector<std::string> channel_names_;
};

// Which pixels of an image take part (object pixels of DiLiGenT, the sample area of a capture).
class Mask {
 public:
  Mask() = default;
  // All pixels set to `value`.
  Mask(int width, int height, bool value);

  int width() const { return width_; }
  int height() const { return height_; }
  std::size_t pixel_count() const { return bits_.size(); }
  bool operator()(int x, int y) const { return bits_[static_cast<std::size_t>(y) * width_ + x]; }
  bool operator[](std::size_t index) const { return bits_[index] != 0; }
  void Set(int x, int y, bool value) {
    bits_[static_cast<std::size_t>(y) * width_ + x] = value ? 1 : 0;
  }
  void Set(std::size_t index, bool value) { bits_[index] = value ? 1 : 0; }
  std::size_t CountSet() const;
  // Linear indices (y * width + x) of the set pixels, in raster order.
  std::vector<std::size_t> SetIndices() const;
  bool SameSize(const Image& image) const {
    return width_ == image.width() && height_ == image.height();
  }

 private:
  int width_ = 0;
  int height_ = 0;
  std::vector<std::uint8_t> bits_;
};

}  // namespace photomat
