#pragma once

#include <array>
#include <filesystem>
#include <optional>
#include <string>
#include <vector>

#include "core/colour.h"
#include "core/image.h"

namespace photomat {

// How the samples of one image file encode light, decided from the file's own metadata first
// (README, "Input images and colour"). This is the one place photomat makes that decision;
// ReadImage applies it and records it in ImageFileInfo::encoding.

enum class Transfer {
  kLinear,      // light = code / max
  kSrgb,        // IEC 61966-2-1
  kGamma,       // light = (code / max)^gamma (PNG gAMA, oiio:ColorSpace "GammaX.Y")
  kIccProfile,  // through the file's ICC profile (Little CMS) to linear Rec.709 primaries
};

struct SampleEncoding {
  Transfer transfer = Transfer::kLinear;
  double gamma = 1.0;                      // kGamma only: the decoding exponent (2.2, not 0.45455)
  std::vector<unsigned char> icc_profile;  // kIccProfile only
  // Linear RGB of the file -> linear Rec.709 RGB (row-major), from OpenEXR chromaticities; unset
  // when the primaries are Rec.709 already (or unknown).
  std::optional<std::array<double, 9>> to_rec709;
  // Which rule decided: "icc-profile", "png-srgb", "png-gama", "exif-colorspace",
  // "oiio-colorspace", "camera-raw", "untagged-option" (manifest / --colour-space), "default".
  std::string decided_by;
  // What the file said, in words ("gAMA 0.45455", "ICC profile 'Adobe RGB (1998)'", ...).
  std::string evidence;

  // Short name of the decoding: "linear", "srgb", "gamma 2.2", "icc 'Adobe RGB (1998)'", with
  // " + chromaticities" when a primaries matrix follows. Equal names decode alike.
  std::string Name() const;
  // kLinear or kSrgb: whether the samples were display-encoded (non-linear transfer).
  ColourSpace Summary() const;
};

// What an image file says about itself, gathered by ReadImage from OpenImageIO's spec and, for
// PNG, from the chunks (OpenImageIO reports an untagged PNG as "sRGB").
struct EncodingEvidence {
  std::string format;  // OpenImageIO's format name: "png", "jpeg", "tiff", "openexr", "raw", ...
  int bits_per_sample = 8;
  bool floating_point = false;
  int channels = 3;
  std::vector<unsigned char> icc_profile;
  bool png_srgb_chunk = false;
  std::optional<double> png_gama;  // the stored gAMA value (0.45455 for a 2.2 curve)
  std::optional<int> exif_colour_space;
  std::string oiio_colour_space;
  std::optional<std::array<float, 8>> chromaticities;  // OpenEXR: R, G, B, white as x, y
};

// PNG colour chunks read with libpng (sRGB, gAMA, iCCP); other files and unreadable PNGs leave
// `evidence` as it is (OpenImageIO reports the damage when the pixels are read).
void AddPngChunkEvidence(const std::filesystem::path& path, EncodingEvidence& evidence);

// The order: an ICC profile (plain sRGB -> kSrgb, else through the profile); PNG sRGB; PNG gAMA;
// EXIF ColorSpace 1 (65535, "uncalibrated", says only "not sRGB" and falls through);
// OpenImageIO's oiio:ColorSpace where it comes from the file (not for PNG, JPEG and OpenEXR,
// whose readers fill it in by default); then, for integer files that say nothing, `untagged`
// (the manifest's "colour_space" or --colour-space), then 8-bit sRGB, wider linear. Float files
// are linear unless an ICC profile or oiio:ColorSpace says otherwise. OpenEXR chromaticities add
// the matrix to Rec.709 primaries. Throws nothing: unusable evidence is noted and skipped.
SampleEncoding DecideSampleEncoding(const EncodingEvidence& evidence,
                                    std::optional<ColourSpace> untagged);

// Linear light of each code of a `bits`-bit integer format (bits <= 16) under `encoding`'s
// transfer curve; code / max for kIccProfile, whose curves ApplyColourTransform applies.
std::vector<float> CodeToLightTable(const SampleEncoding& encoding, int bits);
// The transfer curve of a float sample (identity for kIccProfile, as above).
float DecodeFloatSample(const SampleEncoding& encoding, float value);

// Whatever mixes channels, after the curves: the ICC profile's transform (channels 0-2 of an RGB
// profile, channel 0 of a grey one) and the chromaticities matrix (channels 0-2). Does nothing for
// other encodings. Each pixel is transformed alone, so a band of rows converts as the whole image
// would. Throws Error naming `file` when Little CMS cannot build the transform.
void ApplyColourTransform(const SampleEncoding& encoding, ImageView image,
                          const std::filesystem::path& file);

// One image's decision, as recorded in a stack's provenance ("capture": {"images": [...]}).
struct ImageEncodingRecord {
  std::string file;
  std::string encoding;  // SampleEncoding::Name()
  std::string decided_by;
  std::string evidence;
};

// Logs a warning (spdlog) naming the files when the images of one set were decoded differently
// (e.g. one frame sRGB-tagged, the others untagged 16-bit). Returns whether they disagree.
bool WarnIfEncodingsDisagree(const std::vector<ImageEncodingRecord>& records);

}  // namespace photomat
