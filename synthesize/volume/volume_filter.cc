#include "synthesize/volume/volume_filter.h"

#include <tbb/parallel_for.h>

#include <algorithm>
#include <cmath>
#include <vector>

#include "core/wrap.h"

namespace photomat {
namespace {

int EdgeIndex(int index, int length, VolumeEdge edge) {
  return edge == VolumeEdge::kClamp ? std::clamp(index, 0, length - 1) : Wrap(index, length);
}

// One pass along `axis` from `in` into `out` (same shape), plane by plane.
void BlurAxis(const Image& in, Image& out, int axis, const std::vector<float>& kernel,
              VolumeEdge edge) {
  const ImageExtent& size = in.extent();
  const int radius = static_cast<int>(kernel.size() / 2);
  const int length = axis == 0 ? size.width : axis == 1 ? size.height : size.depth;
  // Distance between neighbours along the axis, in a plane.
  const std::ptrdiff_t step = axis == 0   ? 1
                              : axis == 1 ? static_cast<std::ptrdiff_t>(size.width)
                                          : static_cast<std::ptrdiff_t>(size.width) * size.height;
  tbb::parallel_for(0, size.depth, [&](int z) {
    for (int c = 0; c < in.channels(); ++c) {
      const float* source = in.plane(c).data();
      float* target = out.plane(c).data();
      for (int y = 0; y < size.height; ++y) {
        for (int x = 0; x < size.width; ++x) {
          const int position = axis == 0 ? x : axis == 1 ? y : z;
          const std::size_t index = in.Index(x, y, z);
          const float* line = source + static_cast<std::ptrdiff_t>(index) - position * step;
          float sum = 0.0f;
          for (int k = -radius; k <= radius; ++k) {
            sum += kernel[static_cast<std::size_t>(k + radius)] *
                   line[EdgeIndex(position + k, length, edge) * step];
          }
          target[index] = sum;
        }
      }
    }
  });
}

}  // namespace

Image GaussianBlur(const Image& volume, double sigma, VolumeEdge edge) {
  if (!(sigma > 0.0) || volume.empty()) return volume;
  const int radius = std::max(1, static_cast<int>(std::ceil(3.0 * sigma)));
  std::vector<float> kernel(static_cast<std::size_t>(2 * radius + 1));
  double total = 0;
  for (int k = -radius; k <= radius; ++k) {
    total += kernel[static_cast<std::size_t>(k + radius)] =
        static_cast<float>(std::exp(-0.5 * k * k / (sigma * sigma)));
  }
  for (float& w : kernel) w = static_cast<float>(w / total);
  Image a = volume, b = volume;
  BlurAxis(volume, a, 0, kernel, edge);
  BlurAxis(a, b, 1, kernel, edge);
  BlurAxis(b, a, 2, kernel, edge);
  return a;
}

double GaussianStackSigma(int spacing) {
  return spacing > 1 ? std::sqrt((static_cast<double>(spacing) * spacing - 1.0) / 3.0) : 0.0;
}

}  // namespace photomat
