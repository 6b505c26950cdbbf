#include "represent/fitting/pbr_pixel_cost.h"

#include <cmath>

#include "core/microfacet_brdf.h"

namespace photomat {

double CauchyShrink(double squared, double b, double* derivative) {
  const double t = squared / b;
  // Below 1e-4, log1p(t) / t = 1 - t / 2 + t^2 / 3 - t^3 / 4 + O(t^4) (the quotient is 0 / 0 at
  // t = 0; the series' error, under 2e-17, is below double rounding).
  if (t < 1e-4) {
    const double shrink = std::sqrt(1.0 - t / 2.0 + t * t / 3.0 - t * t * t / 4.0);
    if (derivative) {
      *derivative = (-0.5 + 2.0 * t / 3.0 - 0.75 * t * t) / (2.0 * shrink * b);
    }
    return shrink;
  }
  const double log_term = std::log1p(t);
  const double shrink = std::sqrt(log_term / t);
  // d(w^2)/dt = (t / (1 + t) - log1p(t)) / t^2, and dw = d(w^2) / (2 w).
  if (derivative) *derivative = (t / (1.0 + t) - log_term) / (t * t) / (2.0 * shrink * b);
  return shrink;
}

PbrPixelCost::PbrPixelCost(const PbrPixelData& data, double squared_scale)
    : data_(data), squared_scale_(squared_scale) {
  set_num_residuals(static_cast<int>(3 * data.lights.size()));
  *mutable_parameter_block_sizes() = {1, 1, 1, 1, 1, 3};
}

bool PbrPixelCost::Evaluate(double const* const* parameters, double* residuals,
                            double** jacobians) const {
  const double base[3] = {parameters[0][0], parameters[1][0], parameters[2][0]};
  const double roughness = parameters[3][0], f0 = parameters[4][0];
  const double* normal = parameters[5];
  for (std::size_t i = 0; i < data_.lights.size(); ++i) {
    const MicrofacetDerivatives d =
        MicrofacetRadianceDerivatives(normal, data_.lights[i].data(), roughness, f0);
    double e[3];
    for (int c = 0; c < 3; ++c) {
      e[c] = d.value.diffuse * base[c] + d.value.specular - data_.observed[i][c];
    }
    double shrink_derivative = 0.0;
    const double shrink = CauchyShrink(e[0] * e[0] + e[1] * e[1] + e[2] * e[2], squared_scale_,
                                       jacobians ? &shrink_derivative : nullptr);
    for (int c = 0; c < 3; ++c) residuals[3 * i + c] = e[c] * shrink;
    if (!jacobians) continue;
    // de_c / d theta for theta = base red, green, blue, roughness, F0, normal x, y, z.
    double de[3][8] = {};
    for (int c = 0; c < 3; ++c) {
      de[c][c] = d.value.diffuse;
      de[c][3] = d.specular_roughness;  // diffuse does not depend on roughness
      de[c][4] = base[c] * d.diffuse_f0 + d.specular_f0;
      for (int k = 0; k < 3; ++k) {
        de[c][5 + k] = base[c] * d.diffuse_normal[k] + d.specular_normal[k];
      }
    }
    // r_c = e_c w(s), s = sum e^2: dr_c = w de_c + e_c w'(s) 2 sum_c' e_c' de_c'.
    for (int theta = 0; theta < 8; ++theta) {
      const double ds = 2.0 * (e[0] * de[0][theta] + e[1] * de[1][theta] + e[2] * de[2][theta]);
      // Block and column of theta: blocks 0-4 are scalars, block 5 the normal.
      const int block = theta < 5 ? theta : 5;
      const int column = theta < 5 ? 0 : theta - 5;
      const int width = theta < 5 ? 1 : 3;
      if (!jacobians[block]) continue;
      for (int c = 0; c < 3; ++c) {
        const int row = static_cast<int>(3 * i) + c;
        jacobians[block][row * width + column] =
            shrink * de[c][theta] + e[c] * shrink_derivative * ds;
      }
    }
  }
  return true;
}

}  // namespace photomat
