#pragma once

#include <Eigen/Core>
#include <filesystem>
#include <map>
#include <nlohmann/json.hpp>
#include <optional>
#include <set>
#include <string>
#include <vector>

#include "core/colour.h"
#include "core/light_direction.h"
#include "core/progress.h"
#include "relight/web/viewer_pyramid.h"
#include "represent/model/light_basis.h"
#include "represent/model/representation.h"

namespace photomat {

// The web relighting viewer: a self-contained folder that any static file server can serve
// (index.html, viewer.js, basis.js, viewer.css from viewer/src, compiled into photomat), in which
// WebGL2 relights the exported representations with the same shading rule as
// Representation::Relight, out_c = gain_c * sum_j c_j(l) B_j,c, one fragment shader for every
// method. Folder layout:
//
//   index.html, viewer.js, basis.js, viewer.css   the viewer (no network access, no libraries)
//   viewer.json                                    what to show ("format": "photomat-viewer")
//   maps/<method>.f32                              the maps, float32 little-endian
//   maps/normal.png, albedo.png, height.png       display maps, when a method gives normals
//   maps/<method>/levels/<L>/<column>_<row>.f32   a tiled method's pyramid (viewer_pyramid.h)
//   maps/<method>.decoder.f32                      a neural method's decoder (viewer_decoder.h)
//
// A `neural` method (NeuralShading) is the one nonlinear shading the viewer shows: its maps are
// the k coefficient maps as above, its basis is the light direction ({"kind": "direction"}), and
// its description has "shading": ViewerDecoderJson, from which a fragment shader evaluates the
// decoder per pixel. (pbr's microfacet shading is refused.)
//
// A method's maps are stored as ceil(n / 4) RGBA layers of width x height texels (layer-major,
// rows from the top, map 4 * layer + component; unused components 0), uploaded as one RGBA32F
// 2D-array texture: float32 is what Relight computes in, so the viewer's pixels match the CPU's.
// A tiled method (large stacks, ViewerExportOptions::tiling) has instead a deep-zoom pyramid of
// such tiles, described in viewer.json by its "data": {"type": "float32", "layers": n,
// "pyramid": PyramidLayout::ToJson() + {"folder": "maps/<method>/levels"}}; the viewer loads the
// tiles in view at the level the zoom asks for.
//
// The light basis is exported so that basis.js computes the coefficients of any light as
// represent/light_basis.h does (ViewerBasisJson below), and each method carries check lights with
// the C++ coefficients, which the viewer verifies on load (a mismatch is reported on the page and
// as a console error).

struct ViewerExportOptions {
  std::string title = "photomat";
  // Where the capture's lights were (drawn on the light widget); default: the interpolated
  // basis's lights when a method has one.
  std::vector<LightDirection> capture_lights;
  // Methods whose coefficients the viewer reads from a dense (slant, tilt) table even though
  // basis.js has the exact formula (for tests of the table; bases basis.js does not know always
  // use it: ViewerEvaluatesExactly).
  std::set<std::string> table_methods;
  // How each method's relit values encode light (by method name; default linear): kSrgb for
  // stacks read from .ptm/.rti files, whose values are display codes (relight/stack_file.h
  // StackValueEncoding). The viewer decodes them as `photomat relight` does.
  std::map<std::string, ColourSpace> value_encodings;
  // Write normal, albedo and height display maps (from the first method that gives normals):
  // whole PNGs, or with ExportViewerStreamed one-layer tile pyramids of the streamed export's
  // maps (viewer_display_pyramids.h). (ExportViewer's tiled form, for .ptm/.rti files, has none.)
  bool display_maps = true;
  // Whether methods are written as tile pyramids (viewer_pyramid.h), and their tiles' size.
  ViewerTiling tiling = ViewerTiling::kAuto;
  int tile_size = kViewerTileSize;
  // ExportViewerStreamed: bytes its bands and pyramid buffers may hold; 0: the pyramid's
  // buffers plus DefaultBandBudget(kMinimumViewerMemory) (core/memory_limits.h).
  std::size_t memory_bytes = 0;
  Progress* progress = nullptr;
};
inline constexpr std::size_t kMinimumViewerMemory = std::size_t{64} << 20;

// Writes the viewer for `representations` (one or more methods of the same sample, hence the same
// size) into `folder`, whole or not at all (an existing folder is replaced only if it is empty or
// a previous viewer export). Throws Error naming the folder or the method at fault.
void ExportViewer(const std::filesystem::path& folder,
                  const std::vector<Representation>& representations,
                  const ViewerExportOptions& options = {});

// Peak bytes of a process making the viewer in memory (ExportViewer, loaded stacks) of `maps` maps
// in all at `pixels` pixels: 50 + 10 x maps per pixel, an upper bound of the peak RSS measured
// (whole processes, 2048 x 2048: 226 bytes per pixel for one PTM stack of 18 maps, 505 for
// Gradient + PTM + HSH9, 51 maps; 4096 x 3072 PTM: 217), by at most 11 %.
std::size_t InMemoryViewerBytes(std::size_t pixels, int maps);

// The viewer of the map stacks at `stacks` (photomat .exr stacks of one sample), every method
// written as a tile pyramid from the stack read in bands of rows (StackBandReader), never whole:
// memory is the pyramid's buffers (PyramidWriter::BufferBytes) plus a band, within
// options.memory_bytes. With options.display_maps, the normal, albedo and height views of the
// first stack that gives normals, as tile pyramids (WriteDisplayPyramids). Throws Error naming the
// stack or folder at fault (also when the budget cannot hold the pyramid's buffers and one row),
// leaving `folder` as it was.
void ExportViewerStreamed(const std::filesystem::path& folder,
                          const std::vector<std::filesystem::path>& stacks,
                          const ViewerExportOptions& options = {});

// True when basis.js has the basis's formula: linear, PTM, interpolated (Eigen-k), the light
// direction (a shading's input) and hemispherical harmonics (kind "hsh", {"terms": 4, 9 or 16}).
// Others go through the table.
bool ViewerEvaluatesExactly(const LightBasis& basis);

// A light basis that ViewerEvaluatesExactly, as basis.js reads it (README "Web viewer and
// evaluation report"):
//   {"kind": "linear", "matrix": [[...] x k]}                       c = A l
//   {"kind": "ptm"}                                                  (u^2, v^2, uv, u, v, 1)
//   {"kind": "direction"}                                            c = l
//   {"kind": "interpolated", "scheme": "slant-rings" | "triangulation", "values": [[k] per node],
//    "nodes": [[x, y, z]...], "rings": [{"slant": deg, "by_tilt": [[tilt, node]...]}],
//    "pole_slant_deg": 0.5, "projection_scale": 1000, "projected": [[u, v]...],
//    "triangles": [[a, b, c]...], "boundary": [[a, b]...]}     LightInterpolator's weights
//   {"kind": "hsh", "terms": 4 | 9 | 16}                            HSH, RTIViewer's term order
// Other bases go to the viewer as {"kind": "table", ...CoefficientTable::ToJson(), "source_kind",
// "file"}, the table's values in a float32 file. Throws Error for a basis without a formula.
nlohmann::json ViewerBasisJson(const LightBasis& basis);

// A dense table of a basis's coefficients over the hemisphere, for bases without a formula in
// basis.js: rows at slants 0, step, ..., 90 degrees, columns at tilts 0, step, ..., 360 (the last
// column repeats the first, so interpolation wraps without a special case). Bilinear in (slant,
// tilt); at slant 0 every tilt holds the same value, so the pole is continuous.
class CoefficientTable {
 public:
  explicit CoefficientTable(const LightBasis& basis, double step_degrees = 1.0);

