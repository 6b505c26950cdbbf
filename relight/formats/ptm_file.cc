#include "relight/formats/ptm_file.h"

#include <OpenImageIO/filesystem.h>
#include <OpenImageIO/imageio.h>
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

// One greyscale JPEG stream of a compressed PTM, decoded through OpenImageIO from memory.
std::vector<std::uint8_t> DecodeJpegPlane(std::span<const std::uint8_t> stream, const PtmFile& ptm,
                                          int plane, const fs::path& file) {
  const auto fail = [&](const std::string& why) -> std::vector<std::uint8_t> {
    throw Error(file, fmt::format("JPEG plane {}: {}", plane, why));
  };
  if (stream.empty()) return fail("empty stream");
  // OpenImageIO reads from memory through an IOProxy handed to the JPEG reader it creates.
  OIIO::Filesystem::IOMemReader memory(stream.data(), stream.size());
  auto input = OIIO::ImageInput::create("plane.jpg", false, nullptr, &memory);
  OIIO::ImageSpec spec;
  if (!input || !input->set_ioproxy(&memory) || !input->open("plane.jpg", spec)) {
    const std::string why = input ? input->geterror() : OIIO::geterror();
    return fail(fmt::format("not a readable JPEG ({})", why));
  }
  if (spec.width != ptm.width || spec.height != ptm.height || spec.nchannels != 1) {
    return fail(fmt::format("{}x{} with {} channel(s), expected {}x{} greyscale", spec.width,
                            spec.height, spec.nchannels, ptm.width, ptm.height));
  }
  // Row by row: read_image allocates a large staging buffer per call, which dominates the time
  // of small planes.
  std::vector<std::uint8_t> pixels(static_cast<std::size_t>(ptm.width) * ptm.height);
  for (int y = 0; y < ptm.height; ++y) {
    if (!input->read_scanline(y, 0, OIIO::TypeDesc::UINT8,
                              pixels.data() + static_cast<std::size_t>(y) * ptm.width)) {
      return fail(fmt::format("cannot decode: {}", input->geterror()));
    }
  }
  return pixels;
}

// The JPEG variants (a real HP sample; relight's legacy reader): after the biases, the JPEG
// quality, then one line of N integers each for transforms, motion vectors x and y, decoding
// order, reference planes, stream sizes and side-information sizes (N = 18 for RGB, 9 for LRGB,
// planes numbered as in PtmFile::planes); then plane 0's stream and side information, plane 1's,
// ... A plane with a reference r stores its difference to r plus 128 (modulo 256), so r must be
// decoded first; side information is 5-byte records (big-endian pixel index, byte) of pixels the
// JPEG could not carry. Planes are stored in the file's row order (bottom to top), like raw ones.
// photomat supports no transforms or motion vectors (all real files have none).
void ReadJpegPlanes(HeaderReader& reader, PtmFile& ptm) {
  const std::size_t n = static_cast<std::size_t>(ptm.PlaneCount());
  reader.Integers(1, "the JPEG quality");
  const auto transforms = reader.Integers(n, "the plane transforms");
  const auto motion_x = reader.Integers(n, "the motion vectors (x)");
  const auto motion_y = reader.Integers(n, "the motion vectors (y)");
  const auto order = reader.Integers(n, "the plane decoding order");
  const auto reference = reader.Integers(n, "the reference planes");
  const auto sizes = reader.Integers(n, "the compressed plane sizes");
  const auto side = reader.Integers(n, "the side-information sizes");
  std::vector<int> sequence(n, -1);  // sequence[k] = the plane decoded k-th
  for (std::size_t s = 0; s < n; ++s) {
    if (transforms[s] != 0 || motion_x[s] != 0 || motion_y[s] != 0) {
      reader.Fail(fmt::format("JPEG plane {}: transforms and motion vectors are not supported", s));
    }
    if (order[s] < 0 || order[s] >= static_cast<long long>(n) || sequence[order[s]] != -1) {
      reader.Fail("the JPEG plane decoding order is not a permutation of the planes");
    }
    sequence[order[s]] = static_cast<int>(s);
    if (reference[s] < -1 || reference[s] >= static_cast<long long>(n) ||
        reference[s] == static_cast<long long>(s)) {
      reader.Fail(fmt::format("JPEG plane {}: invalid reference plane {}", s, reference[s]));
    }
    if (sizes[s] < 0 || side[s] < 0 || side[s] % 5 != 0) {
      reader.Fail(fmt::format("JPEG plane {}: invalid sizes {} and {}", s, sizes[s], side[s]));
    }
  }
  for (std::size_t s = 0; s < n; ++s) {
    if (reference[s] >= 0 && order[reference[s]] > order[s]) {
      reader.Fail(fmt::format("JPEG plane {} refers to plane {}, which is decoded after it", s,
                              reference[s]));
    }
  }
  // Locate every plane's stream and side information before decoding any.
  std::vector<std::span<const std::uint8_t>> streams(n), sides(n);
  for (std::size_t s = 0; s < n; ++s) {
    streams[s] = reader.Bytes(static_cast<std::size_t>(sizes[s]), fmt::format("JPEG plane {}", s));
    sides[s] = reader.Bytes(static_cast<std::size_t>(side[s]),
                            fmt::format("the side information of JPEG plane {}", s));
  }
  const std::size_t pixels = static_cast<std::size_t>(ptm.width) * ptm.height;
  std::vector<std::vector<std::uint8_t>> file_order(n);  // rows as stored
  for (int s : sequence) {
    std::vector<std::uint8_t> plane = DecodeJpegPlane(streams[s], ptm, s, reader.file());
    if (const long long r = reference[s]; r >= 0) {
      for (std::size_t p = 0; p < pixels; ++p) {
        plane[p] = static_cast<std::uint8_t>(plane[p] - 128 + file_order[r][p]);
      }
    }
    for (std::size_t k = 0; k < sides[s].size(); k += 5) {
      const std::size_t index = (std::size_t{sides[s][k]} << 24) |
                                (std::size_t{sides[s][k + 1]} << 16) |
                                (std::size_t{sides[s][k + 2]} << 8) | sides[s][k + 3];
      if (index >= pixels) {
        reader.Fail(
            fmt::format("JPEG plane {}: side information names pixel {} of {}", s, index, pixels));
      }
      plane[index] = sides[s][k + 4];
    }
    file_order[s] = std::move(plane);
  }
  for (std::size_t s = 0; s < n; ++s) {
    for (std::size_t p = 0; p < pixels; ++p) {
      ptm.planes[s][ImageIndexOfFileByte(ptm, p)] = file_order[s][p];
    }
  }
}

}  // namespace

