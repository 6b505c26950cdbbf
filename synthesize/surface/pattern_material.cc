#include "synthesize/surface/pattern_material.h"

#include <algorithm>

#include "core/error.h"
#include "represent/model/light_basis.h"
#include "represent/surface/surface_integration.h"

namespace photomat {

Image GridFieldImage(const GridShape& grid, const Eigen::VectorXd& field,
                     const std::string& channel) {
  if (field.size() != static_cast<Eigen::Index>(grid.width) * grid.height) {
    throw Error("grid image: one value per grid node needed");
  }
  Image image(grid.width, grid.height, {channel});
  for (Eigen::Index i = 0; i < field.size(); ++i)
    image.pixel(static_cast<std::size_t>(i))[0] = static_cast<float>(field[i]);
  return image;
}

Representation PatternMaterial(const GridShape& grid, const Eigen::VectorXd& field,
                               const PatternMaterialOptions& options) {
  if (field.size() != static_cast<Eigen::Index>(grid.width) * grid.height) {
    throw Error("pattern material: one value per grid node needed");
  }
  if (!(options.relief_pixels >= 0.0)) throw Error("pattern material: relief must not be negative");
  const double low = field.minCoeff(), high = field.maxCoeff();
  const double range = high > low ? high - low : 1.0;
  const int w = grid.width, h = grid.height;
  auto t = [&](int x, int y) {  // normalised field in [0, 1], wrapping
    const double v = (field[((y + h) % h) * w + (x + w) % w] - low) / range;
    return options.invert_height ? 1.0 - v : v;
  };
  Image gradients(w, h, {"p", "q"});
  for (int y = 0; y < h; ++y) {
    for (int x = 0; x < w; ++x) {
      // p = ds/dx; q = ds/dy with y up, i.e. toward row y - 1.
      gradients.at(x, y, 0) =
          static_cast<float>(0.5 * options.relief_pixels * (t(x + 1, y) - t(x - 1, y)));
      gradients.at(x, y, 1) =
          static_cast<float>(0.5 * options.relief_pixels * (t(x, y - 1) - t(x, y + 1)));
    }
  }
  const Image normals = NormalsFromGradients(gradients);
  Image maps(w, h, {"normal.X", "normal.Y", "normal.Z", "albedo.R", "albedo.G", "albedo.B"});
  for (int y = 0; y < h; ++y) {
    for (int x = 0; x < w; ++x) {
      const auto pixel = maps.pixel(x, y);
      for (int c = 0; c < 3; ++c) pixel[c] = normals.at(x, y, c);
      const float mix = static_cast<float>(t(x, y));
      for (int c = 0; c < 3; ++c) {
        pixel[3 + c] = (1.0f - mix) * options.low_albedo[c] + mix * options.high_albedo[c];
      }
    }
  }
  return Representation("gradient", std::move(maps), {3, false, true, 3},
                        LinearLightBasis::Lambertian());
}

}  // namespace photomat
