#pragma once

#include <cmath>
#include <cstddef>
#include <string_view>
#include <vector>

#include "core/image.h"

namespace photomat {

// Where synthesis measures how well pixels match. The maps of a representation live on unrelated
// scales (Gradient's normal components near 0, its albedo near 0.5, PTM's a0..a5 spanning orders
// of magnitude), so the thesis "transforms all pixel values into the same scale" before summing
// errors over channels (section 6.2) while the output still copies the original values. The
// transform below is applied only inside the error computation.

// The overlap error of a pair of pixels: squared (SSD, Efros-Freeman) or absolute (SAD, the
// thesis's modification 2) difference, summed over the scaled channels.
enum class ErrorMetric { kSsd, kSad };
std::string_view ToString(ErrorMetric metric);
// "ssd" or "sad"; throws Error otherwise.
ErrorMetric ParseErrorMetric(std::string_view name);

// How each channel is brought to a common scale (IMPLEMENTER CHOICE, spec 5.1): min-max maps the
// channel's range onto [0, 1] (default); z-score divides by its standard deviation. A constant
// channel carries no information and gets scale 0.
enum class ChannelScaling { kMinMax, kZScore };
std::string_view ToString(ChannelScaling scaling);
// "minmax" or "zscore"; throws Error otherwise.
ChannelScaling ParseChannelScaling(std::string_view name);

struct MatchingOptions {
  ErrorMetric metric = ErrorMetric::kSsd;
  ChannelScaling scaling = ChannelScaling::kMinMax;
  // One non-negative weight per channel multiplying that channel's error term (empty: all 1;
  // 0 leaves a channel out of the matching but it is still copied).
  std::vector<double> weights;
};

// Per channel, value -> (value - offset) * scale. The offset is the channel's mean (so FFT
// correlations work on centred data, which keeps their rounding small; differences do not see
// it), the scale is 1 / range or 1 / standard deviation times the weight (SAD) or its square root
// (SSD), so that the summed error weights each channel's term by exactly its weight.
struct ChannelTransform {
  std::vector<float> offset;
  std::vector<float> scale;

  // The transform of `maps` under `options`. Throws Error for a wrong number of weights or a
  // negative or non-finite weight.
  static ChannelTransform Fit(ConstImageView maps, const MatchingOptions& options);
  int channels() const { return static_cast<int>(scale.size()); }
  // The channels of `image` after the transform (one transform channel per image channel): a new
  // image, since its values differ from the sample's. Its planes (candidate positions along a row
  // contiguous) are what the vectorised searches stream through.
  Image Apply(ConstImageView image) const;
};

// The error of one pair of scaled values under `metric`.
inline double PairError(ErrorMetric metric, double a, double b) {
  const double d = a - b;
  return metric == ErrorMetric::kSsd ? d * d : (d < 0 ? -d : d);
}

// sums[i] += the squared (SSD) or absolute (SAD) difference of values[i] and `wanted`, i < count,
// in float: the vectorised inner loop of the direct searches, one term of every candidate along a
// row at a time.
inline void AccumulatePairErrors(bool squared, const float* values, float wanted, int count,
                                 float* sums) {
  if (squared) {
    for (int i = 0; i < count; ++i) {
      const float d = values[i] - wanted;
      sums[i] += d * d;
    }
  } else {
    for (int i = 0; i < count; ++i) sums[i] += std::fabs(values[i] - wanted);
  }
}

}  // namespace photomat
