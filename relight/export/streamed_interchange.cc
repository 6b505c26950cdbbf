#include "relight/export/streamed_interchange.h"

#include <fmt/format.h>
#include <tbb/parallel_for.h>

#include <algorithm>
#include <functional>
#include <optional>
#include <string>

#include "core/error.h"
#include "core/memory_limits.h"
#include "relight/export/export.h"
#include "relight/formats/interchange.h"

namespace photomat {
namespace {

namespace fs = std::filesystem;

// Largest coefficient planes of a refit (PTM RGB: 6 x 3; HSH16 of one colour: 16).
constexpr std::size_t kMostRefitPlanes = 18;

int BandRows(const StackBandReader& stack, const StreamedInterchangeOptions& options) {
  return BudgetedBandRows(
      options.band_rows, options.memory_bytes, kMinimumInterchangeMemory,
      static_cast<std::size_t>(stack.width()) * StreamedInterchangeBytesPerPixel(stack),
      stack.height());
}

// One pass over the stack from its first row: each band refitted to `method` in encoded values.
void ForEachRefitBand(StackBandReader& stack, const Method& method, int band_rows,
                      Progress& progress, const std::string& phase,
                      const std::function<void(const Representation&)>& use) {
  if (stack.next_row() != 0) stack.Rewind();
  const int bands = (stack.height() + band_rows - 1) / band_rows;
  progress.Start(phase, static_cast<std::size_t>(bands));
  for (int b = 0; b < bands; ++b) {
    const LoadedStack band = stack.ReadNext(band_rows);
    use(RefitEncodedByRows(band, method));
    progress.Advance();
  }
  progress.Finish();
}

}  // namespace

Representation RefitEncodedByRows(const LoadedStack& stack, const Method& method) {
  const Representation& source = stack.representation;
  const int height = source.height();
  std::vector<std::optional<Representation>> rows(static_cast<std::size_t>(height));
  tbb::parallel_for(0, height, [&](int y) {
    Image maps(source.maps().Rows(y, 1));
    maps.set_channel_names(source.maps().channel_names());
    const LoadedStack row{source.WithMaps(std::move(maps)), stack.provenance};
    rows[static_cast<std::size_t>(y)] = ConvertToEncoded(row, method);
  });
  const Representation& first = *rows.front();
  Image maps(source.width(), height, first.maps().channel_names());
  for (int y = 0; y < height; ++y) {
    const Image& row = rows[static_cast<std::size_t>(y)]->maps();
    for (int c = 0; c < maps.channels(); ++c) {
      const auto in = row.plane(c);
      std::copy(in.begin(), in.end(), maps.row(c, y).begin());
    }
  }
  return first.WithMaps(std::move(maps));
}

std::size_t StreamedInterchangeBytesPerPixel(const StackBandReader& stack) {
  const Representation& r = stack.header().representation;
  const std::size_t maps = static_cast<std::size_t>(r.maps().channels());
  const std::size_t stored = static_cast<std::size_t>(stack.stored_channels());
  const std::size_t channels = static_cast<std::size_t>(r.output_channels());
  // ConvertToEncoded relights at the capture's lights, or at RefitLights' 193 when they do not
  // determine the method.
  const std::size_t lights = RelitLightsBound(stack);
  // The band as stored and gathered, the relit images and the fit's observation matrix, the
  // refit's maps (float), their values in file units (double) and bytes (twice: planes and run).
  return 4 * (stored + maps) + 8 * lights * channels + (4 + 8 + 2) * kMostRefitPlanes;
}

PtmFile ExportPtmStreamed(StackBandReader& stack, const fs::path& path, const Method& method,
                          const StreamedInterchangeOptions& options,
                          StreamedInterchangeReport* report) {
  NullProgress none;
  Progress& progress = OrNull(options.progress, none);
  const int band_rows = BandRows(stack, options);
  PtmFile header;
  header.width = stack.width();
  header.height = stack.height();
  std::optional<PtmCoefficientRanges> ranges;
  ForEachRefitBand(stack, method, band_rows, progress, "ptm: coefficient ranges",
                   [&](const Representation& band) {
                     if (!ranges) {
                       header.format = PtmFormatOf(band);
                       ranges.emplace(header.format);
                     }
                     ranges->Add(band);
                   });
  ranges->ChooseScalesAndBiases(header);
  PtmBandWriter writer(path, header);
  ForEachRefitBand(
      stack, method, band_rows, progress, "ptm: write",
      [&](const Representation& band) { writer.WriteNext(QuantisePtmPlanes(band, header)); });
  writer.Commit();
  if (report) *report = {band_rows, 2};
  return header;
}

RtiFile ExportRtiStreamed(StackBandReader& stack, const fs::path& path, const Method& method,
                          const StreamedInterchangeOptions& options,
                          StreamedInterchangeReport* report) {
  NullProgress none;
  Progress& progress = OrNull(options.progress, none);
  const int band_rows = BandRows(stack, options);
  RtiFile header;
  std::optional<RtiTermRanges> ranges;
  ForEachRefitBand(stack, method, band_rows, progress, "rti: coefficient ranges",
                   [&](const Representation& band) {
                     if (!ranges) {
                       header = RtiHeaderOf(band);
                       ranges.emplace(header.terms, header.colours);
                     }
                     ranges->Add(band);
                   });
  header.height = stack.height();
  ranges->ChooseScalesAndBiases(header);
  RtiBandWriter writer(path, header);
  ForEachRefitBand(
      stack, method, band_rows, progress, "rti: write",
      [&](const Representation& band) { writer.WriteNext(QuantiseRtiPlanes(band, header)); });
  writer.Commit();
  if (report) *report = {band_rows, 2};
  return header;
}

}  // namespace photomat
