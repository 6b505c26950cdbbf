#pragma once

#include <Eigen/Core>
#include <filesystem>
#include <memory>
#include <nlohmann/json.hpp>
#include <optional>
#include <string>
#include <vector>

#include "core/colour.h"
#include "core/image_band_io.h"
#include "core/image_io.h"
#include "core/light_direction.h"
#include "core/photometric_set.h"
#include "core/progress.h"

namespace photomat {

// photomat's own description of a photometric set on disk: a folder with the images and a
// `manifest.json`. Every stage that produces a set (generate, capture, calibrate) writes one and
// every stage can read one. Format (README, "Inputs"):
//
//   {
//     "format": "photomat-capture", "version": 1,
//     "colour_space": "linear" | "srgb",      optional; how integer images encode light
//     "mask": "mask.png",                     optional
//     "images": [
//       {"file": "img_000.png", "light": [x, y, z]},              vector (normalised on read)
//       {"file": "img_001.png", "slant_deg": 30, "tilt_deg": 30},  or slant/tilt in degrees
//       ... each may add "intensity": v or [r, g, b]
//       ... and "lamp": [x, y, z], all images or none: the near lamp's position in the sample
//       frame (core/near_light.h: pixels, origin at the image centre, y up), written by
//       `calibrate apply --near-lights`, whose images are divided by the lamps' fall-off
//     ],
//     "ground_truth": {"normals": "...exr", "albedo": "...exr", "height": "...exr"},  optional
//     "provenance": {...}                     optional, free-form, ignored on read
//   }
// When an image gives both a vector and slant/tilt they must agree within 0.05 degree.
struct CaptureManifestImage {
  std::string file;
  LightDirection light;
  std::vector<float> intensity;  // empty, one value, or one per channel
  // The near lamp of a capture divided by its fall-off (PhotometricSet::near_lighting).
  std::optional<Eigen::Vector3d> lamp;
};

struct CaptureManifest {
  std::vector<CaptureManifestImage> images;
  std::optional<ColourSpace> colour_space;
  std::optional<std::string> mask;
  std::optional<std::string> ground_truth_normals;
  std::optional<std::string> ground_truth_albedo;
  std::optional<std::string> ground_truth_height;
  nlohmann::json provenance;
};

inline constexpr const char* kCaptureManifestFormat = "photomat-capture";
inline constexpr const char* kCaptureManifestName = "manifest.json";

// Throws Error naming the file and the JSON path of any fault.
CaptureManifest ReadCaptureManifest(const std::filesystem::path& path);
void WriteCaptureManifest(const std::filesystem::path& path, const CaptureManifest& manifest);

struct SaveSetOptions {
  // 16-bit linear PNG by default (what lab cameras give); kFloat writes EXR.
  SampleType sample_type = SampleType::kUint16;
  // Encoding of integer images (kSrgb for 8-bit images meant for viewing); recorded in the
  // manifest's "colour_space" so that readers linearise them again.
  ColourSpace encoding = ColourSpace::kLinear;
  // File names are "<prefix>_000.png", ...
  std::string prefix = "img";
  nlohmann::json provenance;
};

// A photometric set written band by band of rows, as SavePhotometricSet writes it (which is this
// writer with one band): every image to a temporary name as its rows come (ImageBandWriter), then
// in Finish renamed into place, and the mask and manifest.json written last. A writer destroyed
// before Finish removes its temporaries: a fault part-way leaves no image and no manifest.
class CaptureBandWriter {
 public:
  // `height`: the rows of every image. Creates `folder` if needed (Error naming it otherwise);
  // a folder it created is removed again, if empty, when the writer ends without Finish.
  CaptureBandWriter(std::filesystem::path folder, int height, const SaveSetOptions& options = {});
  ~CaptureBandWriter();
  CaptureBandWriter(const CaptureBandWriter&) = delete;
  CaptureBandWriter& operator=(const CaptureBandWriter&) = delete;

  // The next rows of every image. The first band sets the images' count, width, channels,
  // lights, intensities and near lamps (its NearLighting must be the whole frame's, first_row
  // 0); later bands continue them (their near lamps' first_row where the rows continue).
  // Throws Error naming the set's source for a band that does not continue the first, and
  // naming the file for a write that fails. `progress` advances once per image.
  void WriteNext(const PhotometricSet& band, Progress* progress = nullptr);
  int rows_written() const { return rows_written_; }
  // Every row written: renames the images into place, writes the mask (the bands' rows of it)
  // and manifest.json, and returns the manifest.
  CaptureManifest Finish();

 private:
  struct Images;
  std::filesystem::path folder_;
  int height_ = 0;
  int rows_written_ = 0;
  bool created_folder_ = false;
  bool finished_ = false;
  SaveSetOptions options_;
  CaptureManifest manifest_;
  std::optional<Mask> mask_;
  std::unique_ptr<Images> images_;
};

// Writes the images of `set` (named img_000.png, ...; negative values clamp to 0 in integer
// files), its mask, its near lamps, and manifest.json into `folder` (created if needed). Returns
// the manifest.
// Reports each image to `progress` when given.
CaptureManifest SavePhotometricSet(const std::filesystem::path& folder, const PhotometricSet& set,
                                   const SaveSetOptions& options = {},
                                   Progress* progress = nullptr);

}  // namespace photomat
