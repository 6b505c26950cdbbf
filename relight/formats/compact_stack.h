#pragma once

#include <Eigen/Core>
#include <cstdint>
#include <filesystem>
#include <string>
#include <string_view>
#include <vector>

#include "core/image.h"
#include "represent/stack/map_stack.h"

namespace photomat {

// photomat's compact stack form (issue 19; README "Compact stack form"): any linear stack's maps
// (ptm and hsh coefficient maps, rbf and bilinear PCA planes with their basis, Eigen-k, 3I, ...)
// as LINEAR values quantised to 8 bits, one greyscale PNG (lossless, the default) or JPEG per map,
// with a per-plane scale and bias, in a folder beside a small manifest `compact_stack.json`:
//
//   {"format": "photomat-compact-stack", "version": 1, "width": W, "height": H,
//    "coding": "png" | "jpeg", "quality": Q (jpeg only), "mask": "mask.png",
//    "planes": [{"file": "map_000.png", "channel": "ptm.a0.R", "scale": s, "bias": b}, ...],
//    "stack": {the map stack's description, as in a stack's "photomat:stack" attribute: method,
//              layout, channels, the light basis (rbf/bilinear: their PCA basis), details,
//              capture}}
//
// A map's byte q decodes to value = bias + scale * q inside the mask and to 0 outside it. This is
// photomat-only: relight and OpenLIME read relight's web format (relight_web_format.h), which
// stays the interchange format; this one keeps photomat's own bases and linear values, so relit
// results differ from the float stack's by the quantisation alone.
//
// IMPLEMENTER CHOICEs:
// - The mask is the pixels where any map is nonzero (a fit over a set's mask stores 0 outside it,
//   represent/fitting/fit.h), written as mask.png; outside it every plane stores 0, so background
//   costs almost no bytes and decodes exactly.
// - Each plane's range is its minimum to maximum over the mask's pixels (no value clipped: every
//   value is within scale / 2 of its decoded one, PNG), or with range_quantile < 1 its
//   (1 - q) to q quantiles over the mask, values outside clipped.
// - One greyscale file per map: a JPEG of one channel has no colour transform and no chroma
//   subsampling, so planes never mix.
// - Extra layers of a stack (export's height, derived normals) are not stored.
// - The provenance's source, when absolute, is stored relative to the compact folder (what is
//   published carries no absolute local path).
inline constexpr const char* kCompactStackManifest = "compact_stack.json";
inline constexpr const char* kCompactStackFormat = "photomat-compact-stack";

enum class CompactPlaneCoding { kPng, kJpeg };
std::string_view ToString(CompactPlaneCoding coding);  // "png", "jpeg"
// Throws Error naming the accepted values.
CompactPlaneCoding ParseCompactPlaneCoding(std::string_view name);

struct CompactStackOptions {
  CompactPlaneCoding coding = CompactPlaneCoding::kPng;
  int jpeg_quality = 100;  // 1..100, jpeg only
  // In (0.5, 1]: each plane quantised over its (1 - q) to q quantiles over the mask's pixels,
  // values outside clipped; 1: minimum to maximum.
  double range_quantile = 1.0;
  // Store the maps' principal components instead of the maps (below): k > 0 the k largest (all
  // when the stack has k maps or fewer), -1 every component (a rotation: decorrelated planes, no
  // compression), 0 the maps themselves. IMPLEMENTER CHOICE: 18 by default, measured on DiLiGenT
  // cat (bench/compact_form, README "Compact form against the float stack and relight-cli"): the
  // one setting under 0.3 dB loss and within 2 x relight-cli's size for ptm (18 maps: a rotation),
  // hsh9 (27 maps), rbf and bilinear (9 planes x 3 channels) alike.
  int pca_planes = 18;
};

// The maps' principal components (the optional "pca" of the manifest). Each pixel's n-vector of
// maps is weighted by how much each map moves a relit value, x_j = w_j B_j (w_j: the RMS over the
// capture lights of the map's light coefficient; 1 for gain and shading maps), so that the
// components' errors are errors of relit values; the planes are P = (x - mean) V over the mask,
// V's columns ordered by variance, and the maps decode as B_j = (mean + V P)_j / w_j.
// IMPLEMENTER CHOICE: correlated coefficient maps (HSH's terms) otherwise each take a whole 8-bit
// range of their own; after the rotation the small components get small steps.
struct CompactPca {
  std::vector<std::string> channels;  // the maps', in layout order
  Eigen::VectorXd weights;            // n
  Eigen::VectorXd mean;               // n
  Eigen::MatrixXd axes;               // n x k, orthonormal columns
};
// The weights w_j of `stack`'s maps (above).
Eigen::VectorXd MapWeights(const LoadedStack& stack);
// The principal components of the weighted maps over `mask`; `planes` -1 for all.
CompactPca FitMapPca(const Image& maps, const Mask& mask, const Eigen::VectorXd& weights,
                     int planes);
// The k component planes ("pca.0", ...), 0 outside the mask.
Image ProjectMaps(const Image& maps, const Mask& mask, const CompactPca& pca);
// The maps the component planes decode to, 0 outside the mask.
Image ReconstructMaps(const Image& planes, const Mask& mask, const CompactPca& pca);

// Quantised maps in memory: what the files hold, before their PNG/JPEG coding.
struct CompactPlanes {
  int width = 0;
  int height = 0;
  std::vector<std::string> channels;             // the maps' names, in layout order
  std::vector<std::vector<std::uint8_t>> bytes;  // per plane, width * height, row 0 at the top
  std::vector<double> scale;                     // per plane
  std::vector<double> bias;                      // per plane
  Mask mask;                                     // decoded as 0 outside

  int PlaneCount() const { return static_cast<int>(bytes.size()); }
};

// The pixels where any map is nonzero. Throws Error for non-finite values (naming the map).
Mask NonzeroMapsMask(const Image& maps);

// Quantises every map of `maps` (named channels) over `mask` as described above. Throws Error for
// a range_quantile outside (0.5, 1] or a mask of another size.
CompactPlanes QuantiseMaps(const Image& maps, const Mask& mask, double range_quantile = 1.0);
// The maps the planes decode to (bias + scale * byte inside the mask, 0 outside).
Image DequantiseMaps(const CompactPlanes& planes);

// True for a folder holding a compact_stack.json.
bool IsCompactStackFolder(const std::filesystem::path& path);

// The planes WriteCompactStack writes for `representation`: its maps' count, or the components
// pca_planes keeps.
int CompactPlaneCount(const Representation& representation, const CompactStackOptions& options);

// Writes `stack` (its maps quantised over NonzeroMapsMask) into `folder` whole or not at all (an
// existing folder is replaced only when empty or another compact stack). Throws Error naming the
// folder, and for a nonlinear (pbr) stack, whose shading would amplify the quantisation
// unboundedly.
void WriteCompactStack(const std::filesystem::path& folder, const LoadedStack& stack,
                       const CompactStackOptions& options = {});

// Reads a compact stack folder as a representation like a map stack (the description's method,
// basis and provenance). Throws Error naming the file and the fault: a damaged manifest, a
// missing or unreadable plane or mask, a plane of the wrong size.
LoadedStack ReadCompactStack(const std::filesystem::path& folder);

}  // namespace photomat
