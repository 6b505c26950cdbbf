#pragma once

#include <cstddef>
#include <optional>
#include <span>
#include <string>
#include <string_view>
#include <vector>

#include "core/image.h"

namespace photomat {

// Extent of a voxel grid, x fastest in memory.
struct VolumeSize {
  int x = 0;
  int y = 0;
  int z = 0;

  std::size_t voxel_count() const {
    return static_cast<std::size_t>(x) * static_cast<std::size_t>(y) * static_cast<std::size_t>(z);
  }
  bool operator==(const VolumeSize&) const = default;
  static VolumeSize Cube(int n) { return {n, n, n}; }
};

// "64" (a cube) or "XxYxZ"; nullopt for anything else or non-positive sizes.
std::optional<VolumeSize> ParseVolumeSize(std::string_view text);
std::string ToString(const VolumeSize& size);

// The three slice orientations of a solid texture, named by the plane they lie in. The pixel axes
// of a slice are fixed (Dischler et al. 1998, section 5, where the orientation of a model changes
// the result): xy at z = i has x along columns and y along rows; xz at y = i has x along columns
// and z along rows; yz at x = i has y along columns and z along rows. Row 0 is the top of an
// exported image.
enum class SlicePlane { kXY = 0, kXZ = 1, kYZ = 2 };

std::string_view ToString(SlicePlane plane);
std::optional<SlicePlane> ParseSlicePlane(std::string_view text);  // "xy", "xz", "yz"
constexpr SlicePlane kAllSlicePlanes[] = {SlicePlane::kXY, SlicePlane::kXZ, SlicePlane::kYZ};

// A solid texture: size.x x size.y x size.z voxels of `channels` floats each, interleaved (the
// values of one voxel are contiguous, as in Image), x fastest, then y, then z. Any number of
// channels, so that a relightable representation's maps (normal, albedo, PTM terms) can be a
// volume as well as a colour; channel names say what each one is.
class Volume {
 public:
  Volume() = default;
  // Zero-filled. Throws Error for non-positive or absurd sizes.
  Volume(VolumeSize size, int channels);
  Volume(VolumeSize size, std::vector<std::string> channel_names);

  const VolumeSize& size() const { return size_; }
  int channels() const { return channels_; }
  std::size_t voxel_count() const { return size_.voxel_count(); }
  bool empty() const { return values_.empty(); }
  bool SameShape(const Volume& other) const {
    return size_ == other.size_ && channels_ == other.channels_;
  }

  std::size_t Index(int x, int y, int z) const {
    return (static_cast<std::size_t>(z) * size_.y + y) * size_.x + x;
  }
  float& at(int x, int y, int z, int c) { return values_[Index(x, y, z) * Channels() + c]; }
  float at(int x, int y, int z, int c) const { return values_[Index(x, y, z) * Channels() + c]; }
  std::span<float> voxel(std::size_t index) {
    return {values_.data() + index * Channels(), Channels()};
  }
  std::span<const float> voxel(std::size_t index) const {
    return {values_.data() + index * Channels(), Channels()};
  }
  std::span<float> voxel(int x, int y, int z) { return voxel(Index(x, y, z)); }
  std::span<const float> voxel(int x, int y, int z) const { return voxel(Index(x, y, z)); }
  std::span<float> values() { return values_; }
  std::span<const float> values() const { return values_; }

  // Empty, or one name per channel.
  const std::vector<std::string>& channel_names() const { return channel_names_; }
  void set_channel_names(std::vector<std::string> names);
  int FindChannel(const std::string& name) const;
  // The names, or "channel0", "channel1", ... when there are none.
  std::vector<std::string> ChannelNamesOrDefault() const;

 private:
  std::size_t Channels() const { return static_cast<std::size_t>(channels_); }

  VolumeSize size_;
  int channels_ = 0;
  std::vector<float> values_;
  std::vector<std::string> channel_names_;
};

// Width and height of a slice of `size` in `plane` (see SlicePlane for the axes).
std::pair<int, int> SliceDimensions(const VolumeSize& size, SlicePlane plane);
// Number of slices of that orientation.
int SliceCount(const VolumeSize& size, SlicePlane plane);

// Slice `index` of `plane` as an image with the volume's channels and names.
Image ExtractSlice(const Volume& volume, SlicePlane plane, int index);
// Writes `slice` (of SliceDimensions and the volume's channel count) back into the volume.
void InsertSlice(Volume& volume, SlicePlane plane, int index, const Image& slice);

// Mean of the channels at every voxel (the luminance used by structure measures).
std::vector<float> ChannelMean(const Volume& volume);

}  // namespace photomat
