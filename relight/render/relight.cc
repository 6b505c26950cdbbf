#include "relight/render/relight.h"

#include <fmt/format.h>
#include <tbb/parallel_for.h>

#include "capture/io/capture_manifest.h"
#include "core/enum_names.h"
#include "core/error.h"
#include "core/image_io.h"

namespace photomat {
namespace {

ImageWriteOptions WriteOptions(RelitFormat format) {
  ImageWriteOptions options;
  switch (format) {
    case RelitFormat::kPng8:
      options.sample_type = SampleType::kUint8;
      options.encoding = ColourSpace::kSrgb;
      break;
    case RelitFormat::kPng16:
      options.sample_type = SampleType::kUint16;
      break;
    case RelitFormat::kExr:
      options.sample_type = SampleType::kFloat;
      break;
  }
  return options;
}

// The relit image in linear values.
Image RelightLinear(const Representation& representation, const LightDirection& light,
                    const RelitOutputOptions& options) {
  Image image = representation.Relight(light, options.relight);
  if (options.values == ColourSpace::kSrgb) {
    for (float& v : image.values()) v = static_cast<float>(SrgbToLinear(v));
  }
  return image;
}

constexpr std::array<NamedValue<RelitFormat>, 3> kFormatNames = {
    {{RelitFormat::kPng8, "png8"}, {RelitFormat::kPng16, "png16"}, {RelitFormat::kExr, "exr"}}};

}  // namespace

std::vector<LightDirection> LightSweep(int count, double slant_degrees) {
  if (count < 1 || count > 100000) throw Error("a light sweep needs 1 to 100000 lights");
  if (!(slant_degrees >= 0.0 && slant_degrees <= 90.0)) {
    throw Error("the sweep's slant must be in [0, 90] degrees");
  }
  std::vector<LightDirection> lights;
  for (int i = 0; i < count; ++i) {
    lights.push_back(LightDirection::FromSlantTilt(slant_degrees, 360.0 * i / count));
  }
  return lights;
}

std::string_view ToString(RelitFormat format) { return NameOf(format, kFormatNames); }

RelitFormat ParseRelitFormat(std::string_view name) {
  return ValueNamed(name, kFormatNames, "image format");
}

std::string_view Extension(RelitFormat format) {
  return format == RelitFormat::kExr ? ".exr" : ".png";
}

void WriteRelitImage(const std::filesystem::path& path, const Representation& representation,
                     const LightDirection& light, const RelitOutputOptions& options) {
  WriteImage(path, RelightLinear(representation, light, options), WriteOptions(options.format));
}

void WriteRelitSet(const std::filesystem::path& folder, const Representation& representation,
                   const std::vector<LightDirection>& lights, const RelitOutputOptions& options,
                   Progress* progress) {
  std::vector<Image> images(lights.size());
  tbb::parallel_for(std::size_t{0}, lights.size(), [&](std::size_t i) {
    images[i] = RelightLinear(representation, lights[i], options);
  });
  SaveSetOptions save;
  const ImageWriteOptions write = WriteOptions(options.format);
  save.sample_type = write.sample_type;
  save.encoding = write.encoding;
  save.prefix = "relit";
  save.provenance = {{"relit_from", representation.method()}};
  SavePhotometricSet(folder, PhotometricSet(std::move(images), lights), save, progress);
}

}  // namespace photomat
