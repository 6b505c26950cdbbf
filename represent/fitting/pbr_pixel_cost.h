#pragma once

#include <ceres/cost_function.h>

#include <array>
#include <vector>

#include "core/microfacet_brdf.h"

// The residuals of one pixel of the pbr fit (pbr_fit.cc), with hand-derived Jacobians. Internal
// to the fit (built only with Ceres); its own unit so that its test can check the Jacobians.
namespace photomat {

struct PbrPixelData {
  std::vector<MicrofacetLight> lights;          // each light's own terms (its direction, unit)
  std::vector<double> irradiance;               // each light's at the pixel (near lamps), else 1
  std::vector<std::array<double, 3>> observed;  // RGB per light
};

// The parameters of the fit in one order: base red, green, blue, perceptual roughness, F0, then
// the normal's x, y, z (a free 3-vector here; the fit keeps it on the unit sphere).
inline constexpr int kPbrParameters = 8;

// The three residuals of one light (red, green, blue): the microfacet model's channels
// (core/microfacet_brdf.h) times the light's `irradiance` at the pixel minus the measured ones,
// scaled by sqrt(rho(s) / s) so that their squared norm is Cauchy's rho(s) = b log(1 + s / b) of
// their unscaled squared norm s (a loss per observation, as ceres::CauchyLoss on one residual block
// per light would give). Returns rho(s). `residuals` (3 values) may be null: rho alone, for a trial
// step's cost. `jacobian`, if given, gets the residuals' derivatives by the parameters (3 x
// kPbrParameters, row-major).
double PbrLightResiduals(const MicrofacetSurface& surface, const double* base,
                         const MicrofacetLight& light, double irradiance,
                         const std::array<double, 3>& observed, double squared_scale,
                         double* residuals, double* jacobian);

// All observations of one pixel as one residual block of kPbrParameters + 1 residuals: the 3 x
// lights residuals r of PbrLightResiduals (Jacobian J) compressed to a square root of their normal
// equations (IMPLEMENTER CHOICE). With J^T J = P^T L D L^T P (pivoted LDLT), the block's Jacobian
// is R = D^(1/2) L^T P and its residuals (r', z) with R^T r' = J^T r and z^2 = |r|^2 - |r'|^2:
// the same cost, gradient and Gauss-Newton matrix, so Ceres' trust-region steps are those of the
// 3 x lights rows to rounding, while its per-evaluation work (checking, copying and scaling the
// Jacobian, forming J^T J) is on 9 rows instead of 288 for DiLiGenT (it was a fifth of the fit's
// time). Ceres evaluates a trial step's cost alone (no Jacobians): then the residuals are
// (|r|, 0, ..., 0) and the derivatives are skipped.
// Parameter blocks, in order: base red, green, blue (1 each, so that each can be held on its
// bound), perceptual roughness (1), F0 (1), normal (3).
class PbrPixelCost : public ceres::CostFunction {
 public:
  // `data` must outlive the cost; `squared_scale` is b.
  PbrPixelCost(const PbrPixelData& data, double squared_scale);

  bool Evaluate(double const* const* parameters, double* residuals,
                double** jacobians) const override;

 private:
  const PbrPixelData& data_;
  double squared_scale_;
};

// sqrt(rho(s) / s) for Cauchy's rho with squared scale b: the factor that turns a residual of
// squared norm s into one of squared norm rho(s); 1 at s = 0. `derivative`, if given, gets its
// derivative by s.
double CauchyShrink(double squared, double b, double* derivative = nullptr);

}  // namespace photomat
