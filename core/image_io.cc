#include "core/image_io.h"

#include <OpenImageIO/imageio.h>
#include <OpenImageIO/strutil.h>
#include <fmt/format.h>
#include <tbb/global_control.h>
#include <tbb/task_arena.h>

#include <algorithm>
#include <array>
#include <cctype>
#include <cmath>
#include <cstdint>
#include <limits>
#include <set>
#include <string_view>
#include <utility>
#include <vector>

#include "core/atomic_file.h"
#include "core/enum_names.h"
#include "core/error.h"
#include "core/text_parsing.h"

namespace photomat {
namespace {

namespace fs = std::filesystem;

std::string OiioError(const std::string& own) {
  std::string message = own.empty() ? OIIO::geterror() : own;
  while (!message.empty() && (message.back() == '\n' || message.back() == ' ')) {
    message.pop_back();
  }
  return message.empty() ? "unknown OpenImageIO error" : message;
}

// Rows decoded per call: files are read band by band into a small interleaved buffer whose
// channels are then spread over the image's planes (OpenImageIO strides cannot express planar
// storage of several channels, and reading channel by channel would decode the file once per
// channel). Tiled files are read a row of tiles at a time.
constexpr int kBandRows = 64;

// Reads rows [first, first + count) of the file's first subimage, every channel, as `type`.
class BandReader {
 public:
  BandReader(OIIO::ImageInput& input, const fs::path& path) : input_(input), path_(path) {}

  int band_rows() const {
    const int tile = input_.spec().tile_height;
    return tile > 0 ? std::max(1, kBandRows / tile) * tile : kBandRows;
  }
  void Read(int first, int count, OIIO::TypeDesc type, void* data) const {
    const OIIO::ImageSpec& spec = input_.spec();
    const int y0 = spec.y + first, y1 = spec.y + first + count;
    const bool ok =
        spec.tile_width > 0
            ? input_.read_tiles(0, 0, spec.x, spec.x + spec.width, y0, y1, spec.z, spec.z + 1, 0,
                                spec.nchannels, type, data)
            : input_.read_scanlines(0, 0, y0, y1, spec.z, 0, spec.nchannels, type, data);
    if (!ok) {
      throw Error(path_, fmt::format("cannot decode image: {}", OiioError(input_.geterror())));
    }
  }

