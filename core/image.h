#pragma once

#include <compare>
#include <cstddef>
#include <cstdint>
#include <iterator>
#include <span>
#include <string>
#include <type_traits>
#include <utility>
#include <vector>

namespace photomat {

// The extent of an image: width x height pixels in each of `depth` slices (1 for a picture, more
// for a solid texture).
struct ImageExtent {
  int width = 0;
  int height = 0;
  int depth = 1;

  std::size_t pixel_count() const {
    return static_cast<std::size_t>(width) * static_cast<std::size_t>(height) *
           static_cast<std::size_t>(depth);
  }
  bool operator==(const ImageExtent&) const = default;
  static ImageExtent Cube(int n) { return {n, n, n}; }
};

// "WxHxD".
std::string ToString(const ImageExtent& extent);

// Throws Error naming `what` unless [first, first + count) lies in [0, size).
void CheckRange(int first, int count, int size, const char* what);

// A random-access iterator over values `stride` floats apart (the channels of one pixel).
template <typename T>
class StridedIterator {
 public:
  using iterator_category = std::random_access_iterator_tag;
  using iterator_concept = std::random_access_iterator_tag;
  using value_type = std::remove_cv_t<T>;
  using difference_type = std::ptrdiff_t;
  using pointer = T*;
  using reference = T&;

  StridedIterator() = default;
  StridedIterator(T* value, std::ptrdiff_t stride) : value_(value), stride_(stride) {}

  T& operator*() const { return *value_; }
  T& operator[](difference_type n) const { return value_[n * stride_]; }
  StridedIterator& operator++() { return value_ += stride_, *this; }
  StridedIterator operator++(int) {
    return StridedIterator(std::exchange(value_, value_ + stride_), stride_);
  }
  StridedIterator& operator--() { return value_ -= stride_, *this; }
  StridedIterator operator--(int) {
    return StridedIterator(std::exchange(value_, value_ - stride_), stride_);
  }
  StridedIterator& operator+=(difference_type n) { return value_ += n * stride_, *this; }
  StridedIterator& operator-=(difference_type n) { return value_ -= n * stride_, *this; }
  friend StridedIterator operator+(StridedIterator i, difference_type n) { return i += n; }
  friend StridedIterator operator+(difference_type n, StridedIterator i) { return i += n; }
  friend StridedIterator operator-(StridedIterator i, difference_type n) { return i -= n; }
  friend difference_type operator-(const StridedIterator& a, const StridedIterator& b) {
    return a.stride_ == 0 ? 0 : (a.value_ - b.value_) / a.stride_;
  }
  friend bool operator==(const StridedIterator& a, const StridedIterator& b) {
    return a.value_ == b.value_;
  }
  friend std::strong_ordering operator<=>(const StridedIterator& a, const StridedIterator& b) {
    return a.stride_ < 0 ? b.value_ <=> a.value_ : a.value_ <=> b.value_;
  }

 private:
  T* value_ = nullptr;
  std::ptrdiff_t stride_ = 1;
};

// The channel values of one pixel of a planar image: `count` values, one per plane, `stride`
// floats apart. For code that reads or writes a pixel's n-vector (the maps of one pixel); loops
// over many pixels read better, and run faster, plane by plane.
template <typename T>
class PixelValues {
 public:
  PixelValues(T* first, std::ptrdiff_t stride, int count)
      : first_(first), stride_(stride), count_(count) {}
  // A writable pixel reads as a read-only one.
  template <typename U>
  requires(std::is_same_v<const U, T> && !std::is_same_v<U, T>)
      PixelValues(const PixelValues<U>& other)  // NOLINT: implicit by design
      : first_(other.data()), stride_(other.stride()), count_(static_cast<int>(other.size())) {}

  std::size_t size() const { return static_cast<std::size_t>(count_); }
  template <typename Index>
  requires std::is_integral_v<Index> T& operator[](Index c) const {
    return first_[static_cast<std::ptrdiff_t>(c) * stride_];
  }
  StridedIterator<T> begin() const { return {first_, stride_}; }
  StridedIterator<T> end() const { return {first_ + count_ * stride_, stride_}; }
  T* data() const { return first_; }
  std::ptrdiff_t stride() const { return stride_; }

