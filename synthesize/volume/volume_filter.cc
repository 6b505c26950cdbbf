#include "synthesize/volume/volume_filter.h"

#include <tbb/parallel_for.h>

#include <algorithm>
#include <cmath>
#include <vector>

namespace photomat {
namespace {

int EdgeIndex(int index, int length, VolumeEdge edge) {
  if (edge == VolumeEdge::kClamp) return std::clamp(index, 0, length - 1);
  const int r = index % length;
  return r < 0 ? r + length : r;
}

// One pass along `axis` from `in` into `out` (same shape).
void BlurAxis(const Volume& in, Volume& out, int axis, const std::vector<float>& kernel,
              VolumeEdge edge) {
  const VolumeSize& size = in.size();
  const int radius = static_cast<int>(kernel.size() / 2);
  const int length = axis == 0 ? size.x : axis == 1 ? size.y : size.z;
  const std::size_t channels = static_cast<std::size_t>(in.channels());
  tbb::parallel_for(0, size.z, [&](int z) {
    std::vector<float> sum(channels);
    for (int y = 0; y < size.y; ++y) {
      for (int x = 0; x < size.x; ++x) {
        std::fill(sum.begin(), sum.end(), 0.0f);
        const int position = axis == 0 ? x : axis == 1 ? y : z;
        for (int k = -radius; k <= radius; ++k) {
          const int q = EdgeIndex(position + k, length, edge);
          const auto source = in.voxel(axis == 0 ? q : x, axis == 1 ? q : y, axis == 2 ? q : z);
          const float w = kernel[static_cast<std::size_t>(k + radius)];
          for (std::size_t c = 0; c < channels; ++c) sum[c] += w * source[c];
        }
        std::copy(sum.begin(), sum.end(), out.voxel(x, y, z).begin());
      }
    }
  });
}

}  // namespace

Volume GaussianBlur(const Volume& volume, double sigma, VolumeEdge edge) {
  if (!(sigma > 0.0) || volume.empty()) return volume;
  const int radius = std::max(1, static_cast<int>(std::ceil(3.0 * sigma)));
  std::vector<float> kernel(static_cast<std::size_t>(2 * radius + 1));
  double total = 0;
  for (int k = -radius; k <= radius; ++k) {
    total += kernel[static_cast<std::size_t>(k + radius)] =
        static_cast<float>(std::exp(-0.5 * k * k / (sigma * sigma)));
  }
  for (float& w : kernel) w = static_cast<float>(w / total);
  Volume a = volume, b = volume;
  BlurAxis(volume, a, 0, kernel, edge);
  BlurAxis(a, b, 1, kernel, edge);
  BlurAxis(b, a, 2, kernel, edge);
  return a;
}

double GaussianStackSigma(int spacing) {
  return spacing > 1 ? std::sqrt((static_cast<double>(spacing) * spacing - 1.0) / 3.0) : 0.0;
}

}  // namespace photomat