std::string_view ToString(PtmFormat format) {
  for (const auto& [f, name] : kFormats) {
    if (f == format) return name;
  }
  return "PTM_FORMAT_RGB";
}

int PtmFile::PlaneCount() const { return PlaneCountOf(format); }

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
  if (IsJpeg(ptm.format)) {
    throw Error(fmt::format("photomat writes PTM_FORMAT_RGB, _LUM and _LRGB, not {}",
                            ToString(ptm.format)));
  }
  const std::size_t pixels = static_cast<std::size_t>(ptm.width) * ptm.height;
  if (ptm.width < 1 || ptm.height < 1 || static_cast<int>(ptm.planes.size()) != ptm.PlaneCount()) {
    throw Error("a PTM needs a size and one plane per coefficient");
  }
  for (const auto& plane : ptm.planes) {
    if (plane.size() != pixels) throw Error("PTM planes differ from the image size");
  }
  // The layout of real files: one item per line, a space before each newline after numbers.
  std::string out =
      fmt::format("PTM_1.2\n{}\n{}\n{}\n", ToString(ptm.format), ptm.width, ptm.height);
  for (double s : ptm.scale) out += fmt::format("{:.6f} ", s);
  out += "\n";
  for (int b : ptm.bias) out += fmt::format("{} ", b);
  out += "\n";
  const std::size_t header = out.size();
  out.resize(header + pixels * static_cast<std::size_t>(ptm.PlaneCount()));
  auto* payload = reinterpret_cast<std::uint8_t*>(out.data()) + header;
  const auto put = [&](int first_plane, int count, int stride) {
    for (std::size_t p = 0; p < pixels; ++p) {
      const std::size_t source = ImageIndexOfFileByte(ptm, p);
      for (int k = 0; k < count; ++k) *payload++ = ptm.planes[first_plane + k * stride][source];
    }
  };
  switch (ptm.format) {
    case PtmFormat::kRgb:
      for (int c = 0; c < 3; ++c) put(c, 6, 3);
      break;
    case PtmFormat::kLum:
      put(0, 6, 1);
      break;
    default:
      put(0, 6, 1);
      put(6, 3, 1);
      break;
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

}  // namespace

PtmFile PtmFromRepresentation(const Representation& representation) {
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
  PtmFile ptm;
  ptm.format = lrgb                          ? PtmFormat::kLrgb
               : layout.output_channels == 1 ? PtmFormat::kLum
                                             : PtmFormat::kRgb;
  ptm.width = representation.width();
  ptm.height = representation.height();
  const std::size_t pixels = representation.maps().pixel_count();
  const int planes = ptm.PlaneCount();
  // Coefficients in file units (codes 0..255), LRGB chroma normalised per pixel.
  std::vector<double> values(pixels * planes);
  for (std::size_t p = 0; p < pixels; ++p) {
    const auto maps = representation.maps().pixel(p);
    double* v = &values[p * planes];
    if (!std::all_of(maps.begin(), maps.end(), [](float m) { return std::isfinite(m); })) {
      throw Error(fmt::format("{}: a coefficient is not finite", method));
    }
    if (!lrgb) {
      for (int k = 0; k < planes; ++k) v[k] = 255.0 * maps[k];
      continue;
    }
    const double peak = std::max({maps[6], maps[7], maps[8]});
    const double k = peak > 0.0 ? peak : 1.0;
    for (int j = 0; j < 6; ++j) v[j] = 255.0 * maps[j] * k;
    for (int c = 0; c < 3; ++c) v[6 + c] = 255.0 * maps[6 + c] / k;
  }
  for (int j = 0; j < 6; ++j) {
    double low = INFINITY, high = -INFINITY;
    for (std::size_t p = 0; p < pixels; ++p) {
      for (int plane = 0; plane < planes; ++plane) {
        if (CoefficientOf(ptm.format, plane) != j) continue;
        low = std::min(low, values[p * planes + plane]);
        high = std::max(high, values[p * planes + plane]);
      }
    }
    if (!std::isfinite(low) || !std::isfinite(high)) {
      throw Error(fmt::format("{}: coefficient a{} is not finite", method, j));
    }
    ChooseQuantisation(low, high, ptm.scale[j], ptm.bias[j]);
  }
  ptm.planes.assign(planes, std::vector<std::uint8_t>(pixels));
  for (std::size_t p = 0; p < pixels; ++p) {
    for (int plane = 0; plane < planes; ++plane) {
      const double v = values[p * planes + plane];
      const int j = CoefficientOf(ptm.format, plane);
      ptm.planes[plane][p] = j < 0 ? static_cast<std::uint8_t>(std::clamp(std::lround(v), 0L, 255L))
                                   : Quantise(v, ptm.scale[j], ptm.bias[j]);
    }
  }
  return ptm;
}

}  // namespace photomat
