#include "synthesize/texture/synthesis_quality.h"

#include <fmt/format.h>
#include <tbb/parallel_for.h>

#include <Eigen/Core>
#include <algorithm>
#include <cmath>
#include <limits>

#include "core/error.h"

namespace photomat {
namespace {

constexpr double kFloatEpsilon = 0x1.0p-24;
constexpr int kChunk = 128;  // output patches per matrix product

double PairDifference(const Image& image, int x0, int y0, int x1, int y1) {
  double sum = 0.0;
  for (int c = 0; c < image.channels(); ++c) {
    const double d = static_cast<double>(image.at(x0, y0, c)) - image.at(x1, y1, c);
    sum += d * d;
  }
  return sum;
}

void Finish(PairContrast& contrast, double sum, double reference_sum) {
  contrast.mean = contrast.pairs ? sum / static_cast<double>(contrast.pairs) : 0.0;
  contrast.reference_mean = contrast.reference_pairs
                                ? reference_sum / static_cast<double>(contrast.reference_pairs)
                                : 0.0;
  if (contrast.reference_mean > 0.0) {
    contrast.ratio = contrast.mean / contrast.reference_mean;
  } else {
    contrast.ratio = contrast.mean > 0.0 ? std::numeric_limits<double>::infinity() : 1.0;
  }
}

// Sum of squared neighbour differences over the interior pairs (right and down) of an image.
void InteriorPairs(const Image& image, double& sum, std::size_t& pairs) {
  for (int y = 0; y < image.height(); ++y) {
    for (int x = 0; x < image.width(); ++x) {
      if (x + 1 < image.width()) sum += PairDifference(image, x, y, x + 1, y), ++pairs;
      if (y + 1 < image.height()) sum += PairDifference(image, x, y, x, y + 1), ++pairs;
    }
  }
}

// The values of the patch at (x, y), channel-major, into `out` (size patch^2 * channels).
template <typename Out>
void GatherPatch(const Image& image, int x, int y, int patch, Out&& out) {
  int k = 0;
  for (int c = 0; c < image.channels(); ++c) {
    for (int v = 0; v < patch; ++v) {
      for (int u = 0; u < patch; ++u) out[k++] = image.at(x + u, y + v, c);
    }
  }
}

ChannelTransform QualityScale(const Image& sample, ChannelScaling scaling) {
  MatchingOptions matching;
  matching.metric = ErrorMetric::kSsd;
  matching.scaling = scaling;
  return ChannelTransform::Fit(sample, matching);
}

}  // namespace

double MeanNearestPatchDistance(const Image& sample, const Image& output,
                                const QualityOptions& options) {
  const int patch = options.patch_size;
  const int stride = options.patch_stride > 0 ? options.patch_stride : patch;
  if (patch < 1) throw Error(fmt::format("patch size {} is not positive", patch));
  if (sample.channels() != output.channels()) {
    throw Error(fmt::format("the output has {} channels, the sample {}", output.channels(),
                            sample.channels()));
  }
  if (std::min({sample.width(), sample.height(), output.width(), output.height()}) < patch) {
    throw Error(fmt::format("{}-pixel patches do not fit in a {}x{} sample and {}x{} output", patch,
                            sample.width(), sample.height(), output.width(), output.height()));
  }
  const ChannelTransform scale = QualityScale(sample, options.scaling);
  const Image s = scale.Apply(sample), o = scale.Apply(output);
  const int dims = patch * patch * s.channels();
  const int sample_columns = s.width() - patch + 1;
  const int sample_patches = sample_columns * (s.height() - patch + 1);
  Eigen::MatrixXf candidates(dims, sample_patches);
  Eigen::VectorXf candidate_norms(sample_patches);
  tbb::parallel_for(0, sample_patches, [&](int i) {
    GatherPatch(s, i % sample_columns, i / sample_columns, patch, candidates.col(i));
    candidate_norms[i] = candidates.col(i).squaredNorm();
  });
  const float largest_norm = candidate_norms.maxCoeff();

  std::vector<std::pair<int, int>> positions;
  for (int y = 0; y + patch <= o.height(); y += stride) {
    for (int x = 0; x + patch <= o.width(); x += stride) positions.emplace_back(x, y);
  }
  const int count = static_cast<int>(positions.size());
  std::vector<double> distances(count);
  const int chunks = (count + kChunk - 1) / kChunk;
  tbb::parallel_for(0, chunks, [&](int chunk) {
    const int first = chunk * kChunk, size = std::min(kChunk, count - first);
    Eigen::MatrixXf queries(dims, size);
    for (int k = 0; k < size; ++k) {
      GatherPatch(o, positions[first + k].first, positions[first + k].second, patch,
                  queries.col(k));
    }
    const Eigen::MatrixXf products = candidates.transpose() * queries;
    for (int k = 0; k < size; ++k) {
      const float query_norm = queries.col(k).squaredNorm();
      const Eigen::VectorXf estimate =
          (candidate_norms.array() + query_norm - 2.0f * products.col(k).array()).matrix();
      // Float rounding of each estimate is below ~dims u (|s|^2 + |o|^2); re-score exactly every
      // candidate within four times that of the smallest.
      const float reach = estimate.minCoeff() + static_cast<float>(8.0 * dims * kFloatEpsilon) *
                                                    (largest_norm + query_norm);
      double best = std::numeric_limits<double>::infinity();
      for (int i = 0; i < sample_patches; ++i) {
        if (estimate[i] > reach) continue;
        const double exact =
            (candidates.col(i).cast<double>() - queries.col(k).cast<double>()).squaredNorm();
        best = std::min(best, exact);
      }
      distances[first + k] = std::sqrt(best / dims);
    }
  });
  double sum = 0.0;
  for (double d : distances) sum += d;
  return count ? sum / count : 0.0;
}

PairContrast SeamScore(const Image& output, const SourceMap& map, const ChannelTransform& scale) {
  if (map.width() != output.width() || map.height() != output.height()) {
    throw Error(fmt::format("the source map is {}x{} but the output {}x{}", map.width(),
                            map.height(), output.width(), output.height()));
  }
  const Image o = scale.Apply(output);
  PairContrast contrast;
  double seam_sum = 0.0, inside_sum = 0.0;
  auto visit = [&](int x0, int y0, int x1, int y1) {
    const SamplePixel a = map.at(x0, y0), b = map.at(x1, y1);
    const double d = PairDifference(o, x0, y0, x1, y1);
    if (b.x - a.x == x1 - x0 && b.y - a.y == y1 - y0) {
      inside_sum += d;
      ++contrast.reference_pairs;
    } else {
      seam_sum += d;
      ++contrast.pairs;
    }
  };
  for (int y = 0; y < o.height(); ++y) {
    for (int x = 0; x < o.width(); ++x) {
      if (x + 1 < o.width()) visit(x, y, x + 1, y);
      if (y + 1 < o.height()) visit(x, y, x, y + 1);
    }
  }
  Finish(contrast, seam_sum, inside_sum);
  return contrast;
}

PairContrast WrapScore(const Image& output, const ChannelTransform& scale) {
  const Image o = scale.Apply(output);
  PairContrast contrast;
  double wrap_sum = 0.0, inside_sum = 0.0;
  InteriorPairs(o, inside_sum, contrast.reference_pairs);
  const int w = o.width(), h = o.height();
  if (w > 1) {
    for (int y = 0; y < h; ++y) wrap_sum += PairDifference(o, w - 1, y, 0, y), ++contrast.pairs;
  }
  if (h > 1) {
    for (int x = 0; x < w; ++x) wrap_sum += PairDifference(o, x, h - 1, x, 0), ++contrast.pairs;
  }
  Finish(contrast, wrap_sum, inside_sum);
  return contrast;
}

PairContrast RoughnessRatio(const Image& sample, const Image& output,
                            const ChannelTransform& scale) {
  PairContrast contrast;
  double output_sum = 0.0, sample_sum = 0.0;
  InteriorPairs(scale.Apply(output), output_sum, contrast.pairs);
  InteriorPairs(scale.Apply(sample), sample_sum, contrast.reference_pairs);
  Finish(contrast, output_sum, sample_sum);
  return contrast;
}

double SampleCoverage(const SourceMap& map) {
  std::vector<char> copied(static_cast<std::size_t>(map.sample_width()) * map.sample_height(), 0);
  for (const SamplePixel& source : map.pixels()) {
    if (source.valid())
      copied[static_cast<std::size_t>(source.y) * map.sample_width() + source.x] = 1;
  }
  const auto count = std::count(copied.begin(), copied.end(), 1);
  return copied.empty() ? 0.0 : static_cast<double>(count) / static_cast<double>(copied.size());
}

SynthesisQuality MeasureSynthesis(const Image& sample, const Image& output, const SourceMap* map,
                                  const QualityOptions& options) {
  SynthesisQuality quality;
  quality.patch_size = options.patch_size;
  quality.nearest_patch_distance = MeanNearestPatchDistance(sample, output, options);
  const ChannelTransform scale = QualityScale(sample, options.scaling);
  quality.roughness = RoughnessRatio(sample, output, scale);
  quality.wrap = WrapScore(output, scale);
  if (map) {
    quality.seams = SeamScore(output, *map, scale);
    quality.sample_coverage = SampleCoverage(*map);
  }
  return quality;
}

nlohmann::json ToJson(const SynthesisQuality& quality) {
  auto contrast = [](const PairContrast& c) {
    return nlohmann::json{
        {"mean", c.mean},
        {"reference_mean", c.reference_mean},
        {"pairs", c.pairs},
        {"reference_pairs", c.reference_pairs},
        {"ratio", std::isfinite(c.ratio) ? nlohmann::json(c.ratio) : nlohmann::json("inf")}};
  };
  nlohmann::json json = {{"nearest_patch_distance", quality.nearest_patch_distance},
                         {"patch_size", quality.patch_size},
                         {"roughness", contrast(quality.roughness)},
                         {"wrap", contrast(quality.wrap)}};
  if (quality.seams) json["seams"] = contrast(*quality.seams);
  if (quality.sample_coverage) json["sample_coverage"] = *quality.sample_coverage;
  return json;
}

}  // namespace photomat
