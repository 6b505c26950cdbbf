#include "calibrate/radiometry/exposure.h"

#include <fmt/format.h>
#include <tbb/parallel_for.h>

#include <algorithm>

#include "core/error.h"
#include "core/image_io.h"

namespace photomat {
namespace {

namespace fs = std::filesystem;

bool Clipped(PixelValues<const float> pixel, double level) {
  return std::any_of(pixel.begin(), pixel.end(), [&](float v) { return v >= level; });
}
bool UnderExposed(PixelValues<const float> pixel, double level) {
  return std::all_of(pixel.begin(), pixel.end(), [&](float v) { return v <= level; });
}

PhotometricSet WithImages(const PhotometricSet& set, std::vector<Image> images) {
  PhotometricSet out(std::move(images), set.lights(), set.image_names(), set.source());
  if (set.mask()) out.set_mask(*set.mask());
  if (!set.intensities().empty()) out.set_intensities(set.intensities());
  return out;
}

}  // namespace

std::vector<Mask> MeasuredPixelMasks(const PhotometricSet& set, const ExposureLimits& limits) {
  std::vector<Mask> masks(set.size());
  tbb::parallel_for(0, set.size(), [&](int i) {
    const Image& image = set.image(i);
    Mask mask(image.width(), image.height(), true);
    for (std::size_t p = 0; p < image.pixel_count(); ++p) {
      const auto pixel = image.pixel(p);
      if (Clipped(pixel, limits.saturation) || UnderExposed(pixel, limits.under_exposure)) {
        mask.Set(p, false);
      }
    }
    masks[i] = std::move(mask);
  });
  return masks;
}

ExposureCounts CountExposureFaults(const PhotometricSet& set, const ExposureLimits& limits) {
  ExposureCounts counts;
  counts.clipped.resize(set.size());
  counts.under_exposed.resize(set.size());
  const std::vector<std::size_t> pixels = set.MaskOrAll().SetIndices();
  tbb::parallel_for(0, set.size(), [&](int i) {
    for (std::size_t p : pixels) {
      const auto pixel = set.image(i).pixel(p);
      if (Clipped(pixel, limits.saturation)) ++counts.clipped[i];
      if (UnderExposed(pixel, limits.under_exposure)) ++counts.under_exposed[i];
    }
  });
  return counts;
}

Image ReadDarkFrame(const fs::path& path) {
  std::vector<fs::path> files{path};
  if (fs::is_directory(path)) {
    files = ListImageFiles(path);
    if (files.empty()) throw Error(path, "no dark-frame images in the folder");
  }
  Image sum = ReadImage(files.front()).image;
  for (std::size_t i = 1; i < files.size(); ++i) {
    const Image frame = ReadImage(files[i]).image;
    if (!frame.SameShape(sum)) {
      throw Error(files[i],
                  fmt::format("dark frame is {}x{}x{} but {} is {}x{}x{}", frame.width(),
                              frame.height(), frame.channels(), files.front().filename().string(),
                              sum.width(), sum.height(), sum.channels()));
    }
    const auto values = frame.values();
    auto total = sum.values();
    for (std::size_t v = 0; v < total.size(); ++v) total[v] += values[v];
  }
  for (float& v : sum.values()) v /= static_cast<float>(files.size());
  return sum;
}

PhotometricSet SubtractDarkFrame(const PhotometricSet& set, const Image& dark) {
  if (dark.width() != set.width() || dark.height() != set.height() ||
      (dark.channels() != 1 && dark.channels() != set.channels())) {
    set.Fail(fmt::format(
        "the dark frame is {}x{} with {} channels but the images are {}x{} with {}", dark.width(),
        dark.height(), dark.channels(), set.width(), set.height(), set.channels()));
  }
  std::vector<Image> images(set.size());
  tbb::parallel_for(0, set.size(), [&](int i) {
    Image image = set.image(i);
    for (int c = 0; c < image.channels(); ++c) {
      const std::span<const float> d = dark.plane(dark.channels() == 1 ? 0 : c);
      const std::span<float> values = image.plane(c);
      for (std::size_t p = 0; p < values.size(); ++p) values[p] -= d[p];
    }
    images[i] = std::move(image);
  });
  return WithImages(set, std::move(images));
}

}  // namespace photomat
