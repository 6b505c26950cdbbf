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
#include <cstring>
#include <limits>
#include <set>
#include <string_view>
#include <utility>
#include <vector>

#include "core/atomic_file.h"
#include "core/cpu_dispatch.h"
#include "core/enum_names.h"
#include "core/error.h"
#include "core/image_band_io.h"
#include "core/jpeg_structure.h"
#include "core/text_parsing.h"

namespace photomat {
namespace {

namespace fs = std::filesystem;

// OpenImageIO's message on one line: a reader may append several (a truncated PNG: the read
// error, libpng's, then "PNG library error"), and photomat's errors are one line each.
std::string OiioError(const std::string& own) {
  const std::string message = own.empty() ? OIIO::geterror() : own;
  std::string joined;
  for (const std::string_view line : OIIO::Strutil::splitsv(message, "\n")) {
    const std::string_view trimmed = OIIO::Strutil::strip(line);
    if (trimmed.empty()) continue;
    if (!joined.empty()) joined += "; ";
    joined += trimmed;
  }
  return joined.empty() ? "unknown OpenImageIO error" : joined;
}

// Rows decoded per call for scanline files: a small interleaved buffer whose channels are then
// spread over the image's planes (OpenImageIO strides cannot express planar storage of several
// channels, and reading channel by channel would decode the file once per channel). Tiled files
// are read a row of tiles at a time.
constexpr int kChunkRows = 16;
// Rows per band of the writer for formats other than EXR.
constexpr int kBandRows = 64;

// Pixels of an interleaved row whose first `kept` channels include one at full scale. Most rows
// of a capture have no sample at full scale, and for those one pass over the row's bytes (memchr
// for 8 bits, a vectorised test for 16) replaces testing each pixel's channels: the test was a
// third of the decoding loop's instructions. A row whose every channel is kept is looked at
// whole; with a dropped alpha (at full scale in most files) the pixels are always tested.
template <typename T>
PHOTOMAT_HOT_LOOP std::size_t CountPixelsAtFullScale(const T* row, int width, int stride,
                                                     int kept) {
  constexpr T kMax = std::numeric_limits<T>::max();
  const std::size_t samples = static_cast<std::size_t>(width) * stride;
  if (kept == stride) {
    if constexpr (sizeof(T) == 1) {
      if (std::memchr(row, kMax, samples) == nullptr) return 0;
    } else {
      unsigned any = 0;
      for (std::size_t i = 0; i < samples; ++i) any |= row[i] == kMax ? 1u : 0u;
      if (any == 0) return 0;
    }
  }
  std::size_t saturated = 0;
  for (int x = 0; x < width; ++x) {
    const T* pixel = row + static_cast<std::size_t>(x) * stride;
    bool at_max = false;
    for (int c = 0; c < kept; ++c) at_max |= pixel[c] == kMax;
    saturated += at_max ? 1 : 0;
  }
  return saturated;
}

// Decodes one interleaved row of an 8- or 16-bit file into row `y` of `band`'s planes through
// the encoding's code -> light table; returns the pixels with a kept channel at the largest code
// (CountPixelsAtFullScale). kFileChannels and kKept fix the file's and the band's channel counts
// at compile time for the common layouts (RGB, RGBA without its alpha, grey), so that one pass
// over the pixels converts each sample with no inner loop (half the time of a pass per channel:
// decoding is a large share of a fit's CPU time); 0 reads the counts at run time.
template <int kFileChannels, int kKept, typename T>
PHOTOMAT_HOT_LOOP std::size_t DecodeIntegerRow(const T* row, int file_channels,
                                               const std::vector<float>& light_of_code,
                                               ImageView band, int y) {
  const int stride = kFileChannels > 0 ? kFileChannels : file_channels;
  const int kept = kKept > 0 ? kKept : band.channels();
  const int width = band.width();
  const float* table = light_of_code.data();
  if constexpr (kKept > 0) {
    float* out[kKept];
    for (int c = 0; c < kKept; ++c) out[c] = band.row(c, y).data();
    for (int x = 0; x < width; ++x) {
      const T* pixel = row + static_cast<std::size_t>(x) * stride;
      for (int c = 0; c < kKept; ++c) out[c][x] = table[pixel[c]];
    }
  } else {
    for (int c = 0; c < kept; ++c) {
      float* out = band.row(c, y).data();
      for (int x = 0; x < width; ++x) out[x] = table[row[x * stride + c]];
    }
  }
  return CountPixelsAtFullScale(row, width, stride, kept);
}

template <typename T>
std::size_t DecodeIntegerRow(const T* row, int file_channels,
                             const std::vector<float>& light_of_code, ImageView band, int y) {
  const int kept = band.channels();
  if (file_channels == 3 && kept == 3) {
    return DecodeIntegerRow<3, 3>(row, file_channels, light_of_code, band, y);
  }
  if (file_channels == 4 && kept == 3) {
    return DecodeIntegerRow<4, 3>(row, file_channels, light_of_code, band, y);
  }
  if (file_channels == 1 && kept == 1) {
    return DecodeIntegerRow<1, 1>(row, file_channels, light_of_code, band, y);
  }
  return DecodeIntegerRow<0, 0>(row, file_channels, light_of_code, band, y);
}

// Float, half and unusual integer widths, converted to float by OpenImageIO (integers to
// [0, 1]), then through the encoding's transfer curve; returns the number of non-finite samples.
std::size_t DecodeFloatRow(const float* row, int file_channels, const SampleEncoding& encoding,
                           ImageView band, int y) {
  const int width = band.width(), kept = band.channels();
  std::size_t non_finite = 0;
  for (int c = 0; c < kept; ++c) {
    float* out = band.row(c, y).data();
    for (int x = 0; x < width; ++x) {
      const float value = row[x * file_channels + c];
      if (!std::isfinite(value)) ++non_finite;
      out[x] = DecodeFloatSample(encoding, value);
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

// The file's encoding: the caller's override of integer codes, else decided from the file's
// metadata (core/sample_encoding, the one place of that decision).
SampleEncoding DecideEncoding(OIIO::ImageInput& input, const fs::path& path,
                              const ImageReadOptions& options) {
  if (!options.colour_space) {
    return DecideSampleEncoding(GatherEvidence(input, path), options.untagged_colour_space);
  }
  SampleEncoding encoding;
  const bool forced = !input.spec().format.is_floating_point();
  const ColourSpace space = forced ? *options.colour_space : ColourSpace::kLinear;
  encoding.transfer = space == ColourSpace::kSrgb ? Transfer::kSrgb : Transfer::kLinear;
  encoding.decided_by = forced ? "caller" : "default";
  encoding.evidence = forced ? "the reader asked for these codes" : "float samples are linear";
  return encoding;
}

}  // namespace

// The open file, its code -> light table (integer files) and one chunk of its interleaved
// samples, as 8-bit, 16-bit or float.
struct ImageBandReader::Decoder {
  std::unique_ptr<OIIO::ImageInput> input;
  OIIO::ImageSpec spec;
  OIIO::TypeDesc type;
  std::vector<float> light_of_code;
  int chunk_rows = kChunkRows;
  int chunk_first = 0;
  int chunk_count = 0;
  std::vector<std::byte> samples;

  std::size_t RowBytes() const {
    return static_cast<std::size_t>(spec.width) * spec.nchannels * type.size();
  }
  // Makes the chunk holding row `y` current.
  void Load(int y, const fs::path& path) {
    if (y >= chunk_first && y < chunk_first + chunk_count) return;
    chunk_first = y / chunk_rows * chunk_rows;
    chunk_count = std::min(chunk_rows, spec.height - chunk_first);
    samples.resize(RowBytes() * chunk_rows);
    const int y0 = spec.y + chunk_first, y1 = y0 + chunk_count;
    const bool ok = Read(y0, y1);
    if (!ok) {
      chunk_count = 0;
      throw Error(path, fmt::format("cannot decode image: {}", OiioError(input->geterror())));
    }
  }
  const std::byte* Row(int y) const { return samples.data() + RowBytes() * (y - chunk_first); }

 private:
  bool Read(int y0, int y1) {
    if (spec.tile_width > 0) {
      return input->read_tiles(0, 0, spec.x, spec.x + spec.width, y0, y1, spec.z, spec.z + 1, 0,
                               spec.nchannels, type, samples.data());
    }
    // Why not always read_scanlines: OpenImageIO 2.4's read_scanlines allocates (and frees) a
    // conversion buffer of about 64 MB on every call, whatever the rows asked for; a streamed
    // fit calls it thousands of times, and the fresh pages' faults and the unmaps were about a
    // tenth of a whole PTM fit's CPU time (perf, DiLiGenT cat). Samples already in the type we
    // want need no conversion, so they are read natively, straight into the chunk.
    if (spec.channelformats.empty() && spec.format == type) {
      return input->read_native_scanlines(0, 0, y0, y1, spec.z, samples.data());
    }
    return input->read_scanlines(0, 0, y0, y1, spec.z, 0, spec.nchannels, type, samples.data());
  }
};

ImageBandReader::ImageBandReader(const fs::path& path, const ImageReadOptions& options)
    : path_(path), decoder_(std::make_unique<Decoder>()) {
  std::error_code ec;
  if (!fs::exists(path, ec)) throw Error(path, "image file not found");
  OIIO::ImageSpec config = CameraRawConfig(options.camera_raw);
  // Photometric data drop alpha, and their colour samples are measurements: read them as stored.
  // OpenImageIO would otherwise multiply the colours of a file with unassociated alpha (PNG,
  // some TIFFs) by its alpha, silently scaling the light of every pixel whose alpha is below 1.
  // Readers that keep alpha (stacks, masks) keep OpenImageIO's associated convention, the one
  // its writers assume.
  if (!options.keep_alpha) config.attribute("oiio:UnassociatedAlpha", 1);
  decoder_->input = OIIO::ImageInput::open(path.string(), &config);
  if (!decoder_->input) throw Error(path, fmt::format("cannot read image: {}", OiioError("")));
  if (std::string_view(decoder_->input->format_name()) == "jpeg") CheckJpegIsWhole(path);
  const OIIO::ImageSpec& spec = decoder_->spec = decoder_->input->spec();
  if (spec.width <= 0 || spec.height <= 0 || spec.nchannels <= 0) {
    throw Error(path, "image has no pixels");
  }
  width_ = spec.width;
  height_ = spec.height;
  kept_ = spec.nchannels;
  if (!options.keep_alpha && spec.alpha_channel == spec.nchannels - 1 && spec.nchannels > 1) {
    kept_ = spec.nchannels - 1;
  }
  if (kept_ == spec.nchannels && !spec.channelnames.empty()) channel_names_ = spec.channelnames;
  const OIIO::TypeDesc format = spec.format;
  info_.floating_point = format.is_floating_point();
  info_.bits_per_sample = static_cast<int>(format.size() * 8);
  for (const auto& attribute : spec.extra_attribs) {
    if (attribute.type() == OIIO::TypeString) {
      info_.attributes[attribute.name().string()] = attribute.get_string();
    }
  }
  // Decided once, when the file is opened; every band is converted by the same decision.
  info_.encoding = DecideEncoding(*decoder_->input, path, options);
  info_.colour_space = info_.encoding.Summary();
  const bool integer = !info_.floating_point && (format.basetype == OIIO::TypeDesc::UINT8 ||
                                                 format.basetype == OIIO::TypeDesc::UINT16);
  if (integer) {
    const bool eight_bit = format.basetype == OIIO::TypeDesc::UINT8;
    decoder_->type = eight_bit ? OIIO::TypeDesc::UINT8 : OIIO::TypeDesc::UINT16;
    decoder_->light_of_code = CodeToLightTable(info_.encoding, eight_bit ? 8 : 16);
  } else {
    decoder_->type = OIIO::TypeDesc::FLOAT;
  }
  const int tile = spec.tile_height;
  decoder_->chunk_rows = tile > 0 ? std::max(1, kChunkRows / tile) * tile : kChunkRows;
}

ImageBandReader::ImageBandReader() = default;
ImageBandReader::~ImageBandReader() = default;
ImageBandReader::ImageBandReader(ImageBandReader&&) noexcept = default;
ImageBandReader& ImageBandReader::operator=(ImageBandReader&&) noexcept = default;

void ImageBandReader::ReadNext(ImageView band) {
  if (band.width() != width_ || band.channels() != kept_ || band.height() > height_ - next_row_) {
    throw Error(path_, fmt::format("cannot read rows {}..{} of a {}x{} image with {} channels "
                                   "into a {}x{} band of {}",
                                   next_row_, next_row_ + band.height(), width_, height_, kept_,
                                   band.width(), band.height(), band.channels()));
  }
  const int file_channels = decoder_->spec.nchannels;
  const std::vector<float>& table = decoder_->light_of_code;
  std::size_t non_finite = 0;
  for (int r = 0; r < band.height(); ++r) {
    const int y = next_row_ + r;
    decoder_->Load(y, path_);
    const std::byte* row = decoder_->Row(y);
    if (decoder_->type == OIIO::TypeDesc::UINT8) {
      info_.saturated_pixels += DecodeIntegerRow(reinterpret_cast<const std::uint8_t*>(row),
                                                 file_channels, table, band, r);
    } else if (decoder_->type == OIIO::TypeDesc::UINT16) {
      info_.saturated_pixels += DecodeIntegerRow(reinterpret_cast<const std::uint16_t*>(row),
                                                 file_channels, table, band, r);
    } else {
      non_finite += DecodeFloatRow(reinterpret_cast<const float*>(row), file_channels,
                                   info_.encoding, band, r);
    }
  }
  next_row_ += band.height();
  if (non_finite > 0) {
    throw Error(path_, fmt::format("{} sample(s) are NaN or infinite", non_finite));
  }
  // The ICC transform and the chromaticities matrix act on each pixel alone: band-local.
  ApplyColourTransform(info_.encoding, band, path_);
}

LoadedImage ReadImage(const fs::path& path, const ImageReadOptions& options) {
  ImageBandReader reader(path, options);
  LoadedImage result;
  result.image = Image(reader.width(), reader.height(), reader.channels());
  reader.ReadNext(result.image.View());
  if (!reader.channel_names().empty()) result.image.set_channel_names(reader.channel_names());
  result.info = reader.info();
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

// The open output and the interleaved buffer of one write call.
struct ImageBandWriter::Encoder {
  std::unique_ptr<OIIO::ImageOutput> output;
  bool integer = false;
  int band_rows = kBandRows;
  std::vector<float> band;
};

ImageBandWriter::ImageBandWriter(const fs::path& path, int width, int height,
                                 std::vector<std::string> channel_names,
                                 const ImageWriteOptions& options)
    : file_(path),
      encoder_(std::make_unique<Encoder>()),
      width_(width),
      height_(height),
      channels_(static_cast<int>(channel_names.size())),
      options_(options) {
  if (width <= 0 || height <= 0 || channels_ <= 0) {
    throw Error(path, "cannot write an empty image");
  }
  encoder_->integer =
      options.sample_type == SampleType::kUint8 || options.sample_type == SampleType::kUint16;
  const bool exr = LowerExtension(path) == ".exr";
  const int threads = AllowedThreads();
  if (exr) LimitOpenImageIoThreads(threads);
  encoder_->output = OIIO::ImageOutput::create(path.string());
  if (!encoder_->output) {
    throw Error(path, fmt::format("no image writer for this extension: {}", OiioError("")));
  }
  OIIO::ImageSpec spec(width, height, channels_, ToOiio(options.sample_type));
  spec.channelnames = std::move(channel_names);
  spec.alpha_channel = -1;
  if (encoder_->integer) {
    spec.attribute("oiio:ColorSpace", options.encoding == ColourSpace::kSrgb ? "sRGB" : "Linear");
  }
  for (const auto& [name, value] : options.attributes) spec.attribute(name, value);
  // After the attributes: a "compression" copied from a file read earlier does not override.
  spec.attribute("compression",
                 exr ? std::string(ToString(options.exr_compression)) : std::string("zip"));
  if (!encoder_->output->open(file_.temp().string(), spec)) {
    throw Error(path, fmt::format("cannot write: {}", OiioError(encoder_->output->geterror())));
  }
  const std::size_t row_values = static_cast<std::size_t>(width) * channels_;
  encoder_->band_rows = std::min(
      height, WriteBandRows(exr, options.exr_compression, threads, row_values * sizeof(float)));
}

ImageBandWriter::~ImageBandWriter() = default;

void ImageBandWriter::WriteNext(ConstImageView image) {
  const fs::path& path = file_.path();
  if (!encoder_->output || image.width() != width_ || image.channels() != channels_ ||
      image.height() > height_ - next_row_) {
    throw Error(path, fmt::format("cannot write {} rows of {}x{} with {} channels after row {} "
                                  "of a {}x{} image with {}",
                                  image.height(), image.width(), image.height(), image.channels(),
                                  next_row_, width_, height_, channels_));
  }
  if (encoder_->integer) {
    for (int c = 0; c < channels_; ++c) {
      for (int y = 0; y < image.height(); ++y) {
        const auto row = image.row(c, y);
        if (std::any_of(row.begin(), row.end(), [](float v) { return !std::isfinite(v); })) {
          throw Error(path, "cannot store NaN or infinite values in an integer image");
        }
      }
    }
  }
  // Band by band: the planes of a band interleaved (and, for integer files, encoded) into a
  // bounded buffer, which OpenImageIO converts to the file's sample type (WriteBandRows).
  const int width = width_, channels = channels_;
  const std::size_t row_values = static_cast<std::size_t>(width) * channels;
  std::vector<float>& band = encoder_->band;
  band.resize(static_cast<std::size_t>(std::min(encoder_->band_rows, image.height())) * row_values);
  for (int first = 0; first < image.height(); first += encoder_->band_rows) {
    const int count = std::min(encoder_->band_rows, image.height() - first);
    for (int r = 0; r < count; ++r) {
      float* row = band.data() + static_cast<std::size_t>(r) * row_values;
      for (int c = 0; c < channels; ++c) {
        const float* in = image.row(c, first + r).data();
        if (encoder_->integer) {
          for (int x = 0; x < width; ++x) {
            row[x * channels + c] = PrepareForQuantising(in[x], options_.encoding);
          }
        } else {
          for (int x = 0; x < width; ++x) row[x * channels + c] = in[x];
        }
      }
    }
    const int y = next_row_ + first;
    if (!encoder_->output->write_scanlines(y, y + count, 0, OIIO::TypeDesc::FLOAT, band.data())) {
      throw Error(path, fmt::format("cannot write: {}", OiioError(encoder_->output->geterror())));
    }
  }
  next_row_ += image.height();
  file_.StartWriteback();  // the disk writes while the next band is fitted
}

void ImageBandWriter::Commit(const std::function<void(const fs::path& temp)>& before_rename) {
  const fs::path& path = file_.path();
  if (next_row_ != height_) {
    throw Error(path, fmt::format("cannot finish: {} of {} rows written", next_row_, height_));
  }
  const bool closed = encoder_->output->close();
  const std::string error = closed ? std::string() : OiioError(encoder_->output->geterror());
  encoder_->output.reset();
  if (!closed) throw Error(path, fmt::format("cannot write: {}", error));
  if (before_rename) before_rename(file_.temp());
  file_.Commit();
}

void WriteImage(const fs::path& path, const Image& image, const ImageWriteOptions& options) {
  if (image.empty()) throw Error(path, "cannot write an empty image");
  if (image.depth() != 1) {
    throw Error(path, fmt::format("cannot write a {} image as one picture (a solid texture is "
                                  "written as a volume)",
                                  ToString(image.extent())));
  }
  try {
    ImageBandWriter writer(path, image.width(), image.height(),
                           image.channel_names().empty() ? DefaultChannelNames(image.channels())
                                                         : image.channel_names(),
                           options);
    writer.WriteNext(image.View());
    writer.Commit();
  } catch (const Error& error) {
    throw error.InFile(path);
  } catch (const std::exception& error) {
    throw Error(path, fmt::format("cannot write: {}", error.what()));
  }
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
