#pragma once

#include <optional>
#include <string>
#include <string_view>

namespace photomat {

// How stored integer samples relate to light. Photometric fitting needs linear data, so sRGB
// samples are decoded with the sRGB transfer function (IEC 61966-2-1) on read.
enum class ColourSpace { kLinear, kSrgb };

std::string_view ToString(ColourSpace space);
// Accepts "linear" and "srgb" (any case); nullopt otherwise.
std::optional<ColourSpace> ParseColourSpace(std::string_view text);

// The sRGB transfer function and its inverse on [0, 1] (values outside are clamped).
double SrgbToLinear(double encoded);
double LinearToSrgb(double linear);

}  // namespace photomat
