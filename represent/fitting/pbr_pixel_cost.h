#pragma once

#include <ceres/cost_function.h>

#include <array>
#include <vector>

// The residuals of one pixel of the pbr fit (pbr_fit.cc), with hand-derived Jacobians. Internal
// to the fit (built only with Ceres); its own unit so that its test can check the Jacobians.
namespace photomat {

struct PbrPixelData {
  std::vector<std::array<double, 3>> lights;    // unit, towards each light
  std::vector<std::array<double, 3>> observed;  // RGB per light
};

// All observations of one pixel as one residual block: per light, the microfacet model's three
// channels (core/microfacet_brdf.h) minus the measured ones, scaled so that the block's squared
// norm is the sum over lights of Cauchy's rho(s) = b log(1 + s / b) of each light's squared
// residual s (a loss per observation, as ceres::CauchyLoss on one residual block per light would
// give; one block because Ceres' per-block work was a third of the fit's time, and the Jacobians by
// hand because automatic ones were half of the rest).
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
