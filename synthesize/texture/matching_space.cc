#include "synthesize/texture/matching_space.h"

#include <fmt/format.h>

#include <algorithm>
#include <cmath>
#include <limits>

#include "core/error.h"

namespace photomat {

std::string_view ToString(ErrorMetric metric) {
  return metric == ErrorMetric::kSsd ? "ssd" : "sad";
}

ErrorMetric ParseErrorMetric(std::string_view name) {
  if (name == "ssd") return ErrorMetric::kSsd;
  if (name == "sad") return ErrorMetric::kSad;
  throw Error(fmt::format("unknown error metric '{}' (ssd or sad)", name));
}

std::string_view ToString(ChannelScaling scaling) {
  return scaling == ChannelScaling::kMinMax ? "minmax" : "zscore";
}

ChannelScaling ParseChannelScaling(std::string_view name) {
  if (name == "minmax") return ChannelScaling::kMinMax;
  if (name == "zscore") return ChannelScaling::kZScore;
  throw Error(fmt::format("unknown channel scaling '{}' (minmax or zscore)", name));
}

ChannelTransform ChannelTransform::Fit(const Image& maps, const MatchingOptions& options) {
  const int n = maps.channels();
  if (!options.weights.empty() && static_cast<int>(options.weights.size()) != n) {
    throw Error(fmt::format("{} channel weights given for {} channels", options.weights.size(), n));
  }
  for (double w : options.weights) {
    if (!std::isfinite(w) || w < 0.0) {
      throw Error(fmt::format("channel weight {} is not a finite non-negative number", w));
    }
  }
  std::vector<double> sum(n, 0.0), sum2(n, 0.0);
  std::vector<double> low(n, std::numeric_limits<double>::infinity());
  std::vector<double> high(n, -std::numeric_limits<double>::infinity());
  for (std::size_t i = 0; i < maps.pixel_count(); ++i) {
    const auto pixel = maps.pixel(i);
    for (int c = 0; c < n; ++c) {
      const double v = pixel[c];
      sum[c] += v;
      sum2[c] += v * v;
      low[c] = std::min(low[c], v);
      high[c] = std::max(high[c], v);
    }
  }
  const double count = static_cast<double>(std::max<std::size_t>(maps.pixel_count(), 1));
  ChannelTransform transform;
  for (int c = 0; c < n; ++c) {
    const double mean = sum[c] / count;
    const double spread = options.scaling == ChannelScaling::kMinMax
                              ? high[c] - low[c]
                              : std::sqrt(std::max(0.0, sum2[c] / count - mean * mean));
    const double weight = options.weights.empty() ? 1.0 : options.weights[c];
    const double weight_factor = options.metric == ErrorMetric::kSsd ? std::sqrt(weight) : weight;
    // A spread at float noise level is a constant channel: it cannot guide matching.
    const bool constant = !(spread > 1e-12 * std::max(1.0, std::abs(mean)));
    transform.offset.push_back(static_cast<float>(mean));
    transform.scale.push_back(constant ? 0.0f : static_cast<float>(weight_factor / spread));
  }
  return transform;
}

PlanarImage::PlanarImage(int width, int height, int channels)
    : width_(width),
      height_(height),
      channels_(channels),
      values_(static_cast<std::size_t>(width) * height * channels, 0.0f) {}

PlanarImage::PlanarImage(const Image& image, const ChannelTransform& transform)
    : PlanarImage(image.width(), image.height(), image.channels()) {
  if (transform.channels() != image.channels()) {
    throw Error(fmt::format("a channel transform for {} channels applied to {} channels",
                            transform.channels(), image.channels()));
  }
  for (int c = 0; c < channels_; ++c) {
    float* out = plane(c).data();
    const float offset = transform.offset[c], scale = transform.scale[c];
    for (std::size_t i = 0; i < plane_size(); ++i) out[i] = (image.pixel(i)[c] - offset) * scale;
  }
}

}  // namespace photomat
