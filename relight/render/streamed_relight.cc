#include "relight/render/streamed_relight.h"

#include <fmt/format.h>
#include <tbb/parallel_for.h>

#include <algorithm>
#include <memory>

#include "capture/io/capture_manifest.h"
#include "core/disk_space.h"
#include "core/error.h"
#include "core/image_band_io.h"
#include "core/memory_limits.h"

namespace photomat {
namespace {

namespace fs = std::filesystem;

ImageWriteOptions RelitWriteOptions(RelitFormat format) {
  ImageWriteOptions options;
  if (format == RelitFormat::kPng8) {
    options.sample_type = SampleType::kUint8;
    options.encoding = ColourSpace::kSrgb;
  } else if (format == RelitFormat::kPng16) {
    options.sample_type = SampleType::kUint16;
  }
  return options;
}

int BytesPerSample(RelitFormat format) {
  switch (format) {
    case RelitFormat::kPng8:
      return 1;
    case RelitFormat::kPng16:
      return 2;
    case RelitFormat::kExr:
      break;
  }
  return 4;
}

// The band relit under `light`, in linear values (as WriteRelitImage's RelightLinear).
Image RelightBand(const Representation& band, const LightDirection& light,
                  const RelitOutputOptions& options) {
  Image image = band.Relight(light, options.relight);
  if (options.values == ColourSpace::kSrgb) {
    for (float& v : image.values()) v = static_cast<float>(SrgbToLinear(v));
  }
  return image;
}

// Relights the lights [first, first + count) of `lights` over every band of `stack` (from row 0)
// into `paths`, and commits the files. One pass over the stack.
void RelightPass(StackBandReader& stack, const std::vector<LightDirection>& lights,
                 const std::vector<fs::path>& paths, int band_rows,
                 const StreamedRelightOptions& options, const std::string& label) {
  if (stack.next_row() != 0) stack.Rewind();
  const int channels = stack.header().representation.output_channels();
  const std::vector<std::string> names = OutputChannelNames(channels);
  const ImageWriteOptions write = RelitWriteOptions(options.output.format);
  std::vector<std::unique_ptr<ImageBandWriter>> writers;
  for (const fs::path& path : paths) {
    writers.push_back(
        std::make_unique<ImageBandWriter>(path, stack.width(), stack.height(), names, write));
  }
  NullProgress none;
  Progress& progress = OrNull(options.progress, none);
  const int bands = (stack.height() + band_rows - 1) / band_rows;
  progress.Start(label, static_cast<std::size_t>(bands));
  for (int b = 0; b < bands; ++b) {
    const LoadedStack band = stack.ReadNext(band_rows);
    // Each light's band is relit and written by one task: the files are independent.
    tbb::parallel_for(std::size_t{0}, lights.size(), [&](std::size_t i) {
      writers[i]->WriteNext(RelightBand(band.representation, lights[i], options.output));
    });
    progress.Advance();
  }
  progress.Finish();
  for (auto& writer : writers) writer->Commit();
}

int BandRows(const StackBandReader& stack, int lights, const StreamedRelightOptions& options) {
  if (options.band_rows > 0) return std::min(options.band_rows, stack.height());
  const std::size_t memory =
      options.memory_bytes > 0 ? options.memory_bytes : DefaultBandBudget(kMinimumRelightMemory);
  return RelightBandRows(memory, stack, lights);
}

}  // namespace

int RelightBandRows(std::size_t memory_bytes, const StackBandReader& stack, int lights) {
  const std::size_t maps =
      static_cast<std::size_t>(stack.header().representation.maps().channels());
  const std::size_t outputs = static_cast<std::size_t>(
      stack.header().representation.output_channels() * std::min(lights, kRelitImagesPerPass));
  // 4 bytes per stored channel (the decoded band) and per map (the gathered copy); 8 per relit
  // channel (the relit band and the writer's interleaved, converted copy).
  const std::size_t row_bytes =
      static_cast<std::size_t>(stack.width()) *
      (4 * static_cast<std::size_t>(stack.stored_channels()) + 4 * maps + 8 * outputs);
  return RowsWithinBytes(memory_bytes, row_bytes, stack.height());
}

std::size_t RelitOutputBytes(int width, int height, int channels, int lights, RelitFormat format) {
  // The manifest: a line of about 100 bytes per light.
  return static_cast<std::size_t>(lights) *
         (ImageFileBytes(width, height, channels, BytesPerSample(format)) + 128);
}

StreamedRelightReport WriteRelitImageStreamed(const fs::path& path, StackBandReader& stack,
                                              const LightDirection& light,
                                              const StreamedRelightOptions& options) {
  StreamedRelightReport report;
  report.band_rows = BandRows(stack, 1, options);
  report.passes = 1;
  RelightPass(stack, {light}, {path}, report.band_rows, options, "relight");
  return report;
}

StreamedRelightReport WriteRelitSetStreamed(const fs::path& folder, StackBandReader& stack,
                                            const std::vector<LightDirection>& lights,
                                            const StreamedRelightOptions& options) {
  if (lights.empty()) throw Error(folder, "no lights to relight under");
  std::error_code ec;
  fs::create_directories(folder, ec);
  if (ec) throw Error(folder, fmt::format("cannot create folder: {}", ec.message()));
  const bool exr = options.output.format == RelitFormat::kExr;
  CaptureManifest manifest;
  manifest.colour_space =
      options.output.format == RelitFormat::kPng8 ? ColourSpace::kSrgb : ColourSpace::kLinear;
  for (std::size_t i = 0; i < lights.size(); ++i) {
    manifest.images.push_back(
        {fmt::format("relit_{:03}.{}", i, exr ? "exr" : "png"), lights[i], {}, {}});
  }
  manifest.provenance = {{"relit_from", stack.header().representation.method()}};

  StreamedRelightReport report;
  report.band_rows = BandRows(stack, static_cast<int>(lights.size()), options);
  const std::size_t passes =
      (lights.size() + kRelitImagesPerPass - 1) / static_cast<std::size_t>(kRelitImagesPerPass);
  for (std::size_t pass = 0; pass < passes; ++pass) {
    const std::size_t first = pass * kRelitImagesPerPass;
    const std::size_t count = std::min<std::size_t>(kRelitImagesPerPass, lights.size() - first);
    std::vector<LightDirection> pass_lights(lights.begin() + first, lights.begin() + first + count);
    std::vector<fs::path> paths;
    for (std::size_t i = first; i < first + count; ++i)
      paths.push_back(folder / manifest.images[i].file);
    const std::string label =
        passes == 1 ? std::string("relight")
                    : fmt::format("relight {}-{} of {}", first + 1, first + count, lights.size());
    RelightPass(stack, pass_lights, paths, report.band_rows, options, label);
    ++report.passes;
  }
  WriteCaptureManifest(folder / kCaptureManifestName, manifest);
  return report;
}

}  // namespace photomat