 private:
  T* first_;
  std::ptrdiff_t stride_;
  int count_;
};

// A non-owning view of a planar image: `channels` planes of height rows of width values, x
// fastest (unit stride), rows `row_stride` values apart and planes `plane_stride` apart. A band of
// rows, a subset of channels and the xy and xz slices of a solid texture are all views of the same
// storage, with no copy. Functions that only read an image take a ConstImageView, so that all of
// these pass as they are.
template <typename T>
class BasicImageView {
 public:
  BasicImageView() = default;
  BasicImageView(T* data, int width, int height, int channels, std::ptrdiff_t row_stride,
                 std::ptrdiff_t plane_stride)
      : data_(data),
        width_(width),
        height_(height),
        channels_(channels),
        row_stride_(row_stride),
        plane_stride_(plane_stride) {}
  // A writable view reads as a read-only one.
  template <typename U>
  requires(std::is_same_v<const U, T> && !std::is_same_v<U, T>)
      BasicImageView(const BasicImageView<U>& other)  // NOLINT: implicit by design
      : BasicImageView(other.data(), other.width(), other.height(), other.channels(),
                       other.row_stride(), other.plane_stride()) {}

  int width() const { return width_; }
  int height() const { return height_; }
  int channels() const { return channels_; }
  std::ptrdiff_t row_stride() const { return row_stride_; }
  std::ptrdiff_t plane_stride() const { return plane_stride_; }
  std::size_t pixel_count() const { return static_cast<std::size_t>(width_) * height_; }
  bool empty() const { return width_ <= 0 || height_ <= 0 || channels_ <= 0; }
  T* data() const { return data_; }

  T& at(int x, int y, int c) const { return data_[Offset(x, y, c)]; }
  // Row y of channel c: width contiguous values.
  std::span<T> row(int c, int y) const {
    return {data_ + Offset(0, y, c), static_cast<std::size_t>(width_)};
  }
  PixelValues<T> pixel(int x, int y) const {
    return {data_ + Offset(x, y, 0), plane_stride_, channels_};
  }

  // Rows [first, first + count): a band of the image. Throws Error outside the image.
  BasicImageView Rows(int first, int count) const {
    CheckRange(first, count, height_, "rows");
    return {data_ + first * row_stride_, width_, count, channels_, row_stride_, plane_stride_};
  }
  // Channels [first, first + count). Throws Error outside the image.
  BasicImageView ChannelRange(int first, int count) const {
    CheckRange(first, count, channels_, "channels");
    return {data_ + first * plane_stride_, width_, height_, count, row_stride_, plane_stride_};
  }

 private:
  std::ptrdiff_t Offset(int x, int y, int c) const {
    return c * plane_stride_ + y * row_stride_ + x;
  }

  T* data_ = nullptr;
  int width_ = 0;
  int height_ = 0;
  int channels_ = 0;
  std::ptrdiff_t row_stride_ = 0;
  std::ptrdiff_t plane_stride_ = 0;
};

using ImageView = BasicImageView<float>;
using ConstImageView = BasicImageView<const float>;

// A width x height x depth image of `channels` float values per pixel, stored planar: plane c is
// width * height * depth contiguous values, x fastest, then y, then z; row 0 is the top. A picture
// has depth 1; a solid texture is an image of depth > 1 whose xy slices are stacked along z.
// Planar storage lets every per-channel pass (relighting, scaling, filters, FFTs, OpenCV calls)
// stream one contiguous plane, and lets views select rows, channels and slices without copies.
// Channel names are optional; map stacks name them by meaning ("normal.X", "ptm.a0.R").
class Image {
 public:
  Image() = default;
  // Zero-filled. Throws Error for negative or absurd sizes.
  Image(int width, int height, int channels);
  Image(int width, int height, std::vector<std::string> channel_names);
  // Zero-filled. Throws Error unless every extent and the channel count are positive (and the
  // image not absurdly large).
  Image(ImageExtent extent, int channels);
  Image(ImageExtent extent, std::vector<std::string> channel_names);
  // A copy of the pixels of `view` (without channel names).
  explicit Image(ConstImageView view);

