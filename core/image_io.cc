#include "core/image_io.h"

#include <OpenImageIO/imageio.h>
#include <OpenImageIO/strutil.h>
#include <fmt/format.h>

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
#include "core/error.h"

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

// 256-entry decoding table: exact for every 8-bit code.
const std::array<float, 256>& Srgb8ToLinearTable() {
  static const std::array<float, 256> table = [] {
    std::array<float, 256> t{};
    for (int i = 0; i < 256; ++i) t[i] = static_cast<float>(SrgbToLinear(i / 255.0));
    return t;
  }();
  return table;
}

template <typename T>
void ConvertIntegerSamples(const std::vector<T>& samples, int channels, int kept_channels,
                           ColourSpace space, Image& image, ImageFileInfo& info) {
  constexpr T kMax = std::numeric_limits<T>::max();
  constexpr double kScale = 1.0 / static_cast<double>(kMax);
  const auto& table = Srgb8ToLinearTable();
  std::span<float> out = image.values();
  const std::size_t pixels = image.pixel_count();
  for (std::size_t p = 0; p < pixels; ++p) {
    bool saturated = false;
    for (int c = 0; c < kept_channels; ++c) {
      const T code = samples[p * channels + c];
      saturated |= code == kMax;
      float value;
      if (space == ColourSpace::kLinear) {
        value = static_cast<float>(code * kScale);
      } else if constexpr (sizeof(T) == 1) {
        value = table[code];
      } else {
        value = static_cast<float>(SrgbToLinear(code * kScale));
      }
      out[p * kept_channels + c] = value;
    }
    if (saturated) ++info.saturated_pixels;
  }
}

}  // namespace

LoadedImage ReadImage(const fs::path& path, const ImageReadOptions& options) {
  std::error_code ec;
  if (!fs::exists(path, ec)) throw Error(path, "image file not found");
  auto input = OIIO::ImageInput::open(path.string());
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

  const auto pixels = static_cast<std::size_t>(spec.width) * spec.height;
  const auto read = [&](OIIO::TypeDesc type, void* data) {
    if (!input->read_image(0, 0, 0, spec.nchannels, type, data)) {
      throw Error(path, fmt::format("cannot decode image: {}", OiioError(input->geterror())));
    }
  };
  if (!info.floating_point &&
      (format.basetype == OIIO::TypeDesc::UINT8 || format.basetype == OIIO::TypeDesc::UINT16)) {
    const bool eight_bit = format.basetype == OIIO::TypeDesc::UINT8;
    info.colour_space =
        options.colour_space.value_or(eight_bit ? ColourSpace::kSrgb : ColourSpace::kLinear);
    if (eight_bit) {
      std::vector<std::uint8_t> samples(pixels * spec.nchannels);
      read(OIIO::TypeDesc::UINT8, samples.data());
      ConvertIntegerSamples(samples, spec.nchannels, kept, info.colour_space, result.image, info);
    } else {
      std::vector<std::uint16_t> samples(pixels * spec.nchannels);
      read(OIIO::TypeDesc::UINT16, samples.data());
      ConvertIntegerSamples(samples, spec.nchannels, kept, info.colour_space, result.image, info);
    }
  } else {
    // Float, half and unusual integer widths: OpenImageIO converts to float (integers to [0,1]).
    info.colour_space = info.floating_point ? ColourSpace::kLinear
                                            : options.colour_space.value_or(ColourSpace::kLinear);
    std::vector<float> samples(pixels * spec.nchannels);
    read(OIIO::TypeDesc::FLOAT, samples.data());
    std::span<float> out = result.image.values();
    std::size_t non_finite = 0;
    for (std::size_t p = 0; p < pixels; ++p) {
      for (int c = 0; c < kept; ++c) {
        float value = samples[p * spec.nchannels + c];
        if (!std::isfinite(value)) ++non_finite;
        if (info.colour_space == ColourSpace::kSrgb) {
          value = static_cast<float>(SrgbToLinear(value));
        }
        out[p * kept + c] = value;
      }
    }
    if (non_finite > 0) {
      throw Error(path, fmt::format("{} sample(s) are NaN or infinite", non_finite));
    }
  }
  input->close();
  return result;
}

Mask ReadMask(const fs::path& path) {
  ImageReadOptions options;
  options.colour_space = ColourSpace::kLinear;  // thresholding codes, not light
  options.keep_alpha = true;
  const Image image = ReadImage(path, options).image;
  Mask mask(image.width(), image.height(), false);
  for (std::size_t p = 0; p < image.pixel_count(); ++p) {
    const auto values = image.pixel(p);
    mask.Set(p, std::any_of(values.begin(), values.end(), [](float v) { return v > 0.5f; }));
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

// Integer outputs: the values as they will be quantised (encoded and clamped), checked finite.
std::vector<float> PrepareForQuantising(const fs::path& path, const Image& image,
                                        ColourSpace encoding) {
  std::vector<float> values(image.values().begin(), image.values().end());
  for (float& v : values) {
    if (!std::isfinite(v)) {
      throw Error(path, "cannot store NaN or infinite values in an integer image");
    }
    v = encoding == ColourSpace::kSrgb ? static_cast<float>(LinearToSrgb(v))
                                       : std::clamp(v, 0.0f, 1.0f);
  }
  return values;
}

}  // namespace

void WriteImage(const fs::path& path, const Image& image, const ImageWriteOptions& options) {
  if (image.empty()) throw Error(path, "cannot write an empty image");
  const bool integer =
      options.sample_type == SampleType::kUint8 || options.sample_type == SampleType::kUint16;
  const std::vector<float> quantisable =
      integer ? PrepareForQuantising(path, image, options.encoding) : std::vector<float>{};
  const float* data = integer ? quantisable.data() : image.values().data();

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
    spec.attribute("compression", "zip");
    if (integer) {
      spec.attribute("oiio:ColorSpace", options.encoding == ColourSpace::kSrgb ? "sRGB" : "Linear");
    }
    for (const auto& [name, value] : options.attributes) spec.attribute(name, value);
    if (!output->open(temp.string(), spec)) {
      throw Error(path, fmt::format("cannot write: {}", OiioError(output->geterror())));
    }
    if (!output->write_image(OIIO::TypeDesc::FLOAT, data) || !output->close()) {
      throw Error(path, fmt::format("cannot write: {}", OiioError(output->geterror())));
    }
  });
}

void WriteMask(const fs::path& path, const Mask& mask) {
  Image image(mask.width(), mask.height(), 1);
  for (std::size_t p = 0; p < mask.pixel_count(); ++p) image.pixel(p)[0] = mask[p] ? 1.0f : 0.0f;
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
  std::string extension = path.extension().string();
  for (char& c : extension) c = static_cast<char>(std::tolower(static_cast<unsigned char>(c)));
  return extensions.count(extension) > 0;
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
