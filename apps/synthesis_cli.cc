#include "apps/synthesis_cli.h"

#include <fmt/format.h>

#include <algorithm>
#include <cctype>

#include "core/error.h"
#include "core/json_file.h"
#include "core/text_parsing.h"
#include "synthesize/texture/synthesis_quality.h"

namespace photomat::app {
namespace {}  // namespace

MapsInput LoadMapsInput(const std::filesystem::path& input,
                        const std::optional<std::string>& stack) {
  MapsInput result;
  if (std::filesystem::is_directory(input)) {
    result.path = ResolveStack(input, stack);
    result.stack = LoadRepresentation(result.path);
    result.image = result.stack->representation.maps();
    return result;
  }
  if (stack) throw Error(input, "--stack names a stack of a fit folder, but this is a file");
  ImageReadOptions read;
  read.keep_alpha = true;
  LoadedImage loaded = ReadImage(input, read);
  result.path = input;
  if (loaded.info.attributes.count(kStackAttribute)) {
    result.stack = LoadRepresentation(input);
    result.image = result.stack->representation.maps();
    return result;
  }
  // Plain images: an opaque alpha channel carries nothing to synthesise (the quilting exemplars
  // are RGBA PNGs with alpha 1 everywhere); a varying one is kept as a map.
  Image image = std::move(loaded.image);
  const int alpha = image.FindChannel("A");
  if (alpha == image.channels() - 1 && alpha > 0) {
    bool opaque = true;
    for (std::size_t i = 0; i < image.pixel_count() && opaque; ++i) {
      opaque = image.pixel(i)[alpha] == 1.0f;
    }
    if (opaque) image = image.Channels(0, alpha);
  }
  result.image = std::move(image);
  result.info = std::move(loaded.info);
  return result;
}

void WritePlainMaps(const std::filesystem::path& path, const Image& maps,
                    const ImageFileInfo& input_info) {
  const std::string extension = LowerExtension(path);
  ImageWriteOptions options;
  if (extension == ".exr") {
    options.sample_type = SampleType::kFloat;
  } else if (input_info.bits_per_sample == 8 && !input_info.floating_point &&
             input_info.colour_space == ColourSpace::kSrgb) {
    options.sample_type = SampleType::kUint8;
    options.encoding = ColourSpace::kSrgb;
  } else if (extension == ".jpg" || extension == ".jpeg") {
    options.sample_type = SampleType::kUint8;
    options.encoding = ColourSpace::kSrgb;
  } else {
    options.sample_type = SampleType::kUint16;
    options.encoding = ColourSpace::kLinear;
  }
  WriteImage(path, maps, options);
}

void EvaluateSynthesis(const SynthesisEvaluationOptions& options) {
  const MapsInput synthesised = LoadMapsInput(options.synthesised);
  // A fit folder as the sample: the stack of the synthesised stack's method.
  std::optional<std::string> method;
  if (std::filesystem::is_directory(options.sample) && synthesised.stack) {
    method = synthesised.stack->representation.method();
  }
  const MapsInput sample = LoadMapsInput(options.sample, method);
  if (sample.image.channels() != synthesised.image.channels()) {
    throw Error(options.synthesised,
                fmt::format("has {} maps but the sample {} has {}", synthesised.image.channels(),
                            sample.path.string(), sample.image.channels()));
  }
  if (sample.stack && synthesised.stack &&
      sample.image.channel_names() != synthesised.image.channel_names()) {
    throw Error(options.synthesised,
                fmt::format("its maps are not those of the sample {}", sample.path.string()));
  }
  std::optional<SourceMap> map;
  if (!options.source_map.empty()) {
    map = LoadSourceMap(options.source_map);
    if (map->width() != synthesised.image.width() || map->height() != synthesised.image.height() ||
        map->sample_width() != sample.image.width() ||
        map->sample_height() != sample.image.height()) {
      throw Error(
          options.source_map,
          fmt::format("maps {}x{} from {}x{}, but the synthesis is {}x{} from {}x{}", map->width(),
                      map->height(), map->sample_width(), map->sample_height(),
                      synthesised.image.width(), synthesised.image.height(), sample.image.width(),
                      sample.image.height()));
    }
  }
  QualityOptions quality_options;
  quality_options.patch_size = options.patch_size;
  const SynthesisQuality quality =
      MeasureSynthesis(sample.image, synthesised.image, map ? &*map : nullptr, quality_options);
  fmt::print("{} ({}x{}) grown from {} ({}x{}), {} maps\n", synthesised.path.string(),
             synthesised.image.width(), synthesised.image.height(), sample.path.string(),
             sample.image.width(), sample.image.height(), sample.image.channels());
  fmt::print("{:<34} {:>10}\n", "measure", "value");
  fmt::print("{:<34} {:>10.5f}\n",
             fmt::format("nearest-patch distance ({0}x{0})", quality.patch_size),
             quality.nearest_patch_distance);
  fmt::print("{:<34} {:>10.3f}\n", "roughness (output / sample)", quality.roughness.ratio);
  fmt::print("{:<34} {:>10.3f}\n", "wrap (across edges / inside)", quality.wrap.ratio);
  if (quality.seams) {
    fmt::print("{:<34} {:>10.3f}   ({} seam pairs)\n", "seams (across / inside pieces)",
               quality.seams->ratio, quality.seams->pairs);
  }
  if (quality.sample_coverage) {
    fmt::print("{:<34} {:>10.3f}\n", "sample coverage (variety)", *quality.sample_coverage);
  }
  if (!options.json.empty()) {
    nlohmann::json json = ToJson(quality);
    json["sample"] = sample.path.string();
    json["synthesised"] = synthesised.path.string();
    WriteJsonFile(options.json, json);
  }
}

}  // namespace photomat::app
