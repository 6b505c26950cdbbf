#include "relight/formats/rti_file.h"

#include <fmt/format.h>

#include <algorithm>
#include <bit>
#include <cmath>
#include <cstring>

#include "core/atomic_file.h"
#include "core/error.h"
#include "relight/formats/header_reader.h"
#include "represent/model/hsh.h"

namespace photomat {
namespace {

namespace fs = std::filesystem;

constexpr long long kMaxSide = 1 << 16;
constexpr long long kMaxPixels = 1LL << 28;
constexpr int kHshType = 3;
constexpr int kSeparateColourBasis = 2;  // RTIBuilder's "basis type": one basis per colour

std::size_t FileRowToImageIndex(const RtiFile& rti, std::size_t file_pixel) {
  const auto w = static_cast<std::size_t>(rti.width);
  return (static_cast<std::size_t>(rti.height) - 1 - file_pixel / w) * w + file_pixel % w;
}

}  // namespace

RtiFile ParseRti(std::span<const std::uint8_t> data, const fs::path& file) {
  HeaderReader reader(data, file);
  RtiFile rti;
  if (!reader.NextLineStartsWith("#")) {
    reader.Fail("not an RTI file (it does not start with a '#' line such as #HSH1.2)");
  }
  while (reader.NextLineStartsWith("#")) {
    rti.comments.emplace_back(reader.Line("a comment").substr(1));
    if (rti.comments.size() > 1000) reader.FailAtLine("more than 1000 comment lines");
  }
  const long long type = reader.Integers(1, "the RTI type")[0];
  if (type != kHshType) {
    reader.FailAtLine(
        fmt::format("RTI type {} is not supported (photomat reads type 3, "
                    "hemispherical harmonics)",
                    type));
  }
  const auto size = reader.Integers(3, "width, height and colour count");
  if (size[0] < 1 || size[1] < 1 || size[0] > kMaxSide || size[1] > kMaxSide ||
      size[0] * size[1] > kMaxPixels) {
    reader.FailAtLine(fmt::format("implausible size {} x {}", size[0], size[1]));
  }
  if (size[2] != 1 && size[2] != 3) {
    reader.FailAtLine(fmt::format("{} colours: photomat reads 1 or 3", size[2]));
  }
  const auto basis = reader.Integers(3, "terms, basis type and element size");
  if (!HshLightBasis::ValidTermCount(static_cast<int>(basis[0]))) {
    reader.FailAtLine(fmt::format("{} terms: hemispherical harmonics have 4, 9 or 16", basis[0]));
  }
  if (basis[1] != kSeparateColourBasis) {
    reader.FailAtLine(
        fmt::format("basis type {} is not supported (photomat reads type 2, one "
                    "basis per colour)",
                    basis[1]));
  }
  if (basis[2] != 1) {
    reader.FailAtLine(
        fmt::format("element size {} is not supported (photomat reads 1-byte "
                    "coefficients)",
                    basis[2]));
  }
  rti.width = static_cast<int>(size[0]);
  rti.height = static_cast<int>(size[1]);
  rti.colours = static_cast<int>(size[2]);
  rti.terms = static_cast<int>(basis[0]);
  rti.scale = reader.BinaryFloats(rti.terms, "the scales");
  rti.bias = reader.BinaryFloats(rti.terms, "the biases");
  const std::size_t pixels = static_cast<std::size_t>(rti.width) * rti.height;
  const std::size_t per_pixel = static_cast<std::size_t>(rti.terms) * rti.colours;
  const auto bytes = reader.Bytes(pixels * per_pixel, "the coefficients");
  rti.planes.assign(per_pixel, std::vector<std::uint8_t>(pixels));
  for (std::size_t p = 0; p < pixels; ++p) {
    const std::size_t target = FileRowToImageIndex(rti, p);
    const std::uint8_t* in = bytes.data() + p * per_pixel;
    for (int c = 0; c < rti.colours; ++c) {
      for (int j = 0; j < rti.terms; ++j) rti.planes[j * rti.colours + c][target] = *in++;
    }
  }
  return rti;
}

RtiFile ReadRtiFile(const fs::path& path) {
  const std::string contents = ReadTextFile(path);
  return ParseRti({reinterpret_cast<const std::uint8_t*>(contents.data()), contents.size()}, path);
}

std::string SerializeRti(const RtiFile& rti) {
  const std::size_t pixels = static_cast<std::size_t>(rti.width) * rti.height;
  const std::size_t per_pixel = static_cast<std::size_t>(rti.terms) * rti.colours;
  if (rti.width < 1 || rti.height < 1 || !HshLightBasis::ValidTermCount(rti.terms) ||
      (rti.colours != 1 && rti.colours != 3) ||
      rti.scale.size() != static_cast<std::size_t>(rti.terms) ||
      rti.bias.size() != rti.scale.size() || rti.planes.size() != per_pixel) {
    throw Error(
        "an HSH file needs a size, 4/9/16 terms, 1 or 3 colours, and a scale, a bias and "
        "planes for every term");
  }
  std::string out = "#HSH1.2\r\n";
  for (const std::string& comment : rti.comments) {
    if (comment.find_first_of("\r\n") != std::string::npos) {
      throw Error("RTI comments are single lines");
    }
    out += "#" + comment + "\r\n";
  }
  out += fmt::format("{}\r\n{} {} {}\r\n{} {} 1\r\n", kHshType, rti.width, rti.height, rti.colours,
                     rti.terms, kSeparateColourBasis);
  static_assert(std::endian::native == std::endian::little, "float payloads are little-endian");
  for (const auto* values : {&rti.scale, &rti.bias}) {
    out.append(reinterpret_cast<const char*>(values->data()), values->size() * sizeof(float));
  }
  const std::size_t header = out.size();
  out.resize(header + pixels * per_pixel);
  auto* payload = reinterpret_cast<std::uint8_t*>(out.data()) + header;
  for (std::size_t p = 0; p < pixels; ++p) {
    const std::size_t source = FileRowToImageIndex(rti, p);
    for (int c = 0; c < rti.colours; ++c) {
      for (int j = 0; j < rti.terms; ++j) *payload++ = rti.planes[j * rti.colours + c][source];
    }
  }
  return out;
}

void WriteRtiFile(const fs::path& path, const RtiFile& rti) {
  WriteSerializedAtomically(path, [&] { return SerializeRti(rti); });
}

Representation RepresentationFromRti(const RtiFile& rti) {
  std::vector<std::string> names;
  const auto channels = OutputChannelNames(rti.colours);
  for (int j = 0; j < rti.terms; ++j) {
    for (const auto& c : channels) names.push_back(fmt::format("hsh.h{}.{}", j, c));
  }
  Image maps(rti.width, rti.height, names);
  const int planes = rti.terms * rti.colours;
  for (std::size_t p = 0; p < maps.pixel_count(); ++p) {
    const auto out = maps.pixel(p);
    for (int k = 0; k < planes; ++k) out[k] = static_cast<float>(rti.Coefficient(k, p));
  }
  nlohmann::json details = {{"rti_file", {{"comments", rti.comments}}}};
  return Representation(fmt::format("hsh{}", rti.terms), std::move(maps),
                        {rti.terms, true, false, rti.colours},
                        std::make_shared<HshLightBasis>(rti.terms), std::move(details));
}

RtiFile RtiFromRepresentation(const Representation& representation) {
  const MapLayout& layout = representation.layout();
  if (representation.shading()) {
    throw Error(
        fmt::format("a {} representation is a nonlinear {} shading that an .rti file's "
                    "harmonics cannot hold: export its maps with `photomat export` "
                    "(glTF tile, PNG/EXR maps) instead",
                    representation.method(), representation.shading()->kind()));
  }
  if (representation.basis().kind() != "hsh" || !layout.basis_per_channel || layout.has_gain ||
      (layout.output_channels != 1 && layout.output_channels != 3)) {
    throw Error(fmt::format("a {} representation cannot be stored as an HSH .rti file as it is",
                            representation.method()));
  }
  RtiFile rti;
  rti.width = representation.width();
  rti.height = representation.height();
  rti.colours = layout.output_channels;
  rti.terms = layout.basis_size;
  const Image& maps = representation.maps();
  const std::size_t pixels = maps.pixel_count();
  rti.scale.resize(rti.terms);
  rti.bias.resize(rti.terms);
  for (int j = 0; j < rti.terms; ++j) {
    float low = INFINITY, high = -INFINITY;
    for (std::size_t p = 0; p < pixels; ++p) {
      for (int c = 0; c < rti.colours; ++c) {
        const float value = maps.pixel(p)[j * rti.colours + c];
        if (!std::isfinite(value)) {
          throw Error(fmt::format("{}: term {} is not finite", representation.method(), j));
        }
        low = std::min(low, value);
        high = std::max(high, value);
      }
    }
    if (!std::isfinite(low) || !std::isfinite(high)) {
      throw Error(fmt::format("{}: term {} is not finite", representation.method(), j));
    }
    rti.bias[j] = low;
    rti.scale[j] = high > low ? high - low : 1.0f;
  }
  rti.planes.assign(static_cast<std::size_t>(rti.terms) * rti.colours,
                    std::vector<std::uint8_t>(pixels));
  for (std::size_t p = 0; p < pixels; ++p) {
    for (int k = 0; k < rti.terms * rti.colours; ++k) {
      const int j = k / rti.colours;
      const double unit = (maps.pixel(p)[k] - rti.bias[j]) / rti.scale[j];
      rti.planes[k][p] = static_cast<std::uint8_t>(std::clamp(std::lround(unit * 255.0), 0L, 255L));
    }
  }
  return rti;
}

}  // namespace photomat
