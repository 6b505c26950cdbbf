#include "synthesize/texture/source_map.h"

#include <fmt/format.h>

#include <algorithm>
#include <cmath>
#include <nlohmann/json.hpp>

#include "core/error.h"
#include "core/image_io.h"
#include "core/json_file.h"

namespace photomat {
namespace {

constexpr const char* kSourceMapAttribute = "photomat:source-map";
constexpr const char* kSourceMapFormat = "photomat-source-map";

}  // namespace

SourceMap::SourceMap(int width, int height, int sample_width, int sample_height)
    : width_(width), height_(height), sample_width_(sample_width), sample_height_(sample_height) {
  if (width < 1 || height < 1 || sample_width < 1 || sample_height < 1) {
    throw Error(fmt::format("a source map needs positive sizes, not {}x{} from {}x{}", width,
                            height, sample_width, sample_height));
  }
  pixels_.assign(static_cast<std::size_t>(width) * height, SamplePixel{});
}

bool SourceMap::Complete() const {
  return std::all_of(pixels_.begin(), pixels_.end(), [this](const SamplePixel& p) {
    return p.x >= 0 && p.y >= 0 && p.x < sample_width_ && p.y < sample_height_;
  });
}

Image SourceMap::Apply(const Image& sample) const {
  if (sample.width() != sample_width_ || sample.height() != sample_height_) {
    throw Error(fmt::format("the source map was made for a {}x{} sample, not {}x{}", sample_width_,
                            sample_height_, sample.width(), sample.height()));
  }
  if (!Complete()) throw Error("the source map leaves output pixels without a source");
  Image out(width_, height_, sample.channels());
  if (!sample.channel_names().empty()) out.set_channel_names(sample.channel_names());
  // Plane by plane: every output pixel's value is the sample's at its source.
  std::vector<std::size_t> sources(pixels_.size());
  for (std::size_t i = 0; i < pixels_.size(); ++i) {
    sources[i] = sample.Index(pixels_[i].x, pixels_[i].y);
  }
  for (int c = 0; c < sample.channels(); ++c) {
    const float* in = sample.plane(c).data();
    float* to = out.plane(c).data();
    for (std::size_t i = 0; i < sources.size(); ++i) to[i] = in[sources[i]];
  }
  return out;
}

SourceMap SourceMap::Cropped(int width, int height) const {
  if (width > width_ || height > height_) {
    throw Error(
        fmt::format("cannot crop a {}x{} source map to {}x{}", width_, height_, width, height));
  }
  SourceMap out(width, height, sample_width_, sample_height_);
  for (int y = 0; y < height; ++y) {
    for (int x = 0; x < width; ++x) out.Set(x, y, at(x, y));
  }
  return out;
}

void SaveSourceMap(const std::filesystem::path& path, const SourceMap& map) {
  if (!map.Complete()) throw Error(path, "the source map is incomplete");
  Image image(map.width(), map.height(), std::vector<std::string>{"source.x", "source.y"});
  for (std::size_t i = 0; i < map.pixels().size(); ++i) {
    image.plane(0)[i] = static_cast<float>(map.pixels()[i].x);
    image.plane(1)[i] = static_cast<float>(map.pixels()[i].y);
  }
  const nlohmann::json description = {{"format", kSourceMapFormat},
                                      {"version", 1},
                                      {"sample_width", map.sample_width()},
                                      {"sample_height", map.sample_height()}};
  ImageWriteOptions options;
  options.attributes[kSourceMapAttribute] = description.dump();
  WriteImage(path, image, options);
}

SourceMap LoadSourceMap(const std::filesystem::path& path) {
  ImageReadOptions read;
  read.keep_alpha = true;
  const LoadedImage loaded = ReadImage(path, read);
  const auto attribute = loaded.info.attributes.find(kSourceMapAttribute);
  if (attribute == loaded.info.attributes.end()) {
    throw Error(path, "not a photomat source map (no photomat:source-map attribute)");
  }
  nlohmann::json description;
  try {
    description = nlohmann::json::parse(attribute->second);
  } catch (const nlohmann::json::exception& error) {
    throw Error(path, fmt::format("damaged source-map description: {}", error.what()));
  }
  if (!description.is_object() || description.value("format", "") != kSourceMapFormat ||
      !description.contains("sample_width") || !description["sample_width"].is_number_integer() ||
      !description.contains("sample_height") || !description["sample_height"].is_number_integer()) {
    throw Error(path, "damaged source-map description");
  }
  const Image& image = loaded.image;
  const int x_channel = image.FindChannel("source.x"), y_channel = image.FindChannel("source.y");
  if (x_channel < 0 || y_channel < 0) {
    throw Error(path, "a source map needs the channels source.x and source.y");
  }
  const int sample_width = description["sample_width"].get<int>();
  const int sample_height = description["sample_height"].get<int>();
  if (sample_width < 1 || sample_height < 1) throw Error(path, "implausible sample size");
  SourceMap map(image.width(), image.height(), sample_width, sample_height);
  for (int y = 0; y < image.height(); ++y) {
    for (int x = 0; x < image.width(); ++x) {
      const float sx = image.at(x, y, x_channel), sy = image.at(x, y, y_channel);
      if (sx != std::floor(sx) || sy != std::floor(sy) || sx < 0 || sy < 0 || sx >= sample_width ||
          sy >= sample_height) {
        throw Error(path, fmt::format("pixel ({}, {}): source ({}, {}) is not a pixel of the "
                                      "{}x{} sample",
                                      x, y, sx, sy, sample_width, sample_height));
      }
      map.Set(x, y, {static_cast<std::int32_t>(sx), static_cast<std::int32_t>(sy)});
    }
  }
  return map;
}

}  // namespace photomat
