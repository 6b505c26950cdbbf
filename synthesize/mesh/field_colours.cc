#include "synthesize/mesh/field_colours.h"

#include <fmt/format.h>

#include <algorithm>
#include <opencv2/core.hpp>
#include <opencv2/imgproc.hpp>

#include "core/colour.h"
#include "core/error.h"

namespace photomat {

ColourMap ParseColourMap(const std::string& text) {
  if (text == "viridis") return ColourMap::kViridis;
  if (text == "inferno") return ColourMap::kInferno;
  if (text == "turbo") return ColourMap::kTurbo;
  if (text == "grey" || text == "gray") return ColourMap::kGrey;
  throw Error(
      fmt::format("unknown colour map \"{}\": expected viridis, inferno, turbo or grey", text));
}

std::vector<Eigen::Vector3f> FieldColours(const Eigen::VectorXd& field,
                                          const FieldColourOptions& options) {
  std::vector<Eigen::Vector3f> colours(field.size());
  if (field.size() == 0) return colours;
  const double low = options.low.value_or(field.minCoeff());
  const double high = options.high.value_or(field.maxCoeff());
  const double range = high > low ? high - low : 1.0;
  // The 256-entry sRGB table of the map, decoded once.
  cv::Mat ramp(1, 256, CV_8UC1);
  for (int i = 0; i < 256; ++i) ramp.at<unsigned char>(0, i) = static_cast<unsigned char>(i);
  cv::Mat table;
  switch (options.map) {
    case ColourMap::kViridis:
      cv::applyColorMap(ramp, table, cv::COLORMAP_VIRIDIS);
      break;
    case ColourMap::kInferno:
      cv::applyColorMap(ramp, table, cv::COLORMAP_INFERNO);
      break;
    case ColourMap::kTurbo:
      cv::applyColorMap(ramp, table, cv::COLORMAP_TURBO);
      break;
    case ColourMap::kGrey:
      cv::cvtColor(ramp, table, cv::COLOR_GRAY2BGR);
      break;
  }
  std::vector<Eigen::Vector3f> linear(256);
  for (int i = 0; i < 256; ++i) {
    const cv::Vec3b bgr = table.at<cv::Vec3b>(0, i);
    for (int c = 0; c < 3; ++c) linear[i][c] = static_cast<float>(SrgbToLinear(bgr[2 - c] / 255.0));
  }
  for (Eigen::Index i = 0; i < field.size(); ++i) {
    const double t = std::clamp((field[i] - low) / range, 0.0, 1.0);
    colours[i] = linear[static_cast<int>(t * 255.0 + 0.5)];
  }
  return colours;
}

}  // namespace photomat
