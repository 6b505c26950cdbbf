#include "relight/formats/ptm_file.h"

#include <fmt/format.h>

#include <algorithm>
#include <cmath>
#include <numeric>

#include "core/atomic_file.h"
#include "core/error.h"
#include "relight/formats/header_reader.h"

namespace photomat {
namespace {

namespace fs = std::filesystem;

// Larger PTMs than this are not plausible (and would be 4 GB of coefficients).
constexpr long long kMaxSide = 1 << 16;
constexpr long long kMaxPixels = 1LL << 28;

struct FormatName {
  PtmFormat format;
  std::string_view name;
};
constexpr std::array<FormatName, 5> kFormats = {{
    {PtmFormat::kRgb, "PTM_FORMAT_RGB"},
    {PtmFormat::kLum, "PTM_FORMAT_LUM"},
    {PtmFormat::kLrgb, "PTM_FORMAT_LRGB"},
    {PtmFormat::kJpegRgb, "PTM_FORMAT_JPEG_RGB"},
    {PtmFormat::kJpegLrgb, "PTM_FORMAT_JPEG_LRGB"},
}};

bool IsJpeg(PtmFormat format) {
  return format == PtmFormat::kJpegRgb || format == PtmFormat::kJpegLrgb;
}

int PlaneCountOf(PtmFormat format) {
  switch (format) {
    case PtmFormat::kRgb:
    case PtmFormat::kJpegRgb:
      return 18;
    case PtmFormat::kLum:
      return 6;
    case PtmFormat::kLrgb:
    case PtmFormat::kJpegLrgb:
      break;
  }
  return 9;
}

// Index of the quantisation parameters (scale, bias) that plane `plane` uses; -1 for LRGB's
// verbatim colour bytes.
int CoefficientOf(PtmFormat format, int plane) {
  switch (format) {
    case PtmFormat::kRgb:
    case PtmFormat::kJpegRgb:
      return plane / 3;
    case PtmFormat::kLum:
      return plane;
    case PtmFormat::kLrgb:
    case PtmFormat::kJpegLrgb:
      break;
  }
  return plane < 6 ? plane : -1;
}

PtmFormat ParseFormat(HeaderReader& reader) {
  const std::string_view line = reader.Line("the PTM format");
  for (const auto& [format, name] : kFormats) {
    if (line == name) return format;
  }
  for (std::string_view known : {"PTM_FORMAT_PTM_LUT", "PTM_FORMAT_PTM_C_LUT",
                                 "PTM_FORMAT_JPEGLS_RGB", "PTM_FORMAT_JPEGLS_LRGB"}) {
    if (line == known) {
      reader.FailAtLine(
          fmt::format("{} is not supported (photomat reads PTM_FORMAT_RGB, _LUM, "
                      "_LRGB, _JPEG_RGB and _JPEG_LRGB)",
                      known));
    }
  }
  reader.FailAtLine(fmt::format("unknown PTM format \"{}\"", line.substr(0, 60)));
}

// Row `file_row` of the file (bottom to top) is image row height - 1 - file_row.
std::size_t ImageIndexOfFileByte(const PtmFile& ptm, std::size_t file_pixel) {
  const std::size_t w = static_cast<std::size_t>(ptm.width);
  const std::size_t file_row = file_pixel / w;
  return (static_cast<std::size_t>(ptm.height) - 1 - file_row) * w + file_pixel % w;
}

// Raw payloads: RGB = three blocks (R, G, B) of 6 bytes per pixel; LUM = one block; LRGB 1.2 =
// 6 bytes per pixel then 3 per pixel; LRGB before 1.2 = 9 interleaved bytes per pixel.
void ReadRawPlanes(HeaderReader& reader, PtmFile& ptm) {
  const std::size_t pixels = static_cast<std::size_t>(ptm.width) * ptm.height;
  const auto interleaved = [&](int first_plane, int count, std::string_view what) {
    const auto bytes = reader.Bytes(pixels * count, what);
    for (std::size_t p = 0; p < pixels; ++p) {
      const std::size_t target = ImageIndexOfFileByte(ptm, p);
      for (int k = 0; k < count; ++k) ptm.planes[first_plane + k][target] = bytes[p * count + k];
    }
  };
  const auto block = [&](int channel, std::string_view what) {
    const auto bytes = reader.Bytes(pixels * 6, what);
    for (std::size_t p = 0; p < pixels; ++p) {
      const std::size_t target = ImageIndexOfFileByte(ptm, p);
      for (int j = 0; j < 6; ++j) ptm.planes[j * 3 + channel][target] = bytes[p * 6 + j];
    }
  };
  switch (ptm.format) {
    case PtmFormat::kRgb:
      block(0, "the red coefficients");
      block(1, "the green coefficients");
      block(2, "the blue coefficients");
      return;
    case PtmFormat::kLum:
      interleaved(0, 6, "the coefficients");
      return;
    case PtmFormat::kLrgb:
      if (ptm.version == "PTM_1.2") {
        interleaved(0, 6, "the luminance coefficients");
        interleaved(6, 3, "the RGB bytes");
      } else {
        interleaved(0, 9, "the interleaved coefficients and RGB bytes");
      }
      return;
    case PtmFormat::kJpegRgb:
    case PtmFormat::kJpegLrgb:
      break;
  }
}

// The JPEG variants (a real HP sample; RTIViewer, Perathoner's ptmlib, relight's legacy reader):
// after the biases, the compression parameter (the JPEG quality), then N integers each for the
// transforms, the motion vectors (N x, then N y), the decoding order, the reference planes, the
// stream sizes and the side-information sizes (N = 18 for RGB, 9 for LRGB, planes numbered as in
// the file: JpegStreamPlane); then plane 0's stream and side information, plane 1's, ... The
// prediction and its checks: relight/formats/ptm_jpeg.h. Planes are stored in the file's row order
// (bottom to top), like raw ones.
void ReadJpegPlanes(HeaderReader& reader, PtmFile& ptm) {
  const std::size_t n = static_cast<std::size_t>(ptm.PlaneCount());
  // The quality is informational: decoding does not need it, so any integer is accepted.
  ptm.jpeg.quality = static_cast<int>(
      std::clamp(reader.Integers(1, "the JPEG quality")[0], -1000000LL, 1000000LL));
  const auto transforms = reader.Integers(n, "the plane transforms");
  // As two lines of N (RTIViewer, ptmlib) or one line of 2 N: all x, then all y.
  const auto motion = reader.Integers(2 * n, "the motion vectors");
  const auto order = reader.Integers(n, "the plane decoding order");
  const auto reference = reader.Integers(n, "the reference planes");
  const auto sizes = reader.Integers(n, "the compressed plane sizes");
  const auto side = reader.Integers(n, "the side-information sizes");
  const auto small = [](long long v) {
    return static_cast<int>(std::clamp(v, -(1LL << 30), 1LL << 30));
  };
  ptm.jpeg.planes.assign(n, {});
  for (std::size_t s = 0; s < n; ++s) {
    if (transforms[s] < 0 || transforms[s] > 3) {
      reader.Fail(
          fmt::format("JPEG plane {}: unknown transform {} (0 none, 1 inverted reference, "
                      "2 motion compensation, 3 both)",
                      s, transforms[s]));
    }
    if (sizes[s] < 0 || side[s] < 0 || side[s] % 5 != 0) {
      reader.Fail(fmt::format("JPEG plane {}: invalid sizes {} and {}", s, sizes[s], side[s]));
    }
    PtmPlaneCoding& plane = ptm.jpeg.planes[s];
    plane.inverted = (transforms[s] & 1) != 0;
    plane.motion_compensated = (transforms[s] & 2) != 0;
    plane.motion_x = small(motion[s]);
    plane.motion_y = small(motion[n + s]);
    plane.order = small(order[s]);
    plane.reference = small(reference[s]);
  }
  CheckPtmJpegCoding(ptm.jpeg, static_cast<int>(n), ptm.width, ptm.height, reader.file());
  // Locate every plane's stream and side information before decoding any.
  std::vector<PtmJpegStream> streams(n);
  for (std::size_t s = 0; s < n; ++s) {
    streams[s].jpeg =
        reader.Bytes(static_cast<std::size_t>(sizes[s]), fmt::format("JPEG plane {}", s));
    streams[s].side_information = reader.Bytes(
        static_cast<std::size_t>(side[s]), fmt::format("the side information of JPEG plane {}", s));
  }
  const std::vector<PlaneBytes> stored =
      DecodePtmJpegPlanes(ptm.jpeg, streams, ptm.width, ptm.height, reader.file());
  const std::size_t pixels = static_cast<std::size_t>(ptm.width) * ptm.height;
  for (std::size_t s = 0; s < n; ++s) {
    auto& plane = ptm.planes[JpegStreamPlane(ptm.format, static_cast<int>(s))];
    for (std::size_t p = 0; p < pixels; ++p) plane[ImageIndexOfFileByte(ptm, p)] = stored[s][p];
  }
}

// The header fields and streams of a JPEG variant (the layout ReadJpegPlanes reads).
void AppendJpegPlanes(const PtmFile& ptm, std::string& out) {
  const int n = ptm.PlaneCount();
  const PtmJpegCoding coding =
      ptm.jpeg.planes.empty() ? PtmJpegCoding::Unpredicted(n, ptm.jpeg.quality) : ptm.jpeg;
  const std::size_t pixels = static_cast<std::size_t>(ptm.width) * ptm.height;
  std::vector<PlaneBytes> stored(n, PlaneBytes(pixels));
  for (int s = 0; s < n; ++s) {
    const auto& plane = ptm.planes[JpegStreamPlane(ptm.format, s)];
    for (std::size_t p = 0; p < pixels; ++p) stored[s][p] = plane[ImageIndexOfFileByte(ptm, p)];
  }
  const std::vector<EncodedPtmPlane> encoded =
      EncodePtmJpegPlanes(coding, stored, ptm.width, ptm.height);
  const auto line = [&](const auto& value_of) {
    for (int s = 0; s < n; ++s) out += fmt::format("{}{}", s ? " " : "", value_of(s));
    out += " \n";
  };
  out += fmt::format("{} \n", coding.quality);
  line([&](int s) { return coding.planes[s].Transform(); });
  line([&](int s) { return coding.planes[s].motion_x; });
  line([&](int s) { return coding.planes[s].motion_y; });
  line([&](int s) { return coding.planes[s].order; });
  line([&](int s) { return coding.planes[s].reference; });
  line([&](int s) { return encoded[s].jpeg.size(); });
  line([&](int s) { return encoded[s].side_information.size(); });
  for (const EncodedPtmPlane& plane : encoded) out += plane.jpeg + plane.side_information;
}

// The raw payload (README "Interchange formats"): blocks one after another, each holding every
// pixel (rows bottom to top) with `count` bytes per pixel, the planes first_plane + k stride.
// RGB: the R, G and B blocks of 6 coefficients; LUM: one block; LRGB (1.2): 6 luminance
// coefficients, then the 3 colour bytes.
struct PayloadBlock {
  int first_plane;
  int count;
  int stride;
};

std::vector<PayloadBlock> PayloadBlocks(PtmFormat format) {
  switch (format) {
    case PtmFormat::kRgb:
      return {{0, 6, 3}, {1, 6, 3}, {2, 6, 3}};
    case PtmFormat::kLum:
      return {{0, 6, 1}};
    default:
      return {{0, 6, 1}, {6, 3, 1}};
  }
}

// One image row of `block`: the pixels first .. first + width - 1 of `planes`, `count` bytes each.
void EncodeBlockRow(const std::vector<std::vector<std::uint8_t>>& planes, std::size_t first,
                    int width, const PayloadBlock& block, std::uint8_t* out) {
  for (int x = 0; x < width; ++x) {
    for (int k = 0; k < block.count; ++k) {
      *out++ = planes[block.first_plane + k * block.stride][first + x];
    }
  }
}

// The header of a PTM_1.2 file, in the layout of real files: one item per line, a space before
// each newline after numbers.
std::string PtmHeaderText(const PtmFile& ptm) {
  std::string out =
      fmt::format("PTM_1.2\n{}\n{}\n{}\n", ToString(ptm.format), ptm.width, ptm.height);
  for (double s : ptm.scale) out += fmt::format("{:.6f} ", s);
  out += "\n";
  for (int b : ptm.bias) out += fmt::format("{} ", b);
  out += "\n";
  return out;
}

}  // namespace

std::string_view ToString(PtmFormat format) {
  for (const auto& [f, name] : kFormats) {
    if (f == format) return name;
  }
  return "PTM_FORMAT_RGB";
}

int PtmFile::PlaneCount() const { return PlaneCountOf(format); }

int JpegStreamPlane(PtmFormat format, int stream) {
  // RGB streams run channel by channel, as the raw layout's R, G and B blocks (ptmlib and
  // RTIViewer's plugin for Cinema 4D read red at 0, green at 6, blue at 12).
  if (format == PtmFormat::kRgb || format == PtmFormat::kJpegRgb) {
    return (stream % 6) * 3 + stream / 6;
  }
  return stream;
}

double PtmFile::Coefficient(int plane, std::size_t pixel) const {
  const int j = CoefficientOf(format, plane);
  const double byte = planes[plane][pixel];
  return j < 0 ? byte : (byte - bias[j]) * scale[j];
}

PtmFile ParsePtm(std::span<const std::uint8_t> data, const fs::path& file) {
  HeaderReader reader(data, file);
  PtmFile ptm;
  if (!reader.NextLineStartsWith("PTM_1.")) {
    reader.Fail("not a PTM file (it does not start with PTM_1.x)");
  }
  ptm.version = std::string(reader.Line("the PTM version"));
  if (ptm.version != "PTM_1.0" && ptm.version != "PTM_1.1" && ptm.version != "PTM_1.2") {
    reader.FailAtLine(fmt::format("unknown PTM version \"{}\"", ptm.version.substr(0, 40)));
  }
  ptm.format = ParseFormat(reader);
  const auto size = reader.Integers(2, "the width and height");
  if (size[0] < 1 || size[1] < 1 || size[0] > kMaxSide || size[1] > kMaxSide ||
      size[0] * size[1] > kMaxPixels) {
    reader.FailAtLine(fmt::format("implausible size {} x {}", size[0], size[1]));
  }
  ptm.width = static_cast<int>(size[0]);
  ptm.height = static_cast<int>(size[1]);
  const auto scale = reader.Reals(6, "the 6 scale values");
  const auto bias = reader.Integers(6, "the 6 bias values");
  for (int j = 0; j < 6; ++j) {
    if (scale[j] == 0.0 || std::abs(scale[j]) > 1e6 || std::abs(bias[j]) > 1000000) {
      reader.Fail(
          fmt::format("implausible scale {} or bias {} of coefficient a{}", scale[j], bias[j], j));
    }
    ptm.scale[j] = scale[j];
    ptm.bias[j] = static_cast<int>(bias[j]);
  }
  const std::size_t pixels = static_cast<std::size_t>(ptm.width) * ptm.height;
  if (!IsJpeg(ptm.format)) {
    // Check the size before allocating anything, so a header claiming a huge image fails fast.
    const std::size_t needed = pixels * static_cast<std::size_t>(ptm.PlaneCount());
    if (needed > reader.remaining()) {
      reader.Fail(fmt::format("truncated: a {} x {} {} needs {} bytes of coefficients, {} remain",
                              ptm.width, ptm.height, ToString(ptm.format), needed,
                              reader.remaining()));
    }
  }
  ptm.planes.assign(ptm.PlaneCount(), std::vector<std::uint8_t>(pixels));
  if (IsJpeg(ptm.format)) {
    ReadJpegPlanes(reader, ptm);
  } else {
    ReadRawPlanes(reader, ptm);
  }
  return ptm;
}

PtmFile ReadPtmFile(const fs::path& path) {
  const std::string contents = ReadTextFile(path);
  return ParsePtm({reinterpret_cast<const std::uint8_t*>(contents.data()), contents.size()}, path);
}

std::string SerializePtm(const PtmFile& ptm) {
  const std::size_t pixels = static_cast<std::size_t>(ptm.width) * ptm.height;
  if (ptm.width < 1 || ptm.height < 1 || static_cast<int>(ptm.planes.size()) != ptm.PlaneCount()) {
    throw Error("a PTM needs a size and one plane per coefficient");
  }
  for (const auto& plane : ptm.planes) {
    if (plane.size() != pixels) throw Error("PTM planes differ from the image size");
  }
  std::string out = PtmHeaderText(ptm);
  if (IsJpeg(ptm.format)) {
    AppendJpegPlanes(ptm, out);
    return out;
  }
  const std::size_t width = static_cast<std::size_t>(ptm.width);
  const std::size_t header = out.size();
  out.resize(header + pixels * static_cast<std::size_t>(ptm.PlaneCount()));
  auto* payload = reinterpret_cast<std::uint8_t*>(out.data()) + header;
  for (const PayloadBlock& block : PayloadBlocks(ptm.format)) {
    for (int file_row = 0; file_row < ptm.height; ++file_row) {
      const std::size_t image_row = static_cast<std::size_t>(ptm.height - 1 - file_row);
      EncodeBlockRow(ptm.planes, image_row * width, ptm.width, block, payload);
      payload += width * static_cast<std::size_t>(block.count);
    }
  }
  return out;
}

void WritePtmFile(const fs::path& path, const PtmFile& ptm) {
  WriteSerializedAtomically(path, [&] { return SerializePtm(ptm); });
}

Representation RepresentationFromPtm(const PtmFile& ptm) {
  const std::size_t pixels = static_cast<std::size_t>(ptm.width) * ptm.height;
  const bool lrgb = ptm.format == PtmFormat::kLrgb || ptm.format == PtmFormat::kJpegLrgb;
  const int channels = ptm.format == PtmFormat::kLum ? 1 : 3;
  std::vector<std::string> names;
  if (lrgb) {
    for (int j = 0; j < 6; ++j) names.push_back(fmt::format("ptm.a{}", j));
    for (const auto& c : OutputChannelNames(3)) names.push_back("rgb." + c);
  } else {
    for (int j = 0; j < 6; ++j) {
      for (const auto& c : OutputChannelNames(channels))
        names.push_back(fmt::format("ptm.a{}.{}", j, c));
    }
  }
  Image maps(ptm.width, ptm.height, names);
  for (std::size_t p = 0; p < pixels; ++p) {
    const auto out = maps.pixel(p);
    for (int plane = 0; plane < ptm.PlaneCount(); ++plane) {
      out[plane] = static_cast<float>(ptm.Coefficient(plane, p) / 255.0);
    }
  }
  const MapLayout layout =
      lrgb ? MapLayout{6, false, true, 3} : MapLayout{6, true, false, channels};
  return Representation(
      lrgb ? "ptm-lrgb" : "ptm", std::move(maps), layout, std::make_shared<PtmLightBasis>(),
      {{"ptm_file", {{"version", ptm.version}, {"format", ToString(ptm.format)}}}});
}

namespace {

// Per-coefficient quantisation (README "Interchange formats"): scale >= (max - min) / 254 rounded
// up to the 6 decimals the header holds, integer bias = ceil(-min / scale).
void ChooseQuantisation(double low, double high, double& scale, int& bias) {
  const double range = std::max(high - low, 0.0);
  scale = std::max(std::ceil(range / 254.0 * 1e6) / 1e6, 1e-6);
  bias = static_cast<int>(std::ceil(-low / scale));
}

std::uint8_t Quantise(double value, double scale, int bias) {
  return static_cast<std::uint8_t>(std::clamp(std::lround(value / scale + bias), 0L, 255L));
}

bool IsLrgb(PtmFormat format) {
  return format == PtmFormat::kLrgb || format == PtmFormat::kJpegLrgb;
}

// The coefficients of every pixel of `representation` in file units (codes 0..255), PlaneCount
// per pixel; LRGB chroma normalised per pixel so that its largest channel is 255. Each pixel's
// from its own maps only, so a band gives the rows of the whole map's values.
std::vector<double> FileUnitValues(const Representation& representation, PtmFormat format) {
  const std::size_t pixels = representation.maps().pixel_count();
  const int planes = PlaneCountOf(format);
  std::vector<double> values(pixels * planes);
  for (std::size_t p = 0; p < pixels; ++p) {
    const auto maps = representation.maps().pixel(p);
    double* v = &values[p * planes];
    if (!std::all_of(maps.begin(), maps.end(), [](float m) { return std::isfinite(m); })) {
      throw Error(fmt::format("{}: a coefficient is not finite", representation.method()));
    }
    if (!IsLrgb(format)) {
      for (int k = 0; k < planes; ++k) v[k] = 255.0 * maps[k];
      continue;
    }
    const double peak = std::max({maps[6], maps[7], maps[8]});
    const double k = peak > 0.0 ? peak : 1.0;
    for (int j = 0; j < 6; ++j) v[j] = 255.0 * maps[j] * k;
    for (int c = 0; c < 3; ++c) v[6 + c] = 255.0 * maps[6 + c] / k;
  }
  return values;
}

}  // namespace

PtmFormat PtmFormatOf(const Representation& representation) {
  const std::string& method = representation.method();
  const MapLayout& layout = representation.layout();
  const bool lrgb = method == "ptm-lrgb";
  if (representation.shading()) {
    throw Error(
        fmt::format("a {} representation is a nonlinear {} shading that a PTM file's "
                    "polynomials cannot hold: export its maps with `photomat export` "
                    "(glTF tile, PNG/EXR maps) instead",
                    method, representation.shading()->kind()));
  }
  if ((method != "ptm" && !lrgb) || representation.basis().kind() != "ptm" ||
      (lrgb && (layout.output_channels != 3 || !layout.has_gain || layout.basis_per_channel)) ||
      (!lrgb &&
       (layout.has_gain || (layout.output_channels != 3 && layout.output_channels != 1)))) {
    throw Error(fmt::format("a {} representation cannot be stored as a PTM file as it is", method));
  }
  return lrgb ? PtmFormat::kLrgb : layout.output_channels == 1 ? PtmFormat::kLum : PtmFormat::kRgb;
}

PtmCoefficientRanges::PtmCoefficientRanges(PtmFormat format) : format_(format) {
  low_.fill(INFINITY);
  high_.fill(-INFINITY);
}

void PtmCoefficientRanges::Add(const Representation& band) {
  if (PtmFormatOf(band) != format_) {
    throw Error(
        fmt::format("a {} band added to the ranges of a {}", band.method(), ToString(format_)));
  }
  method_ = band.method();
  const int planes = PlaneCountOf(format_);
  const std::vector<double> values = FileUnitValues(band, format_);
  const std::size_t pixels = values.size() / static_cast<std::size_t>(planes);
  for (int plane = 0; plane < planes; ++plane) {
    const int j = CoefficientOf(format_, plane);
    if (j < 0) continue;
    for (std::size_t p = 0; p < pixels; ++p) {
      low_[j] = std::min(low_[j], values[p * planes + plane]);
      high_[j] = std::max(high_[j], values[p * planes + plane]);
    }
  }
}

void PtmCoefficientRanges::ChooseScalesAndBiases(PtmFile& ptm) const {
  for (int j = 0; j < 6; ++j) {
    if (!std::isfinite(low_[j]) || !std::isfinite(high_[j])) {
      throw Error(fmt::format("{}: coefficient a{} is not finite", method_, j));
    }
    ChooseQuantisation(low_[j], high_[j], ptm.scale[j], ptm.bias[j]);
  }
}

std::vector<std::vector<std::uint8_t>> QuantisePtmPlanes(const Representation& band,
                                                         const PtmFile& ptm) {
  const std::vector<double> values = FileUnitValues(band, ptm.format);
  const int planes = ptm.PlaneCount();
  const std::size_t pixels = values.size() / static_cast<std::size_t>(planes);
  std::vector<std::vector<std::uint8_t>> bytes(planes, std::vector<std::uint8_t>(pixels));
  for (std::size_t p = 0; p < pixels; ++p) {
    for (int plane = 0; plane < planes; ++plane) {
      const double v = values[p * planes + plane];
      const int j = CoefficientOf(ptm.format, plane);
      bytes[plane][p] = j < 0 ? static_cast<std::uint8_t>(std::clamp(std::lround(v), 0L, 255L))
                              : Quantise(v, ptm.scale[j], ptm.bias[j]);
    }
  }
  return bytes;
}

PtmFile PtmFromRepresentation(const Representation& representation) {
  PtmFile ptm;
  ptm.format = PtmFormatOf(representation);
  ptm.width = representation.width();
  ptm.height = representation.height();
  PtmCoefficientRanges ranges(ptm.format);
  ranges.Add(representation);
  ranges.ChooseScalesAndBiases(ptm);
  ptm.planes = QuantisePtmPlanes(representation, ptm);
  return ptm;
}

namespace {

std::size_t PtmPayloadBytes(const PtmFile& header) {
  return static_cast<std::size_t>(header.width) * static_cast<std::size_t>(header.height) *
         static_cast<std::size_t>(header.PlaneCount());
}

}  // namespace

PtmBandWriter::PtmBandWriter(const fs::path& path, const PtmFile& header)
    : PtmBandWriter(path, header, PtmHeaderText(header)) {}

PtmBandWriter::PtmBandWriter(const fs::path& path, const PtmFile& header, const std::string& text)
    : header_{header.version, header.format, header.width, header.height,
              header.scale,   header.bias,   {},           {}},
      header_bytes_(text.size()),
      file_(path, text, text.size() + PtmPayloadBytes(header)) {
  if (IsJpeg(header.format) || header.width < 1 || header.height < 1) {
    throw Error(path, "a .ptm is written in bands in the raw RGB, LUM or LRGB formats only");
  }
}

void PtmBandWriter::WriteNext(const std::vector<std::vector<std::uint8_t>>& planes) {
  const std::size_t width = static_cast<std::size_t>(header_.width);
  if (static_cast<int>(planes.size()) != header_.PlaneCount() || planes.front().empty() ||
      planes.front().size() % width != 0) {
    throw Error(file_.path(), "a band needs every coefficient plane, whole rows of the width");
  }
  const int rows = static_cast<int>(planes.front().size() / width);
  for (const auto& plane : planes) {
    if (plane.size() != planes.front().size()) {
      throw Error(file_.path(), "the planes of a band differ in size");
    }
  }
  if (next_row_ + rows > header_.height) {
    throw Error(file_.path(), fmt::format("rows {}..{} are past the image's {} rows", next_row_,
                                          next_row_ + rows - 1, header_.height));
  }
  // The band's rows are one run of each block, in reverse: the file holds rows bottom to top,
  // so the band's last row comes first, at file row height - next_row - rows.
  const std::size_t pixels = width * static_cast<std::size_t>(header_.height);
  const std::size_t first_file_row = static_cast<std::size_t>(header_.height - next_row_ - rows);
  std::size_t block_start = header_bytes_;
  std::vector<std::uint8_t> run;
  for (const PayloadBlock& block : PayloadBlocks(header_.format)) {
    const std::size_t row_bytes = width * static_cast<std::size_t>(block.count);
    run.resize(row_bytes * static_cast<std::size_t>(rows));
    for (int y = 0; y < rows; ++y) {
      EncodeBlockRow(planes, static_cast<std::size_t>(y) * width, header_.width, block,
                     run.data() + static_cast<std::size_t>(rows - 1 - y) * row_bytes);
    }
    file_.Write(block_start + first_file_row * row_bytes, run);
    block_start += pixels * static_cast<std::size_t>(block.count);
  }
  next_row_ += rows;
}

void PtmBandWriter::Commit() {
  if (next_row_ != header_.height) {
    throw Error(file_.path(),
                fmt::format("only {} of its {} rows were written", next_row_, header_.height));
  }
  file_.Commit();
}

}  // namespace photomat
