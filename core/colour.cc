#include "core/colour.h"

#include <algorithm>
#include <cctype>
#include <cmath>

#include "core/text_parsing.h"

namespace photomat {

std::string_view ToString(ColourSpace space) {
  return space == ColourSpace::kSrgb ? "srgb" : "linear";
}

std::optional<ColourSpace> ParseColourSpace(std::string_view text) {
  const std::string lower = ToLower(text);
  if (lower == "linear") return ColourSpace::kLinear;
  if (lower == "srgb") return ColourSpace::kSrgb;
  return std::nullopt;
}

double SrgbToLinear(double encoded) {
  const double v = std::clamp(encoded, 0.0, 1.0);
  return v <= 0.04045 ? v / 12.92 : std::pow((v + 0.055) / 1.055, 2.4);
}

double LinearToSrgb(double linear) {
  const double v = std::clamp(linear, 0.0, 1.0);
  return v <= 0.0031308 ? v * 12.92 : 1.055 * std::pow(v, 1.0 / 2.4) - 0.055;
}

}  // namespace photomat
