#include "apps/streamed_capture.h"

#include <fmt/format.h>
#include <fmt/ranges.h>

#include "apps/cli_support.h"
#include "capture/io/load_photometric_set.h"
#include "core/disk_space.h"

namespace photomat::app {

bool HoldingSetExceeds(const StreamedSet& set, std::size_t budget_bytes) {
  const double pixel_images =
      static_cast<double>(set.width()) * static_cast<double>(set.height()) * set.size();
  return kWholeSetBytesPerPixelImage * pixel_images > static_cast<double>(budget_bytes);
}

std::vector<std::filesystem::path> PlanScratchStacks(const StreamedSet& set,
                                                     const std::vector<Method>& methods,
                                                     const std::filesystem::path& folder,
                                                     const std::string& source,
                                                     StreamedFitOptions& options) {
  const std::size_t pixels = static_cast<std::size_t>(set.width()) * set.height();
  options.compression =
      FittedStackCompression("auto", set.SelectedPixels(0, set.height()) < pixels);
  options.provenance = {set.lights(), options.encoded_values ? "srgb" : "linear", source,
                        set.encodings()};
  CheckDiskSpace(folder, StreamedStackBytes(set, methods), "the scratch map stacks");
  std::vector<std::filesystem::path> stacks;
  for (const Method& method : methods) stacks.push_back(folder / (method.Name() + ".exr"));
  return stacks;
}

std::vector<std::filesystem::path> FitIntoFolder(StreamedSet& set,
                                                 const std::vector<Method>& methods,
                                                 const std::filesystem::path& folder,
                                                 const std::string& source,
                                                 StreamedFitOptions options, bool warn_clipped) {
  const std::vector<std::filesystem::path> stacks =
      PlanScratchStacks(set, methods, folder, source, options);
  std::vector<std::string> names;
  for (const Method& method : methods) names.push_back(method.Name());
  const StreamedFitReport report = FitStreamed(set, methods, stacks, options);
  if (warn_clipped) WarnAboutClippedPixels(report.saturated_pixels, set.image_names());
  fmt::print("fitted {} to the {} photographs ({}) in bands of {} of {} rows\n",
             fmt::join(names, ", "), set.size(), options.encoded_values ? "sRGB-encoded" : "linear",
             report.band_rows, set.height());
  return stacks;
}

}  // namespace photomat::app
