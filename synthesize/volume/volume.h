#pragma once

#include <cstddef>
#include <optional>
#include <span>
#include <string>
#include <string_view>
#include <vector>

#include "core/image.h"

namespace photomat {

// A solid texture is an Image (core/image.h) of depth > 1: width x height x depth voxels, x
// fastest, then y, then z, each channel a plane. Any number of channels, so that a relightable
// representation's maps (normal, albedo, PTM terms) can be a volume as well as a colour; channel
// names say what each one is.

// "64" (a cube) or "XxYxZ"; nullopt for anything else or non-positive sizes.
std::optional<ImageExtent> ParseVolumeSize(std::string_view text);

// The three slice orientations of a solid texture, named by the plane they lie in. The pixel axes
// of a slice are fixed (Dischler et al. 1998, section 5, where the orientation of a model changes
// the result): xy at z = i has x along columns and y along rows; xz at y = i has x along columns
// and z along rows; yz at x = i has y along columns and z along rows. Row 0 is the top of an
// exported image.
enum class SlicePlane { kXY = 0, kXZ = 1, kYZ = 2 };

std::string_view ToString(SlicePlane plane);
std::optional<SlicePlane> ParseSlicePlane(std::string_view text);  // "xy", "xz", "yz"
constexpr SlicePlane kAllSlicePlanes[] = {SlicePlane::kXY, SlicePlane::kXZ, SlicePlane::kYZ};

// Width and height of a slice of `size` in `plane` (see SlicePlane for the axes).
std::pair<int, int> SliceDimensions(const ImageExtent& size, SlicePlane plane);
// Number of slices of that orientation.
int SliceCount(const ImageExtent& size, SlicePlane plane);

// Slice `index` of `plane` as an image with the volume's channels and names: a copy (an xy or xz
// slice read in place is volume.SliceXY(z) or volume.SliceXZ(y); a yz slice has no unit x
// stride, so it is always copied). Throws Error for an index outside the volume.
Image ExtractSlice(const Image& volume, SlicePlane plane, int index);
// Writes `slice` (of SliceDimensions and the volume's channel count) back into the volume.
void InsertSlice(Image& volume, SlicePlane plane, int index, ConstImageView slice);

// The volume's channel names, or "channel0", "channel1", ... when it has none.
std::vector<std::string> ChannelNamesOrDefault(const Image& volume);

// Mean of the channels at every voxel (the luminance used by structure measures).
std::vector<float> ChannelMean(const Image& volume);

}  // namespace photomat
