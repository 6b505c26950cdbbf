#include "relight/web/viewer_display_pyramids.h"

#include <fmt/format.h>

#include <algorithm>

#include "core/image_band_io.h"
#include "relight/export/export.h"

namespace photomat {
namespace {

namespace fs = std::filesystem;

// Rows of a view's band: 16 MiB of samples, at least one row (the pyramid's buffers come on top).
constexpr std::size_t kViewBandBytes = std::size_t{16} << 20;

struct DisplayView {
  const char* name;
  const char* label;
  const char* file;  // in the export's folder
  const char* encoding;
};

constexpr DisplayView kViews[] = {
    {"normal", "Normal", "normal.png", "(n + 1) / 2"},
    {"albedo", "Albedo", "albedo.png", "sRGB"},
    {"height", "Height", "height.png", "linear"},
};

// The codes of `file` as [0, 1] values, band by band into a pyramid at `folder`; returns the
// file's channels.
int PyramidFromImage(const fs::path& file, const fs::path& folder, const PyramidLayout& layout,
                     Progress& progress, const std::string& label) {
  ImageReadOptions codes;
  codes.colour_space = ColourSpace::kLinear;  // the stored codes / max, whatever the tags say
  ImageBandReader reader(file, codes);
  fs::create_directories(folder);
  PyramidWriter writer(folder, layout, reader.channels());
  const int rows = static_cast<int>(std::clamp<std::size_t>(
      kViewBandBytes / (static_cast<std::size_t>(reader.width()) * 4 * reader.channels()), 1,
      static_cast<std::size_t>(reader.height())));
  const int bands = (reader.height() + rows - 1) / rows;
  progress.Start(label, static_cast<std::size_t>(bands));
  for (int first = 0; first < reader.height(); first += rows) {
    Image band(reader.width(), std::min(rows, reader.height() - first), reader.channels());
    reader.ReadNext(band.View());
    writer.AddRows(band);
    progress.Advance();
  }
  progress.Finish();
  writer.Finish();
  return reader.channels();
}

}  // namespace

bool GivesDisplayMaps(const Representation& representation) {
  return !representation.shading() && (representation.basis().LinearInLight().has_value() ||
                                       representation.basis().kind() == "ptm");
}

nlohmann::json WriteDisplayPyramids(const fs::path& viewer_temp, StackBandReader& stack,
                                    const PyramidLayout& layout, std::size_t memory_bytes,
                                    Progress* progress) {
  NullProgress no_progress;
  Progress& shown = OrNull(progress, no_progress);
  const fs::path scratch = viewer_temp / ".display-maps";
  fs::create_directories(scratch);
  StreamedExportOptions options;
  options.maps.gltf = false;
  options.memory_bytes = memory_bytes;
  options.progress = progress;
  ExportMapsStreamed(stack, scratch, options);
  const std::string source = stack.header().representation.method();
  nlohmann::json views = nlohmann::json::array();
  for (const DisplayView& view : kViews) {
    const std::string folder = fmt::format("maps/views/{}/levels", view.name);
    const int maps = PyramidFromImage(scratch / view.file, viewer_temp / folder, layout, shown,
                                      fmt::format("viewer tiles: {}", view.name));
    nlohmann::json pyramid = layout.ToJson();
    pyramid["folder"] = folder;
    views.push_back(
        {{"name", view.name},
         {"label", view.label},
         {"source", source},
         {"encoding", view.encoding},
         {"data",
          {{"type", "float32"}, {"layers", 1}, {"maps", maps}, {"pyramid", std::move(pyramid)}}}});
  }
  fs::remove_all(scratch);
  return views;
}

}  // namespace photomat
