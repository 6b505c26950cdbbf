#pragma once

#include <array>
#include <cstddef>
#include <filesystem>
#include <map>
#include <optional>
#include <string>
#include <string_view>
#include <vector>

#include "core/colour.h"
#include "core/image.h"
#include "core/sample_encoding.h"

namespace photomat {

// All image files go through OpenImageIO: 8/16-bit PNG and TIFF, JPEG, OpenEXR (float and half,
// many channels), camera RAW and whatever else the installed OpenImageIO reads.

// How camera RAW files (.dng, .cr2, .nef, ...; OpenImageIO's LibRaw plugin) are developed:
// always scene-linear (raw:ColorSpace "sRGB-linear": sRGB primaries, no transfer curve), without
// LibRaw's auto-brightening (raw:auto_bright 0), maximum adjustment (raw:adjust_maximum_thr 0) or
// OpenImageIO's scene-linear rescaling (raw:apply_scene_linear_scale left unset: OpenImageIO
// applies it whenever the key is present), so that values stay proportional to exposure across a
// bracketed series (core/camera_raw_test.cc: within 0.06 %, measured). README, "Input images and
// colour".
struct CameraRawOptions {
  // LibRaw's demosaic (raw:Demosaic): "linear", "VNG", "PPG", "AHD", "DCB", ...
  // IMPLEMENTER CHOICE: "linear" (bilinear interpolation), the one demosaic that is a fixed
  // linear operator: the adaptive ones (AHD, LibRaw's default) choose per pixel by comparing
  // neighbours, and may choose differently under different lights, which photometric fits then
  // read as shading. Pass "AHD" for sharper colour edges.
  std::string demosaic = "linear";
  // White-balance multipliers R, G, B, G2 (raw:user_mul with raw:use_camera_wb 0); unset: the
  // camera's own (raw:use_camera_wb 1; a DNG's AsShotNeutral).
  std::optional<std::array<float, 4>> white_balance;
};

struct ImageReadOptions {
  // How integer samples encode light when the file says nothing about it (no ICC profile, PNG
  // sRGB/gAMA chunk, EXIF ColorSpace or oiio:ColorSpace: DecideSampleEncoding): the manifest's
  // "colour_space" or --colour-space. Unset: untagged 8-bit files are sRGB (what cameras and
  // editors write), 16-bit and wider integer files linear (what lab cameras and DiLiGenT write).
  std::optional<ColourSpace> untagged_colour_space;
  // Overrides the file's tags: integer samples read as this whatever the file says (kLinear: the
  // stored codes / max, for masks, response-curve calibration and tests of stored codes). Float
  // files stay linear.
  std::optional<ColourSpace> colour_space;
  // Photometric data have no use for alpha; map stacks keep every channel.
  bool keep_alpha = false;
  CameraRawOptions camera_raw;
};

// What the file held, before conversion to linear float.
struct ImageFileInfo {
  int bits_per_sample = 0;
  bool floating_point = false;
  // kSrgb when the samples were display-encoded (any non-linear transfer), else kLinear.
  ColourSpace colour_space = ColourSpace::kLinear;
  // What was decided for this file, and why (recorded in stacks' provenance).
  SampleEncoding encoding;
  // Pixels with a channel at the largest code of an integer format: clipped, not measured.
  std::size_t saturated_pixels = 0;
  // String metadata of the file (e.g. photomat's map-stack description in an EXR header).
  std::map<std::string, std::string> attributes;
};

struct LoadedImage {
  Image image;  // linear float; integer formats scaled to [0, 1]
  ImageFileInfo info;
};

// Throws Error naming `path` when the file is missing, not an image, truncated or corrupt, or
// holds non-finite values.
LoadedImage ReadImage(const std::filesystem::path& path, const ImageReadOptions& options = {});

// Whether `path`'s extension (any case) names an image format the installed OpenImageIO reads
// (PNG, TIFF, JPEG, EXR, PNM, camera RAW such as .dng/.cr2/.nef, ...): how photomat picks the
// images out of a folder of frames. OpenImageIO's own list, so RAW and other plugins count.
bool IsReadableImageFileName(const std::filesystem::path& path);

// "img.2.png" before "img.10.png": runs of digits compare as numbers (leading zeros aside), the
// rest character by character; the order of numbered frames however they are padded.
bool NaturalLess(std::string_view a, std::string_view b);

// The image files (IsReadableImageFileName) directly inside `folder`, in NaturalLess order of
// their names; subfolders and other files are skipped. Throws Error naming the folder when it is
// not a readable folder (an empty list is not an error here: callers say what they expected).
std::vector<std::filesystem::path> ListImageFiles(const std::filesystem::path& folder);

// A mask image: a pixel is set where any channel is above half of full scale (thresholding the
// anti-aliased masks of real data sets at 50 %).
Mask ReadMask(const std::filesystem::path& path);

enum class SampleType { kUint8, kUint16, kHalf, kFloat };

// The lossless OpenEXR compressions (b44, pxr24 and dwa lose float bits and are not offered).
// Every one stores float samples bit for bit; they differ in speed and size only (README, "Map
// stacks").
enum class ExrCompression { kNone, kRle, kZips, kZip, kPiz };

// IMPLEMENTER CHOICE: rle, chosen for writing speed among the lossless compressions (README, "Map
// stacks", holds the measured table). On the PTM stack of DiLiGenT cat (612 x 512, 18 float
// channels) rle took a third of zip's CPU time (72 against 216 ms) for 9 % more bytes (3.63 against
// 3.33 MB, zip the smallest; none: 22.6 MB); on a noisy synthetic stack, where no compression saves
// more than 13 % (piz), a seventh (98 against 670 ms). For the smallest file pass zip or piz.
inline constexpr ExrCompression kDefaultExrCompression = ExrCompression::kRle;

// "none", "rle", "zips", "zip", "piz": OpenEXR's own names.
std::string_view ToString(ExrCompression compression);
// Throws Error "unknown EXR compression 'x' (none, rle, zips, zip or piz)".
ExrCompression ParseExrCompression(std::string_view name);

struct ImageWriteOptions {
  SampleType sample_type = SampleType::kFloat;
  // For integer types: kSrgb applies the sRGB curve before quantising (display images), kLinear
  // stores linear values (16-bit data). Values are clamped to [0, 1] before quantising.
  ColourSpace encoding = ColourSpace::kLinear;
  // Written as string metadata where the format allows it (EXR header, PNG text).
  std::map<std::string, std::string> attributes;
  // For .exr files only.
  ExrCompression exr_compression = kDefaultExrCompression;
};

// Writes atomically (temporary name, then rename). The format follows the extension. Throws Error
// naming `path` on failure (including a full disk) and for non-finite values in integer output.
// EXR chunks are compressed in parallel on as many threads as TBB allows the caller (a
// tbb::global_control limit is respected), and the file is the same byte for byte on any number
// of threads.
void WriteImage(const std::filesystem::path& path, const Image& image,
                const ImageWriteOptions& options = {});

// Writes a mask as an 8-bit greyscale image (0 / 255).
void WriteMask(const std::filesystem::path& path, const Mask& mask);

}  // namespace photomat