  int terms() const { return terms_; }
  int slant_steps() const { return slant_steps_; }
  int tilt_steps() const { return tilt_steps_; }
  double step_degrees() const { return step_; }
  // term-fastest, then tilt, then slant: (s * tilt_steps + t) * terms + j.
  const std::vector<float>& values() const { return values_; }
  // Largest |table - basis| over every cell's centre and edge midpoints: the bound the viewer's
  // check lights are held to.
  double max_error() const { return max_error_; }

  // The table's coefficients at `light` (slants past 90 clamp to the horizon), as basis.js
  // computes them.
  Eigen::VectorXd Coefficients(const LightDirection& light) const;
  nlohmann::json ToJson() const;

 private:
  int terms_;
  double step_;
  int slant_steps_;
  int tilt_steps_;
  std::vector<float> values_;
  double max_error_ = 0.0;
};

// The lights whose coefficients the viewer checks: a golden-angle spiral over the hemisphere
// (slant 0 to 89.5 degrees), plus the basis's own nodes when it interpolates.
std::vector<LightDirection> ViewerCheckLights(const LightBasis& basis, int spiral_count = 64);

// "3I", "Gradient", "PTM", "PTM LRGB", "Eigen-6", ...: how the viewer names a method.
std::string MethodLabel(const std::string& method);

}  // namespace photomat
