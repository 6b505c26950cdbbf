#include "core/photometric_set.h"

#include <fmt/format.h>

#include <cmath>

#include "core/error.h"

namespace photomat {

PhotometricSet::PhotometricSet(std::vector<Image> images, std::vector<LightDirection> lights,
                               std::vector<std::string> image_names, std::filesystem::path source)
    : images_(std::move(images)),
      lights_(std::move(lights)),
      image_names_(std::move(image_names)),
      source_(std::move(source)) {
  if (images_.empty()) Fail("a photometric set needs at least one image");
  if (lights_.size() != images_.size()) {
    Fail(fmt::format("{} images but {} light directions", images_.size(), lights_.size()));
  }
  if (image_names_.empty()) {
    for (int i = 0; i < size(); ++i) image_names_.push_back(fmt::format("image {}", i));
  }
  if (image_names_.size() != images_.size()) {
    Fail(fmt::format("{} images but {} image names", images_.size(), image_names_.size()));
  }
  const Image& first = images_.front();
  if (first.empty()) Fail(fmt::format("{} is empty", image_names_.front()));
  for (int i = 1; i < size(); ++i) {
    const Image& image = images_[i];
    if (image.width() != first.width() || image.height() != first.height()) {
      Fail(fmt::format("{} is {}x{} but {} is {}x{}: all images of a set must have one size",
                       image_names_[i], image.width(), image.height(), image_names_.front(),
                       first.width(), first.height()));
    }
    if (image.channels() != first.channels()) {
      Fail(fmt::format("{} has {} channels but {} has {}", image_names_[i], image.channels(),
                       image_names_.front(), first.channels()));
    }
  }
}

void PhotometricSet::set_mask(Mask mask) {
  if (!mask.SameSize(images_.front())) {
    Fail(fmt::format("the mask is {}x{} but the images are {}x{}", mask.width(), mask.height(),
                     width(), height()));
  }
  if (mask.CountSet() == 0) Fail("the mask selects no pixel");
  mask_ = std::move(mask);
}

void PhotometricSet::set_near_lighting(NearLighting lighting) {
  if (lighting.lamps.size() != images_.size()) {
    Fail(fmt::format("{} near lamps for {} images", lighting.lamps.size(), images_.size()));
  }
  for (const NearLight& lamp : lighting.lamps) {
    if (!(lamp.position.z() > 0.0) || !lamp.position.allFinite()) {
      Fail("a near lamp must be above the sample plane (z > 0)");
    }
  }
  if (lighting.width != width() || lighting.first_row < 0 ||
      lighting.first_row + height() > lighting.height) {
    Fail(fmt::format("the near lamps' frame is {}x{} but the images are rows {}-{} of {} columns",
                     lighting.width, lighting.height, lighting.first_row,
                     lighting.first_row + height() - 1, width()));
  }
  near_lighting_ = std::move(lighting);
}

Mask PhotometricSet::MaskOrAll() const { return mask_ ? *mask_ : Mask(width(), height(), true); }

void PhotometricSet::set_intensities(std::vector<std::vector<float>> intensities) {
  if (intensities.size() != images_.size()) {
    Fail(fmt::format("{} light intensities for {} images", intensities.size(), images_.size()));
  }
  for (std::size_t i = 0; i < intensities.size(); ++i) {
    auto& row = intensities[i];
    if (row.size() == 1) row.assign(static_cast<std::size_t>(channels()), row.front());
    if (static_cast<int>(row.size()) != channels()) {
      Fail(fmt::format("the intensity of {} has {} values; give 1 or {} (one per channel)",
                       image_names_[i], row.size(), channels()));
    }
    for (float v : row) {
      if (!std::isfinite(v) || v <= 0.0f) {
        Fail(fmt::format("the intensity of {} is {}; intensities must be positive", image_names_[i],
                         v));
      }
    }
  }
  intensities_ = std::move(intensities);
}

void PhotometricSet::ApplyIntensities() {
  if (intensities_.empty()) return;
  for (std::size_t i = 0; i < images_.size(); ++i) {
    for (int c = 0; c < channels(); ++c) {
      const float intensity = intensities_[i][static_cast<std::size_t>(c)];
      for (float& v : images_[i].plane(c)) v /= intensity;
    }
  }
  intensities_.clear();
}

PhotometricSet PhotometricSet::Subset(std::span<const int> indices) const {
  std::vector<Image> images;
  std::vector<LightDirection> lights;
  std::vector<std::string> names;
  std::vector<std::vector<float>> intensities;
  for (int i : indices) {
    if (i < 0 || i >= size()) Fail(fmt::format("no image {} in a set of {}", i, size()));
    images.push_back(images_[i]);
    lights.push_back(lights_[i]);
    names.push_back(image_names_[i]);
    if (!intensities_.empty()) intensities.push_back(intensities_[i]);
  }
  PhotometricSet subset(std::move(images), std::move(lights), std::move(names), source_);
  subset.mask_ = mask_;
  subset.intensities_ = std::move(intensities);
  if (near_lighting_) {
    NearLighting lighting = *near_lighting_;
    lighting.lamps.clear();
    for (int i : indices) lighting.lamps.push_back(near_lighting_->lamps[i]);
    subset.near_lighting_ = std::move(lighting);
  }
  return subset;
}

void PhotometricSet::Fail(const std::string& fault) const { throw Error(source_, fault); }

}  // namespace photomat
