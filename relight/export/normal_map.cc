#include "relight/export/normal_map.h"

#include <fmt/format.h>

#include <array>
#include <cmath>

#include "core/enum_names.h"
#include "core/error.h"

namespace photomat {

namespace {

constexpr std::array<NamedValue<NormalConvention>, 2> kConventionNames = {
    {{NormalConvention::kOpenGl, "opengl"}, {NormalConvention::kDirectX, "directx"}}};

}  // namespace

std::string_view ToString(NormalConvention convention) {
  return NameOf(convention, kConventionNames);
}

NormalConvention ParseNormalConvention(std::string_view name) {
  return ValueNamed(name, kConventionNames, "normal-map convention");
}

Image EncodeNormalMap(const Image& normals, NormalConvention convention) {
  if (normals.channels() < 3) throw Error("a normal map needs 3 channels (x, y, z)");
  const float flip = convention == NormalConvention::kDirectX ? -1.0f : 1.0f;
  Image encoded(normals.width(), normals.height(), std::vector<std::string>{"R", "G", "B"});
  for (std::size_t p = 0; p < normals.pixel_count(); ++p) {
    const auto n = normals.pixel(p);
    const bool none = n[0] == 0.0f && n[1] == 0.0f && n[2] == 0.0f;
    const float x = none ? 0.0f : n[0], y = none ? 0.0f : n[1] * flip, z = none ? 1.0f : n[2];
    const auto out = encoded.pixel(p);
    out[0] = 0.5f * (x + 1.0f);
    out[1] = 0.5f * (y + 1.0f);
    out[2] = 0.5f * (z + 1.0f);
  }
  return encoded;
}

Image DecodeNormalMap(const Image& encoded, NormalConvention convention) {
  if (encoded.channels() < 3) throw Error("a normal map needs 3 channels (R, G, B)");
  const double flip = convention == NormalConvention::kDirectX ? -1.0 : 1.0;
  Image normals(encoded.width(), encoded.height(),
                std::vector<std::string>{"normal.X", "normal.Y", "normal.Z"});
  for (std::size_t p = 0; p < encoded.pixel_count(); ++p) {
    const auto in = encoded.pixel(p);
    double x = 2.0 * in[0] - 1.0, y = (2.0 * in[1] - 1.0) * flip, z = 2.0 * in[2] - 1.0;
    const double norm = std::sqrt(x * x + y * y + z * z);
    if (norm > 0.0) x /= norm, y /= norm, z /= norm;
    const auto out = normals.pixel(p);
    out[0] = static_cast<float>(x);
    out[1] = static_cast<float>(y);
    out[2] = static_cast<float>(z);
  }
  return normals;
}

}  // namespace photomat
