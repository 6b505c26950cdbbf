#include "represent/fitting/pbr_pixel_cost.h"

#include <Eigen/Cholesky>
#include <Eigen/Core>
#include <algorithm>
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

namespace {

// The response (and its derivatives) of a light of irradiance `factor`: all linear in it.
void ScaleResponse(double factor, MicrofacetDerivatives& d) {
  d.value.diffuse *= factor;
  d.value.specular *= factor;
  d.diffuse_f0 *= factor;
  d.specular_roughness *= factor;
  d.specular_f0 *= factor;
  for (int k = 0; k < 3; ++k) {
    d.diffuse_normal[k] *= factor;
    d.specular_normal[k] *= factor;
  }
}

}  // namespace

double PbrLightResiduals(const MicrofacetSurface& surface, const double* base,
                         const MicrofacetLight& light, double irradiance,
                         const std::array<double, 3>& observed, double squared_scale,
                         double* residuals, double* jacobian) {
  MicrofacetDerivatives d = MicrofacetRadianceDerivatives(surface, light, jacobian != nullptr);
  if (irradiance != 1.0) ScaleResponse(irradiance, d);
  double e[3];
  for (int c = 0; c < 3; ++c) e[c] = d.value.diffuse * base[c] + d.value.specular - observed[c];
  const double squared = e[0] * e[0] + e[1] * e[1] + e[2] * e[2];
  // A trial step's cost: rho itself, without the shrink's square root and quotient.
  if (!residuals) return squared_scale * std::log1p(squared / squared_scale);
  double shrink_derivative = 0.0;
  const double shrink =
      CauchyShrink(squared, squared_scale, jacobian ? &shrink_derivative : nullptr);
  for (int c = 0; c < 3; ++c) residuals[c] = e[c] * shrink;
  const double rho = squared * shrink * shrink;
  if (!jacobian) return rho;
  // de_c / d theta for theta = base red, green, blue, roughness, F0, normal x, y, z.
  double de[3][kPbrParameters] = {};
  for (int c = 0; c < 3; ++c) {
    de[c][c] = d.value.diffuse;
    de[c][3] = d.specular_roughness;  // diffuse does not depend on roughness
    de[c][4] = base[c] * d.diffuse_f0 + d.specular_f0;
    for (int k = 0; k < 3; ++k) de[c][5 + k] = base[c] * d.diffuse_normal[k] + d.specular_normal[k];
  }
  // r_c = e_c w(s), s = sum e^2: dr_c = w de_c + e_c w'(s) 2 sum_c' e_c' de_c'.
  for (int theta = 0; theta < kPbrParameters; ++theta) {
    const double ds = 2.0 * (e[0] * de[0][theta] + e[1] * de[1][theta] + e[2] * de[2][theta]);
    for (int c = 0; c < 3; ++c) {
      jacobian[c * kPbrParameters + theta] = shrink * de[c][theta] + e[c] * shrink_derivative * ds;
    }
  }
  return rho;
}

PbrPixelCost::PbrPixelCost(const PbrPixelData& data, double squared_scale)
    : data_(data), squared_scale_(squared_scale) {
  set_num_residuals(kPbrParameters + 1);
  *mutable_parameter_block_sizes() = {1, 1, 1, 1, 1, 3};
}

