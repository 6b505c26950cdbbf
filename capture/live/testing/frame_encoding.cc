#include "capture/live/testing/frame_encoding.h"

#include <fmt/format.h>
#include <turbojpeg.h>

#include <algorithm>
#include <cmath>

#include "core/error.h"

namespace photomat::testing {
namespace {

double Encode(double linear, ColourSpace encoding) {
  linear = std::clamp(linear, 0.0, 1.0);
  return encoding == ColourSpace::kSrgb ? LinearToSrgb(linear) : linear;
}

std::uint8_t Byte(double unit) {
  return static_cast<std::uint8_t>(std::lround(std::clamp(unit, 0.0, 1.0) * 255.0));
}

// R, G, B of a pixel (a grey image repeats its channel).
void Rgb(const Image& image, int x, int y, double rgb[3]) {
  for (int c = 0; c < 3; ++c) rgb[c] = image.at(x, y, image.channels() == 1 ? 0 : c);
}

double Mean(const Image& image, int x, int y) {
  double sum = 0.0;
  for (int c = 0; c < image.channels(); ++c) sum += image.at(x, y, c);
  return sum / image.channels();
}

std::vector<std::uint8_t> EncodeJpeg(const FrameLayout& layout, const Image& linear,
                                     ColourSpace encoding, int quality) {
  std::vector<std::uint8_t> rgb(linear.pixel_count() * 3);
  for (int y = 0; y < layout.height; ++y) {
    for (int x = 0; x < layout.width; ++x) {
      double v[3];
      Rgb(linear, x, y, v);
      for (int c = 0; c < 3; ++c) {
        rgb[(static_cast<std::size_t>(y) * layout.width + x) * 3 + c] =
            Byte(Encode(v[c], encoding));
      }
    }
  }
  tjhandle handle = tjInitCompress();
  unsigned char* jpeg = nullptr;
  unsigned long size = 0;
  const int result = tjCompress2(handle, rgb.data(), layout.width, layout.width * 3, layout.height,
                                 TJPF_RGB, &jpeg, &size, TJSAMP_444, quality, TJFLAG_ACCURATEDCT);
  std::vector<std::uint8_t> bytes;
  if (result == 0) bytes.assign(jpeg, jpeg + size);
  const std::string message = result == 0 ? "" : tjGetErrorStr2(handle);
  tjFree(jpeg);
  tjDestroy(handle);
  if (result != 0) throw Error(fmt::format("JPEG encoding failed: {}", message));
  return bytes;
}

}  // namespace

std::vector<std::uint8_t> EncodeFrame(const FrameLayout& layout, const Image& linear,
                                      ColourSpace encoding, int jpeg_quality) {
  if (linear.width() != layout.width || linear.height() != layout.height) {
    throw Error(fmt::format("EncodeFrame: image {}x{} for a {}x{} layout", linear.width(),
                            linear.height(), layout.width, layout.height));
  }
  if (layout.format == PixelFormat::kFloat) throw Error("EncodeFrame: FLOAT is no camera format");
  if (layout.format == PixelFormat::kMjpeg) {
    return EncodeJpeg(layout, linear, encoding, jpeg_quality);
  }
  const std::size_t packed = static_cast<std::size_t>(layout.width) * BytesPerPixel(layout.format);
  const std::size_t stride = std::max<std::size_t>(packed, layout.bytes_per_line);
  std::vector<std::uint8_t> bytes(stride * layout.height, 0);
  for (int y = 0; y < layout.height; ++y) {
    std::uint8_t* row = bytes.data() + stride * y;
    for (int x = 0; x < layout.width; ++x) {
      double v[3];
      Rgb(linear, x, y, v);
      switch (layout.format) {
        case PixelFormat::kGrey:
          row[x] = Byte(Encode(Mean(linear, x, y), encoding));
          break;
        case PixelFormat::kY16: {
          const auto code = static_cast<unsigned>(
              std::lround(std::clamp(Mean(linear, x, y), 0.0, 1.0) * 65535.0));
          row[2 * x] = code & 0xff;
          row[2 * x + 1] = code >> 8;
          break;
        }
        case PixelFormat::kRgb24:
        case PixelFormat::kBgr24:
          for (int c = 0; c < 3; ++c) {
            const int slot = layout.format == PixelFormat::kRgb24 ? c : 2 - c;
            row[3 * x + slot] = Byte(Encode(v[c], encoding));
          }
          break;
        case PixelFormat::kYuyv: {
          // BT.601 limited range; the pair's chroma is the mean of its two pixels.
          double e[3];
          for (int c = 0; c < 3; ++c) e[c] = Encode(v[c], encoding);
          const double luma = 0.299 * e[0] + 0.587 * e[1] + 0.114 * e[2];
          row[2 * x] = static_cast<std::uint8_t>(std::lround(16 + 219 * luma));
          if (x % 2 == 1) {
            double pair_b = 0.0, pair_r = 0.0;
            for (int k = x - 1; k <= x; ++k) {
              double p[3];
              Rgb(linear, k, y, p);
              for (int c = 0; c < 3; ++c) p[c] = Encode(p[c], encoding);
              const double l = 0.299 * p[0] + 0.587 * p[1] + 0.114 * p[2];
              pair_b += (p[2] - l) / 1.772 / 2.0;
              pair_r += (p[0] - l) / 1.402 / 2.0;
            }
            row[2 * x - 1] = static_cast<std::uint8_t>(std::lround(128 + 224 * pair_b));
            row[2 * x + 1] = static_cast<std::uint8_t>(std::lround(128 + 224 * pair_r));
          }
          break;
        }
        case PixelFormat::kMjpeg:
        case PixelFormat::kFloat:
          break;
      }
    }
  }
  return bytes;
}

}  // namespace photomat::testing
