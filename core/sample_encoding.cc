#include "core/sample_encoding.h"

#include <fmt/format.h>
#include <fmt/ranges.h>
#include <lcms2.h>
#include <png.h>
#include <spdlog/spdlog.h>

#include <Eigen/Dense>
#include <algorithm>
#include <cmath>
#include <csetjmp>
#include <cstdint>
#include <cstdio>
#include <map>
#include <memory>
#include <string_view>

#include "core/error.h"

namespace photomat {
namespace {

namespace fs = std::filesystem;

// ---- PNG chunks (libpng) -------------------------------------------------------------------

void IgnorePngWarning(png_structp, png_const_charp) {}
[[noreturn]] void AbandonPng(png_structp png, png_const_charp) { png_longjmp(png, 1); }

// The colour chunks before the first IDAT. Holds no C++ objects across setjmp: libpng's errors
// jump back here (the file's damage is OpenImageIO's to report).
bool ReadPngColourChunks(png_structp png, png_infop info, std::FILE* file, bool& srgb,
                         png_fixed_point& gama, bool& has_gama, png_bytep& profile,
                         png_uint_32& profile_size) {
  if (setjmp(png_jmpbuf(png))) return false;
  png_init_io(png, file);
  png_set_sig_bytes(png, 8);
  png_read_info(png, info);
  int intent = 0;
  srgb = png_get_sRGB(png, info, &intent) != 0;
  has_gama = png_get_valid(png, info, PNG_INFO_gAMA) != 0 &&
             png_get_gAMA_fixed(png, info, &gama) != 0 && gama > 0;
  png_charp name = nullptr;
  int compression = 0;
  if (png_get_iCCP(png, info, &name, &compression, &profile, &profile_size) == 0) {
    profile = nullptr, profile_size = 0;
  }
  return true;
}

// ---- ICC profiles (Little CMS) -------------------------------------------------------------

struct ProfileCloser {
  void operator()(void* profile) const { cmsCloseProfile(profile); }
};
using Profile = std::unique_ptr<void, ProfileCloser>;

struct TransformDeleter {
  void operator()(void* transform) const { cmsDeleteTransform(transform); }
};
using Transform = std::unique_ptr<void, TransformDeleter>;

Profile OpenProfile(const std::vector<unsigned char>& bytes) {
  return Profile(cmsOpenProfileFromMem(bytes.data(), static_cast<cmsUInt32Number>(bytes.size())));
}

std::string ProfileDescription(cmsHPROFILE profile) {
  char text[256] = {};
  if (cmsGetProfileInfoASCII(profile, cmsInfoDescription, "en", "US", text, sizeof text) == 0) {
    return "unnamed";
  }
  return text;
}

// IMPLEMENTER CHOICE: a matrix-shaper RGB profile whose colorants are sRGB's within 2e-3 (the
// published sRGB profiles differ by up to 1e-3 in their D50-adapted colorants) and whose three
// curves follow the sRGB curve within 2e-3 at 33 points (a gamma-2.2 curve is 1e-2 away) is
// "plain sRGB", decoded by photomat's own exact sRGB curve instead of a Little CMS transform.
bool IsPlainSrgb(cmsHPROFILE profile) {
  if (cmsGetColorSpace(profile) != cmsSigRgbData || !cmsIsMatrixShaper(profile)) return false;
  const Profile srgb(cmsCreate_sRGBProfile());
  for (const cmsTagSignature tag :
       {cmsSigRedColorantTag, cmsSigGreenColorantTag, cmsSigBlueColorantTag}) {
    const auto* own = static_cast<const cmsCIEXYZ*>(cmsReadTag(profile, tag));
    const auto* reference = static_cast<const cmsCIEXYZ*>(cmsReadTag(srgb.get(), tag));
    if (own == nullptr || reference == nullptr) return false;
    if (std::abs(own->X - reference->X) > 2e-3 || std::abs(own->Y - reference->Y) > 2e-3 ||
        std::abs(own->Z - reference->Z) > 2e-3) {
      return false;
    }
  }
  for (const cmsTagSignature tag : {cmsSigRedTRCTag, cmsSigGreenTRCTag, cmsSigBlueTRCTag}) {
    const auto* curve = static_cast<const cmsToneCurve*>(cmsReadTag(profile, tag));
    if (curve == nullptr) return false;
    for (int i = 0; i <= 32; ++i) {
      const double x = i / 32.0;
      if (std::abs(cmsEvalToneCurveFloat(curve, static_cast<cmsFloat32Number>(x)) -
                   SrgbToLinear(x)) > 2e-3) {
        return false;
      }
    }
  }
  return true;
}

// Linear light in Rec.709 / sRGB primaries, D65 white: what photomat's images hold.
Profile LinearRec709Profile() {
  const cmsCIExyY d65 = {0.3127, 0.3290, 1.0};
  const cmsCIExyYTRIPLE primaries = {{0.64, 0.33, 1.0}, {0.30, 0.60, 1.0}, {0.15, 0.06, 1.0}};
  cmsToneCurve* linear = cmsBuildGamma(nullptr, 1.0);
  cmsToneCurve* curves[3] = {linear, linear, linear};
  Profile profile(cmsCreateRGBProfile(&d65, &primaries, curves));
  cmsFreeToneCurve(linear);
  return profile;
}

Profile LinearGreyProfile() {
  const cmsCIExyY d65 = {0.3127, 0.3290, 1.0};
  cmsToneCurve* linear = cmsBuildGamma(nullptr, 1.0);
  Profile profile(cmsCreateGrayProfile(&d65, linear));
  cmsFreeToneCurve(linear);
  return profile;
}

// ---- chromaticities -------------------------------------------------------------------------

// File RGB -> Rec.709 RGB, white adapted to D65 with the Bradford transform when the file's white
// is another (relative colorimetry: the file's white stays white).
std::optional<std::array<double, 9>> ChromaticitiesToRec709(const std::array<float, 8>& file) {
  Chromaticities c{};
  std::copy(file.begin(), file.end(), c.begin());
  const auto source = RgbToXyzMatrix(c);
  if (!source) return std::nullopt;
  const Eigen::Matrix3d target = *RgbToXyzMatrix(kRec709Chromaticities);
  Eigen::Matrix3d bradford;
  bradford << 0.8951, 0.2664, -0.1614, -0.7502, 1.7135, 0.0367, 0.0389, -0.0685, 1.0296;
  const Eigen::Vector3d from = bradford * XyzOfChromaticity(c[6], c[7]);
  const Eigen::Vector3d to = bradford * XyzOfChromaticity(0.3127, 0.3290);
  const Eigen::Matrix3d adapt = bradford.inverse() * to.cwiseQuotient(from).asDiagonal() * bradford;
  const Eigen::Matrix3d matrix = target.inverse() * adapt * *source;
  std::array<double, 9> out{};
  for (int r = 0; r < 3; ++r) {
    for (int k = 0; k < 3; ++k) out[3 * r + k] = matrix(r, k);
  }
  return out;
}

bool IsRec709(const std::array<float, 8>& c) {
  for (int i = 0; i < 8; ++i) {
    if (std::abs(c[i] - kRec709Chromaticities[i]) > 1e-4) return false;
  }
  return true;
}

// ---- the decision ---------------------------------------------------------------------------

SampleEncoding Decided(Transfer transfer, std::string decided_by, std::string evidence,
                       double gamma = 1.0) {
  SampleEncoding encoding;
  encoding.transfer = transfer;
  encoding.gamma = gamma;
  encoding.decided_by = std::move(decided_by);
  encoding.evidence = std::move(evidence);
  return encoding;
}

// A gamma exponent within 1e-3 of 1 is linear (PNG stores 100000 for 1.0).
SampleEncoding FromGamma(double gamma, std::string decided_by, std::string evidence) {
  if (std::abs(gamma - 1.0) < 1e-3) {
    return Decided(Transfer::kLinear, std::move(decided_by), std::move(evidence));
  }
  return Decided(Transfer::kGamma, std::move(decided_by), std::move(evidence), gamma);
}

// The ICC profile's decision, or nullopt (with the reason in `notes`) when it cannot be used.
std::optional<SampleEncoding> FromIccProfile(const EncodingEvidence& evidence, std::string& notes) {
  const Profile profile = OpenProfile(evidence.icc_profile);
  if (!profile) {
    notes += "unreadable ICC profile ignored; ";
    return std::nullopt;
  }
  const std::string name = ProfileDescription(profile.get());
  const cmsColorSpaceSignature space = cmsGetColorSpace(profile.get());
  const bool rgb = space == cmsSigRgbData && evidence.channels >= 3;
  const bool grey = space == cmsSigGrayData && evidence.channels <= 2;
  if (!rgb && !grey) {
    notes += fmt::format("ICC profile '{}' does not fit {} channel(s), ignored; ", name,
                         evidence.channels);
    return std::nullopt;
  }
  if (rgb && IsPlainSrgb(profile.get())) {
    return Decided(Transfer::kSrgb, "icc-profile", fmt::format("sRGB ICC profile '{}'", name));
  }
  SampleEncoding encoding =
      Decided(Transfer::kIccProfile, "icc-profile", fmt::format("ICC profile '{}'", name));
  encoding.icc_profile = evidence.icc_profile;
  return encoding;
}

// oiio:ColorSpace names photomat understands; nullopt for others.
std::optional<SampleEncoding> FromOiioName(const std::string& name, const std::string& evidence) {
  std::string lower = name;
  std::transform(lower.begin(), lower.end(), lower.begin(),
                 [](unsigned char c) { return static_cast<char>(std::tolower(c)); });
  if (lower == "srgb") return Decided(Transfer::kSrgb, "oiio-colorspace", evidence);
  if (lower == "linear" || lower == "lin_srgb" || lower == "lin_rec709" ||
      lower == "scene_linear") {
    return Decided(Transfer::kLinear, "oiio-colorspace", evidence);
  }
  if (lower.rfind("gamma", 0) == 0) {
    char* end = nullptr;
    const double gamma = std::strtod(lower.c_str() + 5, &end);
    if (end != lower.c_str() + 5 && gamma > 0.1 && gamma < 10) {
      return FromGamma(gamma, "oiio-colorspace", evidence);
    }
  }
  return std::nullopt;
}

SampleEncoding DecideTransfer(const EncodingEvidence& evidence, std::optional<ColourSpace> untagged,
                              std::string& notes) {
  if (!evidence.icc_profile.empty()) {
    if (auto icc = FromIccProfile(evidence, notes)) return *icc;
  }
  if (evidence.floating_point) {
    return Decided(Transfer::kLinear, "default", "float samples are linear");
  }
  if (evidence.format == "raw") {
    return Decided(Transfer::kLinear, "camera-raw",
                   "LibRaw scene-linear output (raw:ColorSpace sRGB-linear)");
  }
  if (evidence.png_srgb_chunk) return Decided(Transfer::kSrgb, "png-srgb", "PNG sRGB chunk");
  if (evidence.png_gama) {
    return FromGamma(1.0 / *evidence.png_gama, "png-gama",
                     fmt::format("PNG gAMA {:.5f}", *evidence.png_gama));
  }
  if (evidence.exif_colour_space == 1) {
    return Decided(Transfer::kSrgb, "exif-colorspace", "EXIF ColorSpace 1 (sRGB)");
  }
  if (evidence.exif_colour_space) {
    notes += fmt::format("EXIF ColorSpace {} (uncalibrated); ", *evidence.exif_colour_space);
  }
  // PNG, JPEG and OpenEXR readers fill oiio:ColorSpace in when the file says nothing; a TIFF's
  // comes from its EXIF ColorSpace, taken above.
  const bool invented = evidence.format == "png" || evidence.format == "jpeg" ||
                        evidence.format == "openexr" ||
                        (evidence.format == "tiff" && evidence.exif_colour_space);
  if (!invented && !evidence.oiio_colour_space.empty()) {
    const std::string said = fmt::format("oiio:ColorSpace \"{}\"", evidence.oiio_colour_space);
    if (auto named = FromOiioName(evidence.oiio_colour_space, said)) return *named;
    notes += said + " not understood; ";
  }
  if (untagged) {
    return Decided(*untagged == ColourSpace::kSrgb ? Transfer::kSrgb : Transfer::kLinear,
                   "untagged-option",
                   fmt::format("untagged; colour_space \"{}\" given", ToString(*untagged)));
  }
  return evidence.bits_per_sample <= 8
             ? Decided(Transfer::kSrgb, "default", "untagged 8-bit: sRGB")
             : Decided(Transfer::kLinear, "default",
                       fmt::format("untagged {}-bit: linear", evidence.bits_per_sample));
}

}  // namespace

std::string SampleEncoding::Name() const {
  std::string name;
  switch (transfer) {
    case Transfer::kLinear:
      name = "linear";
      break;
    case Transfer::kSrgb:
      name = "srgb";
      break;
    case Transfer::kGamma:
      name = fmt::format("gamma {:.4g}", gamma);
      break;
    case Transfer::kIccProfile: {
      const Profile profile = OpenProfile(icc_profile);
      name = fmt::format("icc '{}'", profile ? ProfileDescription(profile.get()) : "?");
      break;
    }
  }
  if (to_rec709) name += " + chromaticities";
  return name;
}

ColourSpace SampleEncoding::Summary() const {
  return transfer == Transfer::kLinear ? ColourSpace::kLinear : ColourSpace::kSrgb;
}

void AddPngChunkEvidence(const fs::path& path, EncodingEvidence& evidence) {
  std::unique_ptr<std::FILE, int (*)(std::FILE*)> file(std::fopen(path.c_str(), "rb"),
                                                       &std::fclose);
  if (!file) return;
  png_byte signature[8] = {};
  if (std::fread(signature, 1, 8, file.get()) != 8 || png_sig_cmp(signature, 0, 8) != 0) return;
  png_structp png =
      png_create_read_struct(PNG_LIBPNG_VER_STRING, nullptr, AbandonPng, IgnorePngWarning);
  if (png == nullptr) return;
  png_infop info = png_create_info_struct(png);
  bool srgb = false, has_gama = false;
  png_fixed_point gama = 0;
  png_bytep profile = nullptr;
  png_uint_32 profile_size = 0;
  if (info != nullptr &&
      ReadPngColourChunks(png, info, file.get(), srgb, gama, has_gama, profile, profile_size)) {
    evidence.png_srgb_chunk = srgb;
    if (has_gama) evidence.png_gama = gama / 100000.0;
    if (profile != nullptr && profile_size > 0 && evidence.icc_profile.empty()) {
      evidence.icc_profile.assign(profile, profile + profile_size);
    }
  }
  png_destroy_read_struct(&png, info != nullptr ? &info : nullptr, nullptr);
}

SampleEncoding DecideSampleEncoding(const EncodingEvidence& evidence,
                                    std::optional<ColourSpace> untagged) {
  std::string notes;
  SampleEncoding encoding = DecideTransfer(evidence, untagged, notes);
  if (evidence.chromaticities && encoding.transfer != Transfer::kIccProfile) {
    const auto& c = *evidence.chromaticities;
    if (!IsRec709(c)) {
      encoding.to_rec709 = ChromaticitiesToRec709(c);
      notes += encoding.to_rec709
                   ? fmt::format("chromaticities {} converted to Rec.709; ", fmt::join(c, " "))
                   : fmt::format("degenerate chromaticities {} ignored; ", fmt::join(c, " "));
    }
  }
  if (!notes.empty()) {
    notes.resize(notes.size() - 2);
    encoding.evidence += "; " + notes;
  }
  return encoding;
}

std::vector<float> CodeToLightTable(const SampleEncoding& encoding, int bits) {
  const std::size_t codes = std::size_t{1} << bits;
  const double max = static_cast<double>(codes - 1);
  std::vector<float> table(codes);
  for (std::size_t code = 0; code < codes; ++code) {
    const double x = static_cast<double>(code) / max;
    double light = x;  // kLinear; kIccProfile's curves come with its matrix
    if (encoding.transfer == Transfer::kSrgb) light = SrgbToLinear(x);
    if (encoding.transfer == Transfer::kGamma) light = std::pow(x, encoding.gamma);
    table[code] = static_cast<float>(light);
  }
  return table;
}

float DecodeFloatSample(const SampleEncoding& encoding, float value) {
  switch (encoding.transfer) {
    case Transfer::kSrgb:
      return static_cast<float>(SrgbToLinear(value));
    case Transfer::kGamma:
      return value <= 0.0f ? 0.0f : static_cast<float>(std::pow(value, encoding.gamma));
    case Transfer::kLinear:
    case Transfer::kIccProfile:
      break;
  }
  return value;
}

void ApplyColourTransform(const SampleEncoding& encoding, ImageView image, const fs::path& file) {
  const int width = image.width();
  if (encoding.transfer == Transfer::kIccProfile) {
    const Profile in = OpenProfile(encoding.icc_profile);
    const bool rgb = in && cmsGetColorSpace(in.get()) == cmsSigRgbData && image.channels() >= 3;
    const Profile out = rgb ? LinearRec709Profile() : LinearGreyProfile();
    const cmsUInt32Number format = rgb ? TYPE_RGB_FLT : TYPE_GRAY_FLT;
    const Transform transform(in && out ? cmsCreateTransform(in.get(), format, out.get(), format,
                                                             INTENT_RELATIVE_COLORIMETRIC,
                                                             cmsFLAGS_NOCACHE)
                                        : nullptr);
    if (!transform) throw Error(file, "Little CMS cannot use the file's ICC profile");
    const int mixed = rgb ? 3 : 1;
    std::vector<float> in_row(static_cast<std::size_t>(width) * mixed), out_row(in_row.size());
    for (int y = 0; y < image.height(); ++y) {
      for (int c = 0; c < mixed; ++c) {
        const float* row = image.row(c, y).data();
        for (int x = 0; x < width; ++x) in_row[x * mixed + c] = row[x];
      }
      cmsDoTransform(transform.get(), in_row.data(), out_row.data(),
                     static_cast<cmsUInt32Number>(width));
      for (int c = 0; c < mixed; ++c) {
        float* row = image.row(c, y).data();
        for (int x = 0; x < width; ++x) row[x] = out_row[x * mixed + c];
      }
    }
    return;
  }
  if (!encoding.to_rec709 || image.channels() < 3) return;
  const std::array<double, 9>& m = *encoding.to_rec709;
  for (int y = 0; y < image.height(); ++y) {
    float* r = image.row(0, y).data();
    float* g = image.row(1, y).data();
    float* b = image.row(2, y).data();
    for (int x = 0; x < width; ++x) {
      const double in[3] = {r[x], g[x], b[x]};
      r[x] = static_cast<float>(m[0] * in[0] + m[1] * in[1] + m[2] * in[2]);
      g[x] = static_cast<float>(m[3] * in[0] + m[4] * in[1] + m[5] * in[2]);
      b[x] = static_cast<float>(m[6] * in[0] + m[7] * in[1] + m[8] * in[2]);
    }
  }
}

bool WarnIfEncodingsDisagree(const std::vector<ImageEncodingRecord>& records) {
  std::map<std::string, std::vector<std::string>> files_by_encoding;
  for (const ImageEncodingRecord& record : records) {
    files_by_encoding[record.encoding].push_back(record.file);
  }
  if (files_by_encoding.size() < 2) return false;
  std::string groups;
  for (const auto& [encoding, files] : files_by_encoding) {
    const std::size_t shown = std::min<std::size_t>(files.size(), 3);
    groups +=
        fmt::format("{}{}: {}{}", groups.empty() ? "" : "; ", encoding,
                    fmt::join(files.begin(), files.begin() + static_cast<long>(shown), ", "),
                    files.size() > shown ? fmt::format(" and {} more", files.size() - shown) : "");
  }
  spdlog::warn("the images of one set are decoded differently ({}); check their colour tags",
               groups);
  return true;
}

}  // namespace photomat
