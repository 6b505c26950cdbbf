#include "capture/live/pixel_format.h"

#include <fmt/format.h>
#include <linux/videodev2.h>
#include <turbojpeg.h>

#include <algorithm>
#include <array>
#include <cctype>
#include <memory>
#include <vector>

#include "core/error.h"

namespace photomat {
namespace {

// What photomat knows of each format: its name, its V4L2 code (0: none) and its bytes per pixel
// (0: compressed).
struct FormatFacts {
  PixelFormat format;
  std::string_view name;
  std::uint32_t fourcc;
  int bytes_per_pixel;
};
constexpr std::array<FormatFacts, 7> kFormatFacts = {{
    {PixelFormat::kGrey, "GREY", V4L2_PIX_FMT_GREY, 1},
    {PixelFormat::kY16, "Y16", V4L2_PIX_FMT_Y16, 2},
    {PixelFormat::kYuyv, "YUYV", V4L2_PIX_FMT_YUYV, 2},
    {PixelFormat::kMjpeg, "MJPG", V4L2_PIX_FMT_MJPEG, 0},
    {PixelFormat::kRgb24, "RGB3", V4L2_PIX_FMT_RGB24, 3},
    {PixelFormat::kBgr24, "BGR3", V4L2_PIX_FMT_BGR24, 3},
    {PixelFormat::kFloat, "FLOAT", 0, 12},
}};

const FormatFacts& Facts(PixelFormat format) {
  for (const FormatFacts& facts : kFormatFacts) {
    if (facts.format == format) return facts;
  }
  throw Error("internal: a pixel format without facts");
}

constexpr std::array<PixelFormat, 6> kAllFormats = {PixelFormat::kY16,   PixelFormat::kRgb24,
                                                    PixelFormat::kBgr24, PixelFormat::kYuyv,
                                                    PixelFormat::kGrey,  PixelFormat::kMjpeg};

// 8-bit code -> linear value, for one encoding.
std::array<float, 256> EightBitTable(ColourSpace encoding) {
  std::array<float, 256> table{};
  for (int code = 0; code < 256; ++code) {
    const double value = code / 255.0;
    table[code] = static_cast<float>(encoding == ColourSpace::kSrgb ? SrgbToLinear(value) : value);
  }
  return table;
}

float Linearise(double encoded, ColourSpace encoding) {
  encoded = std::clamp(encoded, 0.0, 1.0);
  return static_cast<float>(encoding == ColourSpace::kSrgb ? SrgbToLinear(encoded) : encoded);
}

std::size_t RowStride(const FrameLayout& layout) {
  const std::size_t packed = static_cast<std::size_t>(layout.width) * BytesPerPixel(layout.format);
  return layout.bytes_per_line > 0 ? static_cast<std::size_t>(layout.bytes_per_line) : packed;
}

void CheckSize(const FrameLayout& layout, std::size_t available) {
  const std::size_t packed = static_cast<std::size_t>(layout.width) * BytesPerPixel(layout.format);
  const std::size_t stride = RowStride(layout);
  if (stride < packed) {
    throw Error(fmt::format("{} frame: {} bytes per line is less than a {}-pixel row ({} bytes)",
                            ToString(layout.format), stride, layout.width, packed));
  }
  const std::size_t needed = stride * (layout.height - 1) + packed;
  if (available < needed) {
    throw Error(fmt::format("{} frame of {}x{} truncated: {} bytes, expected {}",
                            ToString(layout.format), layout.width, layout.height, available,
                            needed));
  }
}

// Interleaved 8-bit samples with `channels` per pixel, channel order given by `order`.
Image DecodeEightBit(const FrameLayout& layout, std::span<const std::uint8_t> bytes,
                     const std::array<float, 256>& table, int channels,
                     const std::array<int, 3>& order) {
  const int out_channels = channels == 1 ? 1 : 3;
  Image image(layout.width, layout.height, out_channels);
  const std::size_t stride = RowStride(layout);
  for (int y = 0; y < layout.height; ++y) {
    const std::uint8_t* row = bytes.data() + stride * y;
    for (int x = 0; x < layout.width; ++x) {
      const std::uint8_t* px = row + static_cast<std::size_t>(x) * channels;
      for (int c = 0; c < out_channels; ++c) image.at(x, y, c) = table[px[order[c]]];
    }
  }
  return image;
}

Image DecodeY16(const FrameLayout& layout, std::span<const std::uint8_t> bytes) {
  Image image(layout.width, layout.height, 1);
  const std::size_t stride = RowStride(layout);
  for (int y = 0; y < layout.height; ++y) {
    const std::uint8_t* row = bytes.data() + stride * y;
    for (int x = 0; x < layout.width; ++x) {
      const unsigned code = row[2 * x] | (static_cast<unsigned>(row[2 * x + 1]) << 8);
      image.at(x, y, 0) = static_cast<float>(code / 65535.0);
    }
  }
  return image;
}

// BT.601 limited range (Y' in 16..235, Cb/Cr in 16..240) to gamma-encoded R'G'B' in [0, 1].
void YCbCr601ToRgb(int y, int cb, int cr, double rgb[3]) {
  constexpr double kr = 0.299, kb = 0.114, kg = 1.0 - kr - kb;
  const double luma = (y - 16) / 219.0;
  const double pb = (cb - 128) / 224.0;
  const double pr = (cr - 128) / 224.0;
  rgb[0] = luma + 2.0 * (1.0 - kr) * pr;
  rgb[2] = luma + 2.0 * (1.0 - kb) * pb;
  rgb[1] = (luma - kr * rgb[0] - kb * rgb[2]) / kg;
}

Image DecodeYuyv(const FrameLayout& layout, std::span<const std::uint8_t> bytes,
                 ColourSpace encoding) {
  if (layout.width % 2 != 0) {
    throw Error(fmt::format("YUYV frame width {} is odd (pixels come in pairs)", layout.width));
  }
  Image image(layout.width, layout.height, 3);
  const std::size_t stride = RowStride(layout);
  for (int y = 0; y < layout.height; ++y) {
    const std::uint8_t* row = bytes.data() + stride * y;
    for (int x = 0; x < layout.width; x += 2) {
      const std::uint8_t* quad = row + static_cast<std::size_t>(x) * 2;
      for (int k = 0; k < 2; ++k) {
        double rgb[3];
        YCbCr601ToRgb(quad[2 * k], quad[1], quad[3], rgb);
        for (int c = 0; c < 3; ++c) image.at(x + k, y, c) = Linearise(rgb[c], encoding);
      }
    }
  }
  return image;
}

struct TurboJpegHandle {
  tjhandle handle = tjInitDecompress();
  ~TurboJpegHandle() {
    if (handle) tjDestroy(handle);
  }
};

Image DecodeMjpeg(const FrameLayout& layout, std::span<const std::uint8_t> bytes,
                  const std::array<float, 256>& table) {
  TurboJpegHandle jpeg;
  if (!jpeg.handle) throw Error("cannot start the JPEG decoder (libjpeg-turbo)");
  int width = 0, height = 0, subsampling = 0, colour_space = 0;
  // The TurboJPEG 2.1 API takes a non-const buffer but does not write to it.
  auto* data = const_cast<unsigned char*>(bytes.data());
  const auto size = static_cast<unsigned long>(bytes.size());
  if (bytes.empty() || tjDecompressHeader3(jpeg.handle, data, size, &width, &height, &subsampling,
                                           &colour_space) != 0) {
    throw Error(fmt::format("corrupt MJPEG frame ({} bytes): {}", bytes.size(),
                            bytes.empty() ? "empty" : tjGetErrorStr2(jpeg.handle)));
  }
  if (width != layout.width || height != layout.height) {
    throw Error(fmt::format("MJPEG frame is {}x{}, the stream format is {}x{}", width, height,
                            layout.width, layout.height));
  }
  std::vector<std::uint8_t> rgb(static_cast<std::size_t>(width) * height * 3);
  if (tjDecompress2(jpeg.handle, data, size, rgb.data(), width, width * 3, height, TJPF_RGB,
                    TJFLAG_ACCURATEDCT) != 0) {
    // Warnings too (e.g. a truncated frame, whose missing rows would decode as grey): a frame
    // that is not whole is not a measurement.
    throw Error(fmt::format("corrupt MJPEG frame ({} bytes): {}", bytes.size(),
                            tjGetErrorStr2(jpeg.handle)));
  }
  const FrameLayout packed{PixelFormat::kRgb24, width, height, 0};
  return DecodeEightBit(packed, rgb, table, 3, {0, 1, 2});
}

}  // namespace

std::string_view ToString(PixelFormat format) { return Facts(format).name; }

std::optional<PixelFormat> ParsePixelFormat(std::string_view name) {
  std::string upper(name);
  for (char& c : upper) c = static_cast<char>(std::toupper(static_cast<unsigned char>(c)));
  if (upper == "MJPEG") return PixelFormat::kMjpeg;
  if (upper == "RGB24") return PixelFormat::kRgb24;
  if (upper == "BGR24") return PixelFormat::kBgr24;
  if (upper == "FLOAT") return PixelFormat::kFloat;
  for (PixelFormat format : kAllFormats) {
    if (upper == ToString(format)) return format;
  }
  return std::nullopt;
}

std::span<const PixelFormat> AllPixelFormats() { return kAllFormats; }

std::string SupportedPixelFormatList() {
  std::string list;
  for (PixelFormat format : kAllFormats) {
    if (!list.empty()) list += ", ";
    list += ToString(format);
  }
  return list;
}

int ChannelCount(PixelFormat format) {
  return format == PixelFormat::kGrey || format == PixelFormat::kY16 ? 1 : 3;
}

int BytesPerPixel(PixelFormat format) { return Facts(format).bytes_per_pixel; }

std::uint32_t V4l2FourCc(PixelFormat format) { return Facts(format).fourcc; }

std::optional<PixelFormat> PixelFormatFromV4l2(std::uint32_t fourcc) {
  for (PixelFormat format : kAllFormats) {
    if (V4l2FourCc(format) == fourcc) return format;
  }
  return std::nullopt;
}

std::string FourCcToString(std::uint32_t fourcc) {
  std::string text;
  for (int i = 0; i < 4; ++i) {
    const char c = static_cast<char>((fourcc >> (8 * i)) & 0xff);
    text += std::isprint(static_cast<unsigned char>(c)) ? c : '.';
  }
  while (!text.empty() && text.back() == ' ') text.pop_back();
  return text;
}

Image DecodeFrame(const FrameLayout& layout, std::span<const std::uint8_t> bytes,
                  ColourSpace eight_bit_encoding) {
  if (layout.width <= 0 || layout.height <= 0) {
    throw Error(fmt::format("{} frame has no pixels ({}x{})", ToString(layout.format), layout.width,
                            layout.height));
  }
  const std::array<float, 256> table = EightBitTable(eight_bit_encoding);
  if (layout.format == PixelFormat::kMjpeg) return DecodeMjpeg(layout, bytes, table);
  CheckSize(layout, bytes.size());
  switch (layout.format) {
    case PixelFormat::kGrey:
      return DecodeEightBit(layout, bytes, table, 1, {0, 0, 0});
    case PixelFormat::kY16:
      return DecodeY16(layout, bytes);
    case PixelFormat::kYuyv:
      return DecodeYuyv(layout, bytes, eight_bit_encoding);
    case PixelFormat::kRgb24:
      return DecodeEightBit(layout, bytes, table, 3, {0, 1, 2});
    case PixelFormat::kBgr24:
      return DecodeEightBit(layout, bytes, table, 3, {2, 1, 0});
    case PixelFormat::kMjpeg:
    case PixelFormat::kFloat:
      break;
  }
  throw Error(fmt::format("{} is not a camera pixel format", ToString(layout.format)));
}

}  // namespace photomat