  int width() const { return extent_.width; }
  int height() const { return extent_.height; }
  int depth() const { return extent_.depth; }
  const ImageExtent& extent() const { return extent_; }
  int channels() const { return channels_; }
  // Pixels of one plane: width * height * depth.
  std::size_t pixel_count() const { return extent_.pixel_count(); }
  bool empty() const { return values_.empty(); }
  bool SameShape(const Image& other) const {
    return extent_ == other.extent_ && channels_ == other.channels_;
  }

  float& at(int x, int y, int c) { return values_[Offset(x, y, 0, c)]; }
  float at(int x, int y, int c) const { return values_[Offset(x, y, 0, c)]; }
  float& at(int x, int y, int z, int c) { return values_[Offset(x, y, z, c)]; }
  float at(int x, int y, int z, int c) const { return values_[Offset(x, y, z, c)]; }
  // Plane c: pixel_count() values.
  std::span<float> plane(int c) { return {values_.data() + PlaneOffset(c), pixel_count()}; }
  std::span<const float> plane(int c) const {
    return {values_.data() + PlaneOffset(c), pixel_count()};
  }
  // Row y of slice z of plane c: width values.
  std::span<float> row(int c, int y, int z = 0) {
    return {values_.data() + Offset(0, y, z, c), static_cast<std::size_t>(width())};
  }
  std::span<const float> row(int c, int y, int z = 0) const {
    return {values_.data() + Offset(0, y, z, c), static_cast<std::size_t>(width())};
  }
  // The channel values of one pixel (see PixelValues).
  PixelValues<float> pixel(int x, int y, int z = 0) { return pixel(Index(x, y, z)); }
  PixelValues<const float> pixel(int x, int y, int z = 0) const { return pixel(Index(x, y, z)); }
  // Pixel by linear index (z * height + y) * width + x.
  PixelValues<float> pixel(std::size_t index) {
    return {values_.data() + index, PlaneStride(), channels_};
  }
  PixelValues<const float> pixel(std::size_t index) const {
    return {values_.data() + index, PlaneStride(), channels_};
  }
  std::size_t Index(int x, int y, int z = 0) const {
    return (static_cast<std::size_t>(z) * height() + y) * width() + x;
  }
  // All values, plane after plane.
  std::span<float> values() { return values_; }
  std::span<const float> values() const { return values_; }

  // Views of slice 0 (the whole of a picture).
  ImageView View() { return SliceXY(0); }
  ConstImageView View() const { return SliceXY(0); }
  operator ConstImageView() const { return View(); }  // NOLINT: implicit by design
  ImageView Rows(int first, int count) { return View().Rows(first, count); }
  ConstImageView Rows(int first, int count) const { return View().Rows(first, count); }
  ImageView ChannelRange(int first, int count) { return View().ChannelRange(first, count); }
  ConstImageView ChannelRange(int first, int count) const {
    return View().ChannelRange(first, count);
  }
  // The slices of a solid texture: xy at depth z (x along columns, y along rows) and xz at row y
  // (x along columns, z along rows), both with unit x stride. A yz slice has none (its columns
  // are y): ExtractSlice (synthesize/volume) copies it.
  ImageView SliceXY(int z);
  ConstImageView SliceXY(int z) const;
  ImageView SliceXZ(int y);
  ConstImageView SliceXZ(int y) const;

  // Empty, or one name per channel (Error otherwise).
  const std::vector<std::string>& channel_names() const { return channel_names_; }
  void set_channel_names(std::vector<std::string> names);
  // Index of the channel with this name, or -1.
  int FindChannel(const std::string& name) const;

  // The channels [first, first + count) as a new image (names kept).
  Image Channels(int first, int count) const;

 private:
  std::ptrdiff_t PlaneStride() const { return static_cast<std::ptrdiff_t>(pixel_count()); }
  std::size_t PlaneOffset(int c) const { return static_cast<std::size_t>(c) * pixel_count(); }
  std::size_t Offset(int x, int y, int z, int c) const { return PlaneOffset(c) + Index(x, y, z); }

  ImageExtent extent_{0, 0, 1};
  int channels_ = 0;
  std::vector<float> values_;
  std::vector<std::string> channel_names_;
};

// Copies the pixels of `from` into `to` (same width, height and channels; Error otherwise).
void CopyPixels(ConstImageView from, ImageView to);

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