bool PbrPixelCost::Evaluate(double const* const* parameters, double* residuals,
                            double** jacobians) const {
  using Matrix8 = Eigen::Matrix<double, kPbrParameters, kPbrParameters>;
  using Vector8 = Eigen::Matrix<double, kPbrParameters, 1>;
  const double base[3] = {parameters[0][0], parameters[1][0], parameters[2][0]};
  // The terms of the surface once for all lights.
  const MicrofacetSurface surface(parameters[5], parameters[3][0], parameters[4][0]);
  double squared = 0.0;  // |r|^2
  if (!jacobians) {
    for (std::size_t i = 0; i < data_.lights.size(); ++i) {
      squared += PbrLightResiduals(surface, base, data_.lights[i], data_.irradiance[i],
                                   data_.observed[i], squared_scale_, nullptr, nullptr);
    }
    std::fill(residuals, residuals + kPbrParameters + 1, 0.0);
    residuals[0] = std::sqrt(squared);
    return true;
  }
  // J^T J (upper triangle) and J^T r, by hand: Eigen's general product kernels, built for large
  // matrices, took a third of the fit's time on these 3 x 8 updates.
  double upper[kPbrParameters][kPbrParameters] = {};
  double gradient_sum[kPbrParameters] = {};
  for (std::size_t i = 0; i < data_.lights.size(); ++i) {
    double r[3];
    double rows[3 * kPbrParameters];
    squared += PbrLightResiduals(surface, base, data_.lights[i], data_.irradiance[i],
                                 data_.observed[i], squared_scale_, r, rows);
    const double* g0 = rows;
    const double* g1 = rows + kPbrParameters;
    const double* g2 = rows + 2 * kPbrParameters;
    for (int a = 0; a < kPbrParameters; ++a) {
      gradient_sum[a] += g0[a] * r[0] + g1[a] * r[1] + g2[a] * r[2];
      for (int b = a; b < kPbrParameters; ++b)
        upper[a][b] += g0[a] * g0[b] + g1[a] * g1[b] + g2[a] * g2[b];
    }
  }
  Matrix8 normal_matrix;  // J^T J
  Vector8 gradient;       // J^T r
  for (int a = 0; a < kPbrParameters; ++a) {
    gradient[a] = gradient_sum[a];
    for (int b = a; b < kPbrParameters; ++b)
      normal_matrix(a, b) = normal_matrix(b, a) = upper[a][b];
  }
  // The square root R = D^(1/2) L^T P of J^T J = P^T L D L^T P, and r' = D^(-1/2) L^-1 P J^T r
  // (0 where D is: J^T r has no part there). Pivots under 1e-14 of the largest are rounding of a
  // direction the data do not constrain.
  const Eigen::LDLT<Matrix8> ldlt(normal_matrix);
  Matrix8 permutation = Matrix8::Identity();
  permutation = ldlt.transpositionsP() * permutation;
  const Vector8 pivots = ldlt.vectorD();
  const double smallest = 1e-14 * std::max(pivots.maxCoeff(), 0.0);
  Vector8 root_pivots, compressed;
  const Vector8 solved =
      ldlt.matrixL().solve(permutation * gradient);  // L^-1 P J^T r (L unit lower)
  for (int k = 0; k < kPbrParameters; ++k) {
    const bool kept = pivots[k] > smallest;
    root_pivots[k] = kept ? std::sqrt(pivots[k]) : 0.0;
    compressed[k] = kept ? solved[k] / root_pivots[k] : 0.0;
  }
  const Matrix8 root = root_pivots.asDiagonal() * Matrix8(ldlt.matrixL()).transpose() * permutation;
  // |r'| <= |r| exactly (r' is r's part in the range of J); rounding may break that at a
  // perfect fit, where both vanish: then r' is shortened to |r|, z = 0.
  const double projected = compressed.squaredNorm();
  if (projected > squared) compressed *= std::sqrt(squared / projected);
  for (int k = 0; k < kPbrParameters; ++k) residuals[k] = compressed[k];
  residuals[kPbrParameters] = std::sqrt(std::max(0.0, squared - projected));
  // Jacobian rows: R's, then a zero row for z.
  for (int theta = 0; theta < kPbrParameters; ++theta) {
    // Block and column of theta: blocks 0-4 are scalars, block 5 the normal.
    const int block = theta < 5 ? theta : 5;
    const int column = theta < 5 ? 0 : theta - 5;
    const int width = theta < 5 ? 1 : 3;
    if (!jacobians[block]) continue;
    for (int row = 0; row < kPbrParameters; ++row) {
      jacobians[block][row * width + column] = root(row, theta);
    }
    jacobians[block][kPbrParameters * width + column] = 0.0;
  }
  return true;
}

}  // namespace photomat
