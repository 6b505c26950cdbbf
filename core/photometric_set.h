#pragma once

#include <filesystem>
#include <optional>
#include <span>
#include <string>
#include <vector>

#include "core/image.h"
#include "core/light_direction.h"
#include "core/near_light.h"

namespace photomat {

// N registered images of one sample under N known distant lights: linear float data, one light
// direction per image, optional per-channel light intensities and an optional mask. This is what
// capture and calibrate produce and what represent fits.
//
// Invariants (checked on construction and by every setter, violations throw Error naming source()):
// at least one image; all images share width, height and channel count; one light per image;
// intensities are finite and positive; the mask has the images' size.
class PhotometricSet {
 public:
  // `image_names` are the files the images came from (for messages and manifests); empty means
  // "image 0", "image 1", ... `source` is the light file, manifest or folder the set was read from.
  PhotometricSet(std::vector<Image> images, std::vector<LightDirection> lights,
                 std::vector<std::string> image_names = {}, std::filesystem::path source = {});

  int size() const { return static_cast<int>(images_.size()); }
  int width() const { return images_.front().width(); }
  int height() const { return images_.front().height(); }
  int channels() const { return images_.front().channels(); }

  const Image& image(int i) const { return images_[i]; }
  const std::vector<Image>& images() const { return images_; }
  const LightDirection& light(int i) const { return lights_[i]; }
  const std::vector<LightDirection>& lights() const { return lights_; }
  const std::string& image_name(int i) const { return image_names_[i]; }
  const std::vector<std::string>& image_names() const { return image_names_; }
  const std::filesystem::path& source() const { return source_; }

  const std::optional<Mask>& mask() const { return mask_; }
  void set_mask(Mask mask);
  // The mask, or an all-set mask when there is none.
  Mask MaskOrAll() const;

  // Relative intensity of each image's light, one value per channel; empty means all 1.
  const std::vector<std::vector<float>>& intensities() const { return intensities_; }
  // One row per image, each with one value (grey light) or one per channel.
  void set_intensities(std::vector<std::vector<float>> intensities);
  // Divides every channel of every image by its light's intensity, then resets the intensities to
  // 1: afterwards the images are what equal lights would have given.
  void ApplyIntensities();

  // The near lamps of a capture that `calibrate apply --near-lights` divided by their fall-off
  // (core/near_light.h; read from its manifest): the pbr fit uses them per pixel. Absent: the
  // lights are distant (or their nearness unknown).
  const std::optional<NearLighting>& near_lighting() const { return near_lighting_; }
  // Throws Error naming source() unless there is one lamp per image, each above the sample plane,
  // and this set's rows lie inside the lamps' frame.
  void set_near_lighting(NearLighting lighting);

  // The images at `indices`, in that order (lights, names, intensities, near lamps follow; mask
  // kept).
  PhotometricSet Subset(std::span<const int> indices) const;

  // Error about this set, attributed to its source (or to nothing for an in-memory set).
  [[noreturn]] void Fail(const std::string& fault) const;

 private:
  std::vector<Image> images_;
  std::vector<LightDirection> lights_;
  std::vector<std::string> image_names_;
  std::filesystem::path source_;
  std::optional<Mask> mask_;
  std::vector<std::vector<float>> intensities_;
  std::optional<NearLighting> near_lighting_;
};

}  // namespace photomat
