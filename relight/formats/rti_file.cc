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

// The header lines (CRLF, "#HSH1.2" first, as real files) and the float scales and biases.
std::string RtiHeaderText(const RtiFile& rti) {
  if (rti.width < 1 || rti.height < 1 || !HshLightBasis::ValidTermCount(rti.terms) ||
      (rti.colours != 1 && rti.colours != 3) ||
      rti.scale.size() != static_cast<std::size_t>(rti.terms) ||
      rti.bias.size() != rti.scale.size()) {
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
  return out;
}

// One image row of the payload: the pixels first .. first + width - 1 of `planes`, each as its
// terms for each colour in turn.
void EncodeRtiRow(const RtiFile& rti, const std::vector<std::vector<std::uint8_t>>& planes,
                  std::size_t first, std::uint8_t* out) {
  for (int x = 0; x < rti.width; ++x) {
    for (int c = 0; c < rti.colours; ++c) {
      for (int j = 0; j < rti.terms; ++j) *out++ = planes[j * rti.colours + c][first + x];
    }
  }
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
  std::string out = RtiHeaderText(rti);
  if (rti.planes.size() != per_pixel) {
    throw Error("an HSH file needs planes for every term and colour");
  }
  const std::size_t width = static_cast<std::size_t>(rti.width);
  const std::size_t header = out.size();
  out.resize(header + pixels * per_pixel);
  auto* payload = reinterpret_cast<std::uint8_t*>(out.data()) + header;
  for (int file_row = 0; file_row < rti.height; ++file_row) {
    const std::size_t image_row = static_cast<std::size_t>(rti.height - 1 - file_row);
    EncodeRtiRow(rti, rti.planes, image_row * width, payload);
    payload += width * per_pixel;
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

RtiFile RtiHeaderOf(const Representation& representation) {
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
  return rti;
}

RtiTermRanges::RtiTermRanges(int terms, int colours)
    : colours_(colours), low_(terms, INFINITY), high_(terms, -INFINITY) {}

void RtiTermRanges::Add(const Representation& band) {
  const RtiFile layout = RtiHeaderOf(band);
  const int terms = static_cast<int>(low_.size());
  if (layout.terms != terms || layout.colours != colours_) {
    throw Error(fmt::format("a {} band added to the ranges of {} terms x {} colours", band.method(),
                            terms, colours_));
  }
  method_ = band.method();
  const Image& maps = band.maps();
  for (int j = 0; j < terms; ++j) {
    for (int c = 0; c < colours_; ++c) {
      for (const float value : maps.plane(j * colours_ + c)) {
        if (!std::isfinite(value)) {
          throw Error(fmt::format("{}: term {} is not finite", method_, j));
        }
        low_[j] = std::min(low_[j], value);
        high_[j] = std::max(high_[j], value);
      }
    }
  }
}

void RtiTermRanges::ChooseScalesAndBiases(RtiFile& rti) const {
  const int terms = static_cast<int>(low_.size());
  rti.scale.resize(terms);
  rti.bias.resize(terms);
  for (int j = 0; j < terms; ++j) {
    if (!std::isfinite(low_[j]) || !std::isfinite(high_[j])) {
      throw Error(fmt::format("{}: term {} is not finite", method_, j));
    }
    rti.bias[j] = low_[j];
    rti.scale[j] = high_[j] > low_[j] ? high_[j] - low_[j] : 1.0f;
  }
}

std::vector<std::vector<std::uint8_t>> QuantiseRtiPlanes(const Representation& band,
                                                         const RtiFile& rti) {
  const Image& maps = band.maps();
  const int planes = rti.terms * rti.colours;
  std::vector<std::vector<std::uint8_t>> bytes(planes,
                                               std::vector<std::uint8_t>(maps.pixel_count()));
  for (int k = 0; k < planes; ++k) {
    const int j = k / rti.colours;
    const auto values = maps.plane(k);
    for (std::size_t p = 0; p < values.size(); ++p) {
      const double unit = (values[p] - rti.bias[j]) / rti.scale[j];
      bytes[k][p] = static_cast<std::uint8_t>(std::clamp(std::lround(unit * 255.0), 0L, 255L));
    }
  }
  return bytes;
}

RtiFile RtiFromRepresentation(const Representation& representation) {
  RtiFile rti = RtiHeaderOf(representation);
  RtiTermRanges ranges(rti.terms, rti.colours);
  ranges.Add(representation);
  ranges.ChooseScalesAndBiases(rti);
  rti.planes = QuantiseRtiPlanes(representation, rti);
  return rti;
}

RtiBandWriter::RtiBandWriter(const fs::path& path, const RtiFile& header)
    : RtiBandWriter(path, header, RtiHeaderText(header)) {}

RtiBandWriter::RtiBandWriter(const fs::path& path, const RtiFile& header, const std::string& text)
    : header_{header.width, header.height,  header.colours, header.terms, header.scale, header.bias,
              {},           header.comments},
      header_bytes_(text.size()),
      file_(path, text,
            text.size() + static_cast<std::size_t>(header.width) * header.height * header.terms *
                              header.colours) {}

void RtiBandWriter::WriteNext(const std::vector<std::vector<std::uint8_t>>& planes) {
  const std::size_t width = static_cast<std::size_t>(header_.width);
  const std::size_t per_pixel = static_cast<std::size_t>(header_.terms) * header_.colours;
  if (planes.size() != per_pixel || planes.front().empty() || planes.front().size() % width != 0) {
    throw Error(file_.path(), "a band needs every term's planes, whole rows of the width");
  }
  for (const auto& plane : planes) {
    if (plane.size() != planes.front().size()) {
      throw Error(file_.path(), "the planes of a band differ in size");
    }
  }
  const int rows = static_cast<int>(planes.front().size() / width);
  if (next_row_ + rows > header_.height) {
    throw Error(file_.path(), fmt::format("rows {}..{} are past the image's {} rows", next_row_,
                                          next_row_ + rows - 1, header_.height));
  }
  // Rows bottom to top: the band is one run of the payload, its last row first.
  const std::size_t row_bytes = width * per_pixel;
  std::vector<std::uint8_t> run(row_bytes * static_cast<std::size_t>(rows));
  for (int y = 0; y < rows; ++y) {
    EncodeRtiRow(header_, planes, static_cast<std::size_t>(y) * width,
                 run.data() + static_cast<std::size_t>(rows - 1 - y) * row_bytes);
  }
  const std::size_t first_file_row = static_cast<std::size_t>(header_.height - next_row_ - rows);
  file_.Write(header_bytes_ + first_file_row * row_bytes, run);
  next_row_ += rows;
}

void RtiBandWriter::Commit() {
  if (next_row_ != header_.height) {
    throw Error(file_.path(),
                fmt::format("only {} of its {} rows were written", next_row_, header_.height));
  }
  file_.Commit();
}

}  // namespace photomat
