#include "synthesize/texture/matching_space.h"

#include <fmt/format.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <limits>

#include "core/enum_names.h"
#include "core/error.h"

namespace photomat {

namespace {

constexpr std::array<NamedValue<ErrorMetric>, 2> kMetricNames = {
    {{ErrorMetric::kSsd, "ssd"}, {ErrorMetric::kSad, "sad"}}};
constexpr std::array<NamedValue<ChannelScaling>, 2> kScalingNames = {
    {{ChannelScaling::kMinMax, "minmax"}, {ChannelScaling::kZScore, "zscore"}}};

}  // namespace

std::string_view ToString(ErrorMetric metric) { return NameOf(metric, kMetricNames); }

ErrorMetric ParseErrorMetric(std::string_view name) {
  return ValueNamed(name, kMetricNames, "error metric");
}

std::string_view ToString(ChannelScaling scaling) { return NameOf(scaling, kScalingNames); }

ChannelScaling ParseChannelScaling(std::string_view name) {
  return ValueNamed(name, kScalingNames, "channel scaling");
}

ChannelTransform ChannelTransform::Fit(ConstImageView maps, const MatchingOptions& options) {
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
  for (int c = 0; c < n; ++c) {
    for (int y = 0; y < maps.height(); ++y) {
      for (const float value : maps.row(c, y)) {
        const double v = value;
        sum[c] += v;
        sum2[c] += v * v;
        low[c] = std::min(low[c], v);
        high[c] = std::max(high[c], v);
      }
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

Image ChannelTransform::Apply(ConstImageView image) const {
  if (channels() != image.channels()) {
    throw Error(fmt::format("a channel transform for {} channels applied to {} channels",
                            channels(), image.channels()));
  }
  Image out(image.width(), image.height(), image.channels());
  for (int c = 0; c < image.channels(); ++c) {
    const float o = offset[c], s = scale[c];
    for (int y = 0; y < image.height(); ++y) {
      const auto in = image.row(c, y);
      std::transform(in.begin(), in.end(), out.row(c, y).begin(),
                     [o, s](float v) { return (v - o) * s; });
    }
  }
  return out;
}

}  // namespace photomat
