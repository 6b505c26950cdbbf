#pragma once

#include <cstddef>
#include <filesystem>
#include <nlohmann/json.hpp>
#include <string>

#include "core/progress.h"
#include "relight/web/viewer_pyramid.h"
#include "represent/model/representation.h"
#include "represent/stack/stack_band_reader.h"

namespace photomat {

// The normal, albedo and height views of a deep-zoom viewer (issue 16: small stacks have them as
// whole PNGs, large ones could not): the streamed export's maps (relight/export/export.h,
// ExportMapsStreamed: normals and albedo band by band, the height by tiled Poisson), each read
// back band by band into a one-layer tile pyramid of the layout the methods use, so memory stays
// the export's bands and the pyramid's buffers. A view's tiles hold its display codes in [0, 1],
// which the viewer shows as they are (as it shows the small stacks' PNGs):
//   normal  normal.png's codes / 65535: (n + 1) / 2, OpenGL convention (+Y up)
//   albedo  albedo.png's codes / 255: sRGB codes of the Lambertian albedo
//   height  height.png's codes / 65535: the height stretched to [0, 1] over the fitted pixels
// Coarser levels average the codes (the views are for looking at).
//
// IMPLEMENTER CHOICE: the export runs whole into a scratch folder inside `viewer_temp` (removed
// before returning), so that these views are exactly the files `photomat export` writes (the
// browser test compares tiles against them); its stack.exr copy costs scratch disk space and
// time (ExportOutputBytes), not memory.
//
// `stack` must be at its first band (a freshly opened reader). Writes
// `viewer_temp`/maps/views/<name>/levels/...; returns viewer.json's "views":
// [{"name", "label", "source", "encoding", "data": {"type": "float32", "layers": 1, "maps": 3 or
//   1, "pyramid": PyramidLayout::ToJson() + {"folder"}}}, ...]. `memory_bytes`: the export's band
// budget (0: its default).
nlohmann::json WriteDisplayPyramids(const std::filesystem::path& viewer_temp,
                                    StackBandReader& stack, const PyramidLayout& layout,
                                    std::size_t memory_bytes, Progress* progress);

// Whether a stack of this method and description gives display maps (a normal estimate: the
// linear-in-light methods, PTM; not Eigen-k, pbr or neural).
bool GivesDisplayMaps(const Representation& representation);

}  // namespace photomat
