#pragma once

#include <cstdint>
#include <optional>
#include <span>
#include <string>
#include <string_view>

#include "core/colour.h"
#include "core/image.h"

namespace photomat {

// The camera pixel formats photomat decodes, named by their V4L2 fourcc. Every backend (V4L2,
// libcamera) maps its own format codes to these, so decoding lives in one place.
enum class PixelFormat {
  kGrey,   // 'GREY': 8 bits per pixel, one channel
  kY16,    // 'Y16 ': 16 bits little-endian, one channel, always linear
  kYuyv,   // 'YUYV': 4:2:2 packed Y0 U Y1 V, BT.601 limited range (V4L2's default for YUYV)
  kMjpeg,  // 'MJPG': one JPEG image per frame (full-range JFIF YCbCr), decoded by libjpeg-turbo
  kRgb24,  // 'RGB3': R, G, B bytes
  kBgr24,  // 'BGR3': B, G, R bytes (libcamera's RGB888)
  kFloat,  // linear float samples: what a replayed set (folder source) delivers; no camera does
};

// The V4L2 fourcc name ("GREY", "Y16", "YUYV", "MJPG", "RGB3", "BGR3").
std::string_view ToString(PixelFormat format);
// Accepts the fourcc names and the aliases "MJPEG", "RGB24", "BGR24" (any case).
std::optional<PixelFormat> ParsePixelFormat(std::string_view name);
// Every camera format, in order of preference for photometry (deepest and least compressed
// first); kFloat is not among them.
std::span<const PixelFormat> AllPixelFormats();
// "GREY, Y16, YUYV, MJPG, RGB3, BGR3".
std::string SupportedPixelFormatList();

// 1 for GREY and Y16, 3 (linear R, G, B) for the others.
int ChannelCount(PixelFormat format);
// Bytes per pixel of an uncompressed format (0 for MJPEG, 12 for kFloat).
int BytesPerPixel(PixelFormat format);

// V4L2 fourcc codes (v4l2_fourcc('G','R','E','Y') ...; 0 for kFloat), and back.
std::uint32_t V4l2FourCc(PixelFormat format);
std::optional<PixelFormat> PixelFormatFromV4l2(std::uint32_t fourcc);
// A fourcc as its four characters, trailing spaces dropped ("YUYV", "Y16").
std::string FourCcToString(std::uint32_t fourcc);

// The layout of one frame in memory.
struct FrameLayout {
  PixelFormat format = PixelFormat::kGrey;
  int width = 0;
  int height = 0;
  // Bytes from one row to the next (drivers may pad rows); 0 means packed rows. Ignored for MJPEG.
  int bytes_per_line = 0;
};

// Decodes one frame into a linear float image in [0, 1] (1 or 3 channels, row 0 at the top).
// `eight_bit_encoding` says how 8-bit samples (GREY, YUYV, MJPEG, RGB3, BGR3) encode light: kSrgb
// for video cameras (their output is gamma-encoded), kLinear for machine-vision cameras with the
// gamma off. Y16 is always linear. Throws Error (without a file name; callers add the device) for a
// buffer too short for the layout, kFloat (not a camera format), a corrupt JPEG, or a JPEG of
// another size than the layout's.
Image DecodeFrame(const FrameLayout& layout, std::span<const std::uint8_t> bytes,
                  ColourSpace eight_bit_encoding);

}  // namespace photomat