 private:
  OIIO::ImageInput& input_;
  const fs::path& path_;
};

// Decodes an 8- or 16-bit file band by band into the planes of `image`, counting the pixels with
// a kept channel at the largest code.
template <typename T>
void ReadIntegerSamples(const BandReader& reader, int file_channels,
                        const std::vector<float>& light_of_code, Image& image,
                        ImageFileInfo& info) {
  constexpr T kMax = std::numeric_limits<T>::max();
  const int width = image.width(), kept = image.channels();
  const int band = reader.band_rows();
  std::vector<T> samples(static_cast<std::size_t>(band) * width * file_channels);
  for (int first = 0; first < image.height(); first += band) {
    const int count = std::min(band, image.height() - first);
    reader.Read(first, count, OIIO::BaseTypeFromC<T>::value, samples.data());
    for (int r = 0; r < count; ++r) {
      const T* row = samples.data() + static_cast<std::size_t>(r) * width * file_channels;
      for (int c = 0; c < kept; ++c) {
        float* out = image.row(c, first + r).data();
        for (int x = 0; x < width; ++x) out[x] = light_of_code[row[x * file_channels + c]];
      }
      for (int x = 0; x < width; ++x) {
        const T* pixel = row + static_cast<std::size_t>(x) * file_channels;
        if (std::find(pixel, pixel + kept, kMax) != pixel + kept) ++info.saturated_pixels;
      }
    }
  }
}

// Float, half and unusual integer widths: OpenImageIO converts to float (integers to [0, 1]).
// Returns the number of non-finite samples.
std::size_t ReadFloatSamples(const BandReader& reader, int file_channels,
                             const SampleEncoding& encoding, Image& image) {
  const int width = image.width(), kept = image.channels();
  const int band = reader.band_rows();
  std::vector<float> samples(static_cast<std::size_t>(band) * width * file_channels);
  std::size_t non_finite = 0;
  for (int first = 0; first < image.height(); first += band) {
    const int count = std::min(band, image.height() - first);
    reader.Read(first, count, OIIO::TypeDesc::FLOAT, samples.data());
    for (int r = 0; r < count; ++r) {
      const float* row = samples.data() + static_cast<std::size_t>(r) * width * file_channels;
      for (int c = 0; c < kept; ++c) {
        float* out = image.row(c, first + r).data();
        for (int x = 0; x < width; ++x) {
          const float value = row[x * file_channels + c];
          if (!std::isfinite(value)) ++non_finite;
          out[x] = DecodeFloatSample(encoding, value);
        }
      }
    }
  }
  return non_finite;
}

// LibRaw's settings for scene-linear output (CameraRawOptions). Other readers ignore "raw:" keys,
// so every file is opened with them.
OIIO::ImageSpec CameraRawConfig(const CameraRawOptions& options) {
  OIIO::ImageSpec config;
  config.attribute("raw:ColorSpace", "sRGB-linear");
  config.attribute("raw:auto_bright", 0);
  config.attribute("raw:adjust_maximum_thr", 0.0f);
  config.attribute("raw:Demosaic", options.demosaic);
  config.attribute("raw:HighlightMode", 0);  // clip: saturated pixels stay at full scale
  if (options.white_balance) {
    config.attribute("raw:use_camera_wb", 0);
    config.attribute("raw:user_mul", OIIO::TypeDesc(OIIO::TypeDesc::FLOAT, 4),
                     options.white_balance->data());
  } else {
    config.attribute("raw:use_camera_wb", 1);
  }
  return config;
}

// What the file says about its encoding: OpenImageIO's metadata and, for PNG, the chunks.
EncodingEvidence GatherEvidence(OIIO::ImageInput& input, const fs::path& path) {
  const OIIO::ImageSpec& spec = input.spec();
  EncodingEvidence evidence;
  evidence.format = input.format_name();
  evidence.bits_per_sample = static_cast<int>(spec.format.size() * 8);
  evidence.floating_point = spec.format.is_floating_point();
  evidence.channels = spec.nchannels;
  if (const OIIO::ParamValue* icc = spec.find_attribute("ICCProfile");
      icc != nullptr && icc->type().basetype == OIIO::TypeDesc::UINT8) {
    const auto* bytes = static_cast<const unsigned char*>(icc->data());
    evidence.icc_profile.assign(bytes, bytes + icc->type().size());
  }
  if (const OIIO::ParamValue* exif = spec.find_attribute("Exif:ColorSpace")) {
    evidence.exif_colour_space = exif->get_int();
  }
  evidence.oiio_colour_space = spec.get_string_attribute("oiio:ColorSpace");
  if (const OIIO::ParamValue* c =
          spec.find_attribute("chromaticities", OIIO::TypeDesc(OIIO::TypeDesc::FLOAT, 8))) {
    std::array<float, 8> values{};
    const auto* floats = static_cast<const float*>(c->data());
    std::copy(floats, floats + 8, values.begin());
    evidence.chromaticities = values;
  }
  if (evidence.format == "png") AddPngChunkEvidence(path, evidence);
  return evidence;
}

}  // namespace

LoadedImage ReadImage(const fs::path& path, const ImageReadOptions& options) {
  std::error_code ec;
  if (!fs::exists(path, ec)) throw Error(path, "image file not found");
  const OIIO::ImageSpec config = CameraRawConfig(options.camera_raw);
  auto input = OIIO::ImageInput::open(path.string(), &config);
  if (!input) throw Error(path, fmt::format("cannot read image: {}", OiioError("")));
  const OIIO::ImageSpec spec = input->spec();
  if (spec.width <= 0 || spec.height <= 0 || spec.nchannels <= 0) {
    throw Error(path, "image has no pixels");
  }
  int kept = spec.nchannels;
  if (!options.keep_alpha && spec.alpha_channel == spec.nchannels - 1 && spec.nchannels > 1) {
    kept = spec.nchannels - 1;
  }

  LoadedImage result;
  ImageFileInfo& info = result.info;
  const OIIO::TypeDesc format = spec.format;
  info.floating_point = format.is_floating_point();
  info.bits_per_sample = static_cast<int>(format.size() * 8);
  for (const auto& attribute : spec.extra_attribs) {
    if (attribute.type() == OIIO::TypeString) {
      info.attributes[attribute.name().string()] = attribute.get_string();
    }
  }
  result.image = Image(spec.width, spec.height, kept);
  if (kept == spec.nchannels && !spec.channelnames.empty()) {
    result.image.set_channel_names(spec.channelnames);
  }

  if (options.colour_space) {
    const bool forced = !info.floating_point;
    const ColourSpace space = forced ? *options.colour_space : ColourSpace::kLinear;
    info.encoding.transfer = space == ColourSpace::kSrgb ? Transfer::kSrgb : Transfer::kLinear;
    info.encoding.decided_by = forced ? "caller" : "default";
    info.encoding.evidence =
        forced ? "the reader asked for these codes" : "float samples are linear";
  } else {
    info.encoding =
        DecideSampleEncoding(GatherEvidence(*input, path), options.untagged_colour_space);
  }
  info.colour_space = info.encoding.Summary();

  const BandReader reader(*input, path);
  if (!info.floating_point &&
      (format.basetype == OIIO::TypeDesc::UINT8 || format.basetype == OIIO::TypeDesc::UINT16)) {
    const bool eight_bit = format.basetype == OIIO::TypeDesc::UINT8;
    const std::vector<float> light_of_code = CodeToLightTable(info.encoding, eight_bit ? 8 : 16);
    if (eight_bit) {
      ReadIntegerSamples<std::uint8_t>(reader, spec.nchannels, light_of_code, result.image, info);
    } else {
      ReadIntegerSamples<std::uint16_t>(reader, spec.nchannels, light_of_code, result.image, info);
    }
  } else {
    const std::size_t non_finite =
        ReadFloatSamples(reader, spec.nchannels, info.encoding, result.image);
    if (non_finite > 0) {
      throw Error(path, fmt::format("{} sample(s) are NaN or infinite", non_finite));
    }
  }
  ApplyColourTransform(info.encoding, result.image, path);
  input->close();
  return result;
}

Mask ReadMask(const fs::path& path) {
  ImageReadOptions options;
  options.colour_space = ColourSpace::kLinear;  // thresholding codes, not light
  options.keep_alpha = true;
  const Image image = ReadImage(path, options).image;
  Mask mask(image.width(), image.height(), false);
  for (int c = 0; c < image.channels(); ++c) {
    const std::span<const float> plane = image.plane(c);
    for (std::size_t p = 0; p < plane.size(); ++p) {
      if (plane[p] > 0.5f) mask.Set(p, true);
    }
  }
  return mask;
}

namespace {

OIIO::TypeDesc ToOiio(SampleType type) {
  switch (type) {
    case SampleType::kUint8:
      return OIIO::TypeDesc::UINT8;
    case SampleType::kUint16:
      return OIIO::TypeDesc::UINT16;
    case SampleType::kHalf:
      return OIIO::TypeDesc::HALF;
    case SampleType::kFloat:
      break;
  }
  return OIIO::TypeDesc::FLOAT;
}

std::vector<std::string> DefaultChannelNames(int channels) {
  switch (channels) {
    case 1:
      return {"Y"};
    case 2:
      return {"Y", "A"};
    case 3:
      return {"R", "G", "B"};
    case 4:
      return {"R", "G", "B", "A"};
    default:
      break;
  }
  std::vector<std::string> names;
  for (int c = 0; c < channels; ++c) names.push_back(fmt::format("channel{}", c));
  return names;
}

constexpr std::array<NamedValue<ExrCompression>, 5> kExrCompressionNames = {
    {{ExrCompression::kNone, "none"},
     {ExrCompression::kRle, "rle"},
     {ExrCompression::kZips, "zips"},
     {ExrCompression::kZip, "zip"},
     {ExrCompression::kPiz, "piz"}}};

// Scanlines per compressed chunk (OpenEXR's fixed block heights).
int ExrChunkLines(ExrCompression compression) {
  switch (compression) {
    case ExrCompression::kZip:
      return 16;
    case ExrCompression::kPiz:
      return 32;
    case ExrCompression::kNone:
    case ExrCompression::kRle:
    case ExrCompression::kZips:
      break;
  }
  return 1;
}

// The threads TBB lets the calling code use: the process's tbb::global_control limit (photomat's
// --threads, tests' limits) and the arena the caller runs in.
int AllowedThreads() {
  const int limit = static_cast<int>(
      tbb::global_control::active_value(tbb::global_control::max_allowed_parallelism));
  return std::max(1, std::min(limit, tbb::this_task_arena::max_concurrency()));
}

// OpenImageIO's thread counts are process-wide attributes (its own "threads" for format
// conversion, "exr_threads" for OpenEXR's compression pool, applied when the next EXR reader or
// writer is created). This is the one place photomat sets them, before every EXR write, so that
// OpenEXR's pool has as many compressing workers as the caller's TBB limit allows (the calling
// thread meanwhile only writes finished chunks out). OpenImageIO guards its attributes with a
// lock and resizes OpenEXR's pool only when the count changes.
void LimitOpenImageIoThreads(int threads) {
  OIIO::attribute("threads", threads);
  OIIO::attribute("exr_threads", threads);
}

// Rows handed to OpenImageIO per write call. EXR: whole compression chunks, at least
// kExrChunksPerThread per thread so that OpenEXR's pool compresses them in parallel, and
// otherwise as many rows as fit in kExrBandBytes. The interleaved temporary is therefore at most
// max(kExrBandBytes, threads * kExrChunksPerThread * chunk rows * row bytes), never the whole
// image of a tall file (a 612-wide 18-channel float stack: 16 MiB = 380 rows, 368 written per
// call with zip's 16-row chunks). Other formats: kBandRows.
constexpr std::size_t kExrBandBytes = std::size_t{16} << 20;
constexpr int kExrChunksPerThread = 4;

int WriteBandRows(bool exr, ExrCompression compression, int threads, std::size_t row_bytes) {
  if (!exr) return kBandRows;
  const int chunk = ExrChunkLines(compression);
  const std::size_t fitting_chunks = kExrBandBytes / std::max<std::size_t>(row_bytes, 1) / chunk;
  const int chunks = static_cast<int>(std::min<std::size_t>(fitting_chunks, 1 << 20));
  return std::max(chunks, threads * kExrChunksPerThread) * chunk;
}

// Integer outputs: the values as they will be quantised (encoded and clamped).
float PrepareForQuantising(float value, ColourSpace encoding) {
  return encoding == ColourSpace::kSrgb ? static_cast<float>(LinearToSrgb(value))
                                        : std::clamp(value, 0.0f, 1.0f);
}

}  // namespace

void WriteImage(const fs::path& path, const Image& image, const ImageWriteOptions& options) {
  if (image.empty()) throw Error(path, "cannot write an empty image");
  if (image.depth() != 1) {
    throw Error(path, fmt::format("cannot write a {} image as one picture (a solid texture is "
                                  "written as a volume)",
                                  ToString(image.extent())));
  }
  const bool integer =
      options.sample_type == SampleType::kUint8 || options.sample_type == SampleType::kUint16;
  if (integer) {
    const auto values = image.values();
    if (std::any_of(values.begin(), values.end(), [](float v) { return !std::isfinite(v); })) {
      throw Error(path, "cannot store NaN or infinite values in an integer image");
    }
  }

  const bool exr = LowerExtension(path) == ".exr";
  const int threads = AllowedThreads();
  if (exr) LimitOpenImageIoThreads(threads);
  WriteFileAtomically(path, [&](const fs::path& temp) {
    auto output = OIIO::ImageOutput::create(path.string());
    if (!output) {
      throw Error(path, fmt::format("no image writer for this extension: {}", OiioError("")));
    }
    OIIO::ImageSpec spec(image.width(), image.height(), image.channels(),
                         ToOiio(options.sample_type));
    spec.channelnames = image.channel_names().empty() ? DefaultChannelNames(image.channels())
                                                      : image.channel_names();
    spec.alpha_channel = -1;
    if (integer) {
      spec.attribute("oiio:ColorSpace", options.encoding == ColourSpace::kSrgb ? "sRGB" : "Linear");
    }
    for (const auto& [name, value] : options.attributes) spec.attribute(name, value);
    // After the attributes: a "compression" copied from a file read earlier does not override.
    spec.attribute("compression",
                   exr ? std::string(ToString(options.exr_compression)) : std::string("zip"));
    if (!output->open(temp.string(), spec)) {
      throw Error(path, fmt::format("cannot write: {}", OiioError(output->geterror())));
    }
    // Band by band: the planes of a band interleaved (and, for integer files, encoded) into a
    // bounded buffer, which OpenImageIO converts to the file's sample type (WriteBandRows).
    const int width = image.width(), channels = image.channels();
    const std::size_t row_values = static_cast<std::size_t>(width) * channels;
    const int band_rows =
        std::min(image.height(),
                 WriteBandRows(exr, options.exr_compression, threads, row_values * sizeof(float)));
    std::vector<float> band(static_cast<std::size_t>(band_rows) * row_values);
    for (int first = 0; first < image.height(); first += band_rows) {
      const int count = std::min(band_rows, image.height() - first);
      for (int r = 0; r < count; ++r) {
        float* row = band.data() + static_cast<std::size_t>(r) * width * channels;
        for (int c = 0; c < channels; ++c) {
          const float* in = image.row(c, first + r).data();
          if (integer) {
            for (int x = 0; x < width; ++x) {
              row[x * channels + c] = PrepareForQuantising(in[x], options.encoding);
            }
          } else {
            for (int x = 0; x < width; ++x) row[x * channels + c] = in[x];
          }
        }
      }
      if (!output->write_scanlines(first, first + count, 0, OIIO::TypeDesc::FLOAT, band.data())) {
        throw Error(path, fmt::format("cannot write: {}", OiioError(output->geterror())));
      }
    }
    if (!output->close()) {
      throw Error(path, fmt::format("cannot write: {}", OiioError(output->geterror())));
    }
  });
}

std::string_view ToString(ExrCompression compression) {
  return NameOf(compression, kExrCompressionNames);
}

ExrCompression ParseExrCompression(std::string_view name) {
  return ValueNamed(name, kExrCompressionNames, "EXR compression");
}

void WriteMask(const fs::path& path, const Mask& mask) {
  Image image(mask.width(), mask.height(), 1);
  const std::span<float> plane = image.plane(0);
  for (std::size_t p = 0; p < mask.pixel_count(); ++p) plane[p] = mask[p] ? 1.0f : 0.0f;
  ImageWriteOptions options;
  options.sample_type = SampleType::kUint8;
  WriteImage(path, image, options);
}

namespace {

// OpenImageIO's "extension_list": "tiff:tif,tiff;png:png;...". The "null" plugin's extension
// names no image format.
std::set<std::string> ReadableExtensions() {
  std::string list;
  OIIO::getattribute("extension_list", list);
  std::set<std::string> extensions;
  for (std::string_view format_entry : OIIO::Strutil::splitsv(list, ";")) {
    const std::size_t colon = format_entry.find(':');
    if (colon == std::string_view::npos || format_entry.substr(0, colon) == "null") continue;
    for (std::string_view extension : OIIO::Strutil::splitsv(format_entry.substr(colon + 1), ",")) {
      std::string dotted = ".";  // (not "." + ...: GCC 12 warns falsely, -Wrestrict)
      dotted += OIIO::Strutil::lower(extension);
      extensions.insert(std::move(dotted));
    }
  }
  return extensions;
}

// Whether `path`'s extension, in lower case, is one of `extensions` (".png", ...).
bool HasExtensionIn(const std::filesystem::path& path, const std::set<std::string>& extensions) {
  return extensions.count(LowerExtension(path)) > 0;
}

}  // namespace

bool IsReadableImageFileName(const std::filesystem::path& path) {
  return HasExtensionIn(path, ReadableExtensions());
}

bool NaturalLess(std::string_view a, std::string_view b) {
  const auto is_digit = [](char c) { return std::isdigit(static_cast<unsigned char>(c)) != 0; };
  std::size_t i = 0, j = 0;
  while (i < a.size() && j < b.size()) {
    if (is_digit(a[i]) && is_digit(b[j])) {
      std::size_t i_end = i, j_end = j;
      while (i_end < a.size() && is_digit(a[i_end])) ++i_end;
      while (j_end < b.size() && is_digit(b[j_end])) ++j_end;
      // Without leading zeros, a shorter run is a smaller number; equal lengths compare as text.
      std::string_view x = a.substr(i, i_end - i), y = b.substr(j, j_end - j);
      x.remove_prefix(std::min(x.find_first_not_of('0'), x.size()));
      y.remove_prefix(std::min(y.find_first_not_of('0'), y.size()));
      if (x.size() != y.size()) return x.size() < y.size();
      if (x != y) return x < y;
      i = i_end, j = j_end;
      continue;
    }
    if (a[i] != b[j]) return a[i] < b[j];
    ++i, ++j;
  }
  return a.size() - i < b.size() - j;
}

std::vector<std::filesystem::path> ListImageFiles(const std::filesystem::path& folder) {
  std::error_code error;
  if (!std::filesystem::is_directory(folder, error)) throw Error(folder, "not a folder");
  const std::set<std::string> extensions = ReadableExtensions();  // parsed once per listing
  std::vector<std::filesystem::path> files;
  for (std::filesystem::directory_iterator entry(folder, error), end; !error && entry != end;
       entry.increment(error)) {
    std::error_code entry_error;  // a dangling link is not an image, nor a reason to stop
    if (entry->is_regular_file(entry_error) && HasExtensionIn(entry->path(), extensions)) {
      files.push_back(entry->path());
    }
  }
  if (error) throw Error(folder, fmt::format("cannot list the folder: {}", error.message()));
  std::sort(files.begin(), files.end(), [](const auto& x, const auto& y) {
    return NaturalLess(x.filename().string(), y.filename().string());
  });
  return files;
}

}  // namespace photomat
