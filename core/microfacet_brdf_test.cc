#include "core/microfacet_brdf.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <numbers>

#include "core/random.h"

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

// The hand-derived derivatives against central differences of MicrofacetRadiance, at 2000 seeded
// random (normal, light, roughness, F0) with both in front of the camera, roughness down to the
// fit's floor 0.05 (where the lobe is sharpest). Largest error over the derivative's scale (the
// largest of |derivative| and the function's value), measured: 5.1e-3, 5.1e-5 and 5.1e-7 with
// steps 1e-5, 1e-6 and 1e-7: the differences' own step^2 error, so the derivatives are right to
// at least 5e-7; bound 5e-6 with step 1e-7.
TEST(MicrofacetBrdfTest, HandDerivedDerivativesMatchCentralDifferences) {
  Random random(20261203);
  double worst = 0.0;
  int checked = 0;
  while (checked < 2000) {
    double normal[3] = {random.Normal(), random.Normal(), std::abs(random.Normal()) + 0.1};
    double light[3] = {random.Normal(), random.Normal(), std::abs(random.Normal())};
    const double nn =
        std::sqrt(normal[0] * normal[0] + normal[1] * normal[1] + normal[2] * normal[2]);
    const double ln = std::sqrt(light[0] * light[0] + light[1] * light[1] + light[2] * light[2]);
    for (int k = 0; k < 3; ++k) normal[k] /= nn, light[k] /= ln;
    const double roughness = random.Uniform(0.05, 1.0), f0 = random.Uniform(0.0, 1.0);
    const MicrofacetDerivatives d = MicrofacetRadianceDerivatives(normal, light, roughness, f0);
    const MicrofacetResponse<double> value = MicrofacetRadiance(normal, light, roughness, f0);
    if (value.diffuse <= 1e-3) continue;  // at or near the terminator, where n.l has a kink
    ++checked;
    // The same formulas, in another order (h normalised first): rounding apart.
    EXPECT_NEAR(d.value.diffuse, value.diffuse, 1e-12 * value.diffuse);
    EXPECT_NEAR(d.value.specular, value.specular, 1e-12 * value.specular);
    constexpr double kStep = 1e-7;
    const auto compare = [&](double analytic, double plus_diffuse, double minus_diffuse,
                             double plus_specular, double minus_specular,
                             double analytic_specular) {
      const double fd_diffuse = (plus_diffuse - minus_diffuse) / (2 * kStep);
      const double fd_specular = (plus_specular - minus_specular) / (2 * kStep);
      worst = std::max(worst, std::abs(analytic - fd_diffuse) /
                                  std::max({std::abs(fd_diffuse), value.diffuse, 1e-3}));
      worst = std::max(worst, std::abs(analytic_specular - fd_specular) /
                                  std::max({std::abs(fd_specular), value.specular, 1e-3}));
    };
    {
      const auto plus = MicrofacetRadiance(normal, light, roughness + kStep, f0);
      const auto minus = MicrofacetRadiance(normal, light, roughness - kStep, f0);
      compare(0.0, plus.diffuse, minus.diffuse, plus.specular, minus.specular,
              d.specular_roughness);
    }
    {
      const auto plus = MicrofacetRadiance(normal, light, roughness, f0 + kStep);
      const auto minus = MicrofacetRadiance(normal, light, roughness, f0 - kStep);
      compare(d.diffuse_f0, plus.diffuse, minus.diffuse, plus.specular, minus.specular,
              d.specular_f0);
    }
    for (int k = 0; k < 3; ++k) {
      double up[3] = {normal[0], normal[1], normal[2]}, down[3] = {normal[0], normal[1], normal[2]};
      up[k] += kStep;
      down[k] -= kStep;
      const auto plus = MicrofacetRadiance(up, light, roughness, f0);
      const auto minus = MicrofacetRadiance(down, light, roughness, f0);
      compare(d.diffuse_normal[k], plus.diffuse, minus.diffuse, plus.specular, minus.specular,
              d.specular_normal[k]);
    }
  }
  std::printf("largest derivative error over its scale: %.3g\n", worst);
  EXPECT_LT(worst, 5e-6);
}

}  // namespace
}  // namespace photomat
