#include "core/microfacet_brdf.h"

#include <gtest/gtest.h>

#include <cmath>
#include <numbers>

namespace photomat {
namespace {

constexpr double kPi = std::numbers::pi;
const double kUp[3] = {0.0, 0.0, 1.0};

MicrofacetResponse<double> At(const double* normal, double slant_degrees, double roughness,
                              double f0) {
  const double s = slant_degrees * kPi / 180.0;
  const double light[3] = {std::sin(s), 0.0, std::cos(s)};
  return MicrofacetRadiance(normal, light, roughness, f0);
}

TEST(MicrofacetBrdfTest, MirrorPeakIsF0OverFourAlphaSquared) {
  // n = l = v: D = 1 / (pi alpha^2), V = 1/4, F = F0, so pi F D V = F0 / (4 alpha^2) with
  // alpha = roughness^2 (the glTF mapping; alpha = roughness would give F0 / (4 roughness^2)).
  for (double roughness : {0.2, 0.5, 0.9}) {
    const MicrofacetResponse<double> r = At(kUp, 0.0, roughness, 0.05);
    EXPECT_NEAR(r.specular, 0.05 / (4 * std::pow(roughness, 4)), 1e-9) << roughness;
    EXPECT_NEAR(r.diffuse, 0.95, 1e-12);  // (1 - F) n.l
  }
}

TEST(MicrofacetBrdfTest, SpecularAlbedoIsAtMostOneAndNearlyOneWhenSmooth) {
  // Integral over the hemisphere of lights of f_spec cos = specular / pi: the single-scattering
  // directional albedo at normal view, with F0 = 1. Single scattering loses little energy when
  // smooth and much when rough: measured 0.9907 at roughness 0.3 (bound 0.985) and 0.4200 at 0.9
  // (bound 0.40, 5 % below; an independent Python quadrature of the same formulas gave 0.99067
  // and 0.41997, and of D alone (D n.h over the hemisphere) 1.0000).
  for (const auto& [roughness, low] : {std::pair{0.3, 0.985}, std::pair{0.9, 0.40}}) {
    double albedo = 0.0;
    constexpr int kSteps = 4000;
    for (int i = 0; i < kSteps; ++i) {
      const double theta = (i + 0.5) * (kPi / 2) / kSteps;
      albedo += At(kUp, theta * 180 / kPi, roughness, 1.0).specular / kPi * 2 * kPi *
                std::sin(theta) * (kPi / 2) / kSteps;
    }
    EXPECT_LE(albedo, 1.0 + 1e-3) << roughness;
    EXPECT_GE(albedo, low) << roughness;
  }
}

TEST(MicrofacetBrdfTest, ZeroBelowTheHorizonAndFresnelRisesAtGrazing) {
  EXPECT_EQ(At(kUp, 95.0, 0.5, 0.04).diffuse, 0.0);
  EXPECT_EQ(At(kUp, 95.0, 0.5, 0.04).specular, 0.0);
  const double away[3] = {0.0, std::sin(1.7), std::cos(1.7)};  // faces away from the camera
  EXPECT_EQ(At(away, 0.0, 0.5, 0.04).diffuse, 0.0);
  // F0 = 0: Schlick's (1 - v.h)^5 alone, tiny for lights up to slant 60 (v.h >= cos 30).
  EXPECT_LT(1.0 - At(kUp, 60.0, 0.5, 0.0).diffuse / std::cos(kPi / 3), 5e-5);
  // Slant 89: v.h = cos 44.5 degrees, F = F0 + (1 - F0) (1 - v.h)^5.
  const double grazing = 1.0 - At(kUp, 89.0, 0.5, 0.04).diffuse / std::cos(89 * kPi / 180);
  EXPECT_NEAR(grazing, 0.04 + 0.96 * std::pow(1.0 - std::cos(44.5 * kPi / 180), 5), 1e-9);
}

}  // namespace
}  // namespace photomat
