#pragma once

#include <cstddef>
#include <nlohmann/json.hpp>
#include <optional>

#include "core/image.h"
#include "synthesize/texture/matching_space.h"
#include "synthesize/texture/source_map.h"

namespace photomat {

// How good a synthesised texture is, with no ground truth (the thesis could only ask observers):
// whether its local structure occurs in the sample, and whether its seams show. All measures
// work on the channels scaled by the sample (min-max onto [0, 1] by default, as synthesis
// matches), so maps of any scale, and every method's output (or another program's), compare.

struct QualityOptions {
  // Side of the square patches compared (G'MIC's default patch size is 7 too).
  int patch_size = 7;
  // Output patches are taken every `patch_stride` pixels in x and y (0: the patch size, so they
  // tile the output). Every sample position is a candidate.
  int patch_stride = 0;
  ChannelScaling scaling = ChannelScaling::kMinMax;
};

// Mean over output patches of the distance to the nearest sample patch, as the RMS difference
// per value (normalised units): 0 when every output patch occurs in the sample. Nearest by a
// float matrix product (|s|^2 + |o|^2 - 2 s.o), then every sample patch within rounding of the
// nearest re-scored exactly. Throws Error if the images differ in channels or are smaller than a
// patch.
double MeanNearestPatchDistance(const Image& sample, const Image& output,
                                const QualityOptions& options = {});

// Mean squared neighbour differences (summed over the scaled channels) over two sets of pixel
// pairs, and their ratio (1 when both are 0; infinite when only the reference is 0).
struct PairContrast {
  double mean = 0.0;            // the pairs under test
  double reference_mean = 0.0;  // the reference pairs
  std::size_t pairs = 0;
  std::size_t reference_pairs = 0;
  double ratio = 1.0;
};

// Seams of a synthesis from its source map: horizontal and vertical neighbours whose sources are
// not neighbours in the same way lie across a seam (a block boundary's cut, a jump of the pixel
// method); the others lie inside a copied piece. The ratio of their mean differences is 1 for
// invisible seams and grows with their visibility. Wrap pairs are not counted. Throws Error if
// the map does not match the output's size.
PairContrast SeamScore(const Image& output, const SourceMap& map, const ChannelTransform& scale);

// The wrap of an output: pairs across its right/left and bottom/top edges against all interior
// neighbour pairs. About 1 for a tileable output; large when the wrap is a seam.
PairContrast WrapScore(const Image& output, const ChannelTransform& scale);

// The mean neighbour difference of the output against that of the sample: > 1 when seams or
// noise roughen it, < 1 when blending blurs it.
PairContrast RoughnessRatio(const Image& sample, const Image& output,
                            const ChannelTransform& scale);

// Variety: the share of the sample's pixels that the output copies at least once (from the
// source map), in (0, 1]. The nearest-patch distance alone rewards copying a few large pieces
// of the sample over and over (0 for a verbatim tiling); coverage shows what that costs.
double SampleCoverage(const SourceMap& map);

struct SynthesisQuality {
  double nearest_patch_distance = 0.0;
  int patch_size = 0;
  PairContrast roughness;
  PairContrast wrap;
  std::optional<PairContrast> seams;      // with a source map
  std::optional<double> sample_coverage;  // with a source map
};

// Every measure; seams and coverage only when `map` is given.
SynthesisQuality MeasureSynthesis(const Image& sample, const Image& output,
                                  const SourceMap* map = nullptr,
                                  const QualityOptions& options = {});

nlohmann::json ToJson(const SynthesisQuality& quality);

}  // namespace photomat
