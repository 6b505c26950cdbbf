#pragma once

#include <filesystem>
#include <nlohmann/json.hpp>
#include <string>
#include <vector>

#include "core/image.h"
#include "core/photometric_set.h"

namespace photomat {

// A camera response curve: for each channel, the linear value of every code of an integer image
// (relative scale: the top code maps to 1). Images are given as photomat reads integer files with
// ColourSpace::kLinear, i.e. code / (levels - 1) in [0, 1]; Linearise maps them through the curve
// (linear interpolation between codes).
//
// photomat's default for 8-bit files is the sRGB curve (core/image_io.h); a camera whose JPEG or
// 8-bit engine differs is calibrated from an exposure series (RecoverResponseDebevec).
class ResponseCurve {
 public:
  // `tables[c][code]`: non-decreasing, one table per channel, all of the same length >= 2.
  // Throws Error otherwise.
  explicit ResponseCurve(std::vector<std::vector<double>> tables, std::string source = "");
  static ResponseCurve Srgb(int channels = 3, int levels = 256);
  static ResponseCurve Identity(int channels = 3, int levels = 256);

  int channels() const { return static_cast<int>(tables_.size()); }
  int levels() const { return static_cast<int>(tables_.front().size()); }
  const std::vector<double>& table(int channel) const { return tables_[channel]; }
  // How the curve was made ("srgb", "identity", "debevec ...").
  const std::string& source() const { return source_; }

  // The linear value of `encoded` (code / (levels - 1)) in `channel`.
  double ToLinear(int channel, double encoded) const;
  // Every channel of every pixel; a one-channel curve applies to all channels. Throws Error when
  // the image has another channel count.
  Image Linearise(const Image& encoded) const;

  nlohmann::json ToJson() const;
  static ResponseCurve FromJson(const nlohmann::json& json, const std::filesystem::path& file);

 private:
  std::vector<std::vector<double>> tables_;
  std::string source_;
};

// Debevec and Malik's recovery (SIGGRAPH 1997) through OpenCV's CalibrateDebevec: `exposures` are
// images of a static scene (codes / 255, 8-bit) taken with `times` (seconds, any common unit).
// `smoothness` is Debevec's lambda; `samples` the pixels sampled (on a regular grid, so the result
// is reproducible). The curve is made non-decreasing and normalised to 1 at the top code. Throws
// Error for fewer than 2 exposures, mismatched counts or sizes, or non-positive times.
ResponseCurve RecoverResponseDebevec(const std::vector<Image>& exposures,
                                     const std::vector<double>& times, double smoothness = 10.0,
                                     int samples = 70);

// JSON file {"format": "photomat-response", "version": 1, "source": ..., "channels": [[...], ...]}.
void WriteResponseCurve(const std::filesystem::path& path, const ResponseCurve& curve);
ResponseCurve ReadResponseCurve(const std::filesystem::path& path);

// Every image of `set` (read as codes, ColourSpace::kLinear) through the curve.
PhotometricSet LineariseSet(const PhotometricSet& set, const ResponseCurve& curve);

}  // namespace photomat
