#pragma once

#include <filesystem>
#include <vector>

#include "core/image.h"
#include "core/photometric_set.h"

namespace photomat {

// What is a measurement and what is not, and the camera's dark signal.

struct ExposureLimits {
  // A pixel with a channel at or above this (linear, integer full scale = 1) is clipped.
  double saturation = 0.999;
  // A pixel whose channels are all at or below this is under-exposed (no signal above the dark
  // level); 0 keeps every pixel with any signal.
  double under_exposure = 0.0;
};

// Per image, the pixels that are measurements: not clipped and not under-exposed. Compute them on
// the images as read (before dividing by light intensities or gains, which move the clipping
// level). RobustFitOptions::measured takes them.
std::vector<Mask> MeasuredPixelMasks(const PhotometricSet& set, const ExposureLimits& limits = {});

// Share of pixels (over the set's mask) that are clipped and under-exposed, per image.
struct ExposureCounts {
  std::vector<std::size_t> clipped;
  std::vector<std::size_t> under_exposed;
};
ExposureCounts CountExposureFaults(const PhotometricSet& set, const ExposureLimits& limits = {});

// The dark frame of a folder of frames taken with the lens capped (their mean, which averages the
// read noise down), or of a single image file. Throws Error naming the file or folder when there
// are no images or they differ in size.
Image ReadDarkFrame(const std::filesystem::path& path);

// Subtracts the dark frame from every image (negative results are kept: clamping would bias the
// mean of dark pixels upward). Throws Error naming the set's source when the sizes differ; a
// one-channel dark frame applies to every channel.
PhotometricSet SubtractDarkFrame(const PhotometricSet& set, const Image& dark);

}  // namespace photomat
