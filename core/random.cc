#include "core/random.h"

#include <cmath>
#include <numbers>

#include "core/image.h"

namespace photomat {

double Random::Normal() {
  if (has_spare_) {
    has_spare_ = false;
    return spare_;
  }
  const double u1 = 1.0 - Uniform();  // (0, 1]: log stays finite
  const double u2 = Uniform();
  const double radius = std::sqrt(-2.0 * std::log(u1));
  spare_ = radius * std::sin(2.0 * std::numbers::pi * u2);
  has_spare_ = true;
  return radius * std::cos(2.0 * std::numbers::pi * u2);
}

void AddGaussianNoise(Image& image, double sigma, Random& random) {
  for (std::size_t p = 0; p < image.pixel_count(); ++p) {
    for (float& v : image.pixel(p)) v += static_cast<float>(sigma * random.Normal());
  }
}

}  // namespace photomat
