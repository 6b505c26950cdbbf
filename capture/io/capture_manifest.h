#pragma once

#include <Eigen/Core>
#include <filesystem>
#include <nlohmann/json.hpp>
#include <optional>
#include <string>
#include <vector>

#include "core/colour.h"
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

// Writes the images of `set` (named img_000.png, ...; negative values clamp to 0 in integer
// files), its mask, its near lamps, and manifest.json into `folder` (created if needed). Returns
// the manifest.
// Reports each image to `progress` when given.
CaptureManifest SavePhotometricSet(const std::filesystem::path& folder, const PhotometricSet& set,
                                   const SaveSetOptions& options = {},
                                   Progress* progress = nullptr);

}  // namespace photomat
