#pragma once

#include <string_view>

#include "core/image.h"

namespace photomat {

// Tangent-space normal maps for graphics tools. A flat sample seen from the camera is its own
// tangent frame: tangent = image right (+x), bitangent = image up (+y), normal = toward the camera
// (+z), so photomat's normals are already tangent-space normals.
enum class NormalConvention {
  kOpenGl,   // +Y up (glTF, Blender, Unity): green = (ny + 1) / 2
  kDirectX,  // +Y down (Unreal, 3ds Max): green = (1 - ny) / 2
};
std::string_view ToString(NormalConvention convention);  // "opengl", "directx"
// "opengl" or "directx"; throws Error otherwise.
NormalConvention ParseNormalConvention(std::string_view name);

// Unit normals (channels 0..2) to RGB in [0, 1]: (n + 1) / 2 per component, Y flipped for
// DirectX. Pixels without a normal (all zero: outside the fit's mask) become the flat normal
// (0, 0, 1). Store as 16-bit linear PNG (the encoding is not a colour): the 1/65535 steps keep
// every normal within 0.003 degree.
Image EncodeNormalMap(const Image& normals, NormalConvention convention);

// The inverse: RGB in [0, 1] back to unit normals "normal.X/Y/Z".
Image DecodeNormalMap(const Image& encoded, NormalConvention convention);

}  // namespace photomat
