#pragma once

#include <cstdint>
#include <filesystem>
#include <vector>

#include "core/image.h"

namespace photomat {

// A pixel position in the sample.
struct SamplePixel {
  std::int32_t x = -1;
  std::int32_t y = -1;
  bool valid() const { return x >= 0; }
  friend bool operator==(const SamplePixel&, const SamplePixel&) = default;
};

// The outcome of a synthesis as a coordinate transform: for every output pixel, the sample pixel
// it copies. Both synthesis methods copy whole pixels, so an output is `map.Apply(sample)`, every
// output n-vector is a sample n-vector, and the same map grows any other maps of the same sample
// (another representation, a relit image, a mask) exactly as it grew the guide.
class SourceMap {
 public:
  SourceMap() = default;
  // Every pixel unset.
  SourceMap(int width, int height, int sample_width, int sample_height);

  int width() const { return width_; }
  int height() const { return height_; }
  int sample_width() const { return sample_width_; }
  int sample_height() const { return sample_height_; }

  SamplePixel at(int x, int y) const { return pixels_[Index(x, y)]; }
  void Set(int x, int y, SamplePixel source) { pixels_[Index(x, y)] = source; }
  const std::vector<SamplePixel>& pixels() const { return pixels_; }
  // Every output pixel has a source inside the sample.
  bool Complete() const;

  // The output: sample pixel at(x, y) for every output pixel. Throws Error if `sample` is not
  // sample_width() x sample_height() or the map is incomplete.
  Image Apply(const Image& sample) const;

  // The map restricted to [0, width) x [0, height) of this one (cropping an oversized canvas).
  SourceMap Cropped(int width, int height) const;

  friend bool operator==(const SourceMap&, const SourceMap&) = default;

 private:
  std::size_t Index(int x, int y) const { return static_cast<std::size_t>(y) * width_ + x; }

  int width_ = 0;
  int height_ = 0;
  int sample_width_ = 0;
  int sample_height_ = 0;
  std::vector<SamplePixel> pixels_;
};

// A source map on disk: a float32 OpenEXR with channels "source.x" and "source.y" (sample
// pixel coordinates, exact in float up to 2^24) and the attribute "photomat:source-map" =
// {"format": "photomat-source-map", "version": 1, "sample_width": W, "sample_height": H}.
// Atomic write; both throw Error naming `path`.
void SaveSourceMap(const std::filesystem::path& path, const SourceMap& map);
SourceMap LoadSourceMap(const std::filesystem::path& path);

}  // namespace photomat
