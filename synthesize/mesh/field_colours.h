#pragma once

#include <Eigen/Core>
#include <optional>
#include <string>
#include <vector>

namespace photomat {

// Per-vertex (or per-pixel) scalar fields shown as colours.
enum class ColourMap { kViridis, kInferno, kTurbo, kGrey };
// "viridis", "inferno", "turbo", "grey"; Error otherwise.
ColourMap ParseColourMap(const std::string& text);

struct FieldColourOptions {
  ColourMap map = ColourMap::kViridis;
  // The field values mapped to the two ends of the colour map; unset: the field's minimum and
  // maximum. Values outside are clamped.
  std::optional<double> low;
  std::optional<double> high;
};

// Linear RGB colours (OpenCV's colour maps, which are defined as 8-bit sRGB, decoded to linear).
std::vector<Eigen::Vector3f> FieldColours(const Eigen::VectorXd& field,
                                          const FieldColourOptions& options = {});

}  // namespace photomat
