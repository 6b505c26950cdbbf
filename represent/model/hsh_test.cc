#include "represent/model/hsh.h"

#include <fmt/format.h>
#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include <cmath>

#include "capture/synthetic/synthetic_capture.h"
#include "core/error.h"
#include "core/json_file.h"
#include "core/photometric_set.h"
#include "represent/evaluation/evaluation.h"
#include "represent/fitting/fit.h"
#include "represent/model/light_basis.h"

namespace photomat {
namespace {

using ::testing::HasSubstr;
using ::testing::ThrowsMessage;

// Lights at five slants (15..75) x 12 tilts: enough distinct slants for 16 terms.
std::vector<LightDirection> FiveRingDome() {
  std::vector<LightDirection> lights;
  for (int slant = 15; slant <= 75; slant += 15) {
    for (int tilt = 0; tilt < 360; tilt += 30) {
      lights.push_back(LightDirection::FromSlantTilt(slant, tilt + slant));
    }
  }
  return lights;
}

TEST(HshTest, TheBasisIsOrthonormalOverTheHemisphere) {
  // Midpoint quadrature in (cos theta, phi): d omega = d(cos theta) d phi.
  const int n_c = 400, n_phi = 400;
  const HshLightBasis basis(16);
  Eigen::MatrixXd gram = Eigen::MatrixXd::Zero(16, 16);
  for (int i = 0; i < n_c; ++i) {
    const double c = (i + 0.5) / n_c;
    const double s = std::sqrt(1 - c * c);
    for (int j = 0; j < n_phi; ++j) {
      const double phi = 2 * M_PI * (j + 0.5) / n_phi;
      const Eigen::VectorXd h =
          basis.Coefficients(LightDirection::FromVector(s * std::cos(phi), s * std::sin(phi), c));
      gram += h * h.transpose() * (1.0 / n_c) * (2 * M_PI / n_phi);
    }
  }
  EXPECT_LT((gram - Eigen::MatrixXd::Identity(16, 16)).cwiseAbs().maxCoeff(), 2e-3);
}

TEST(HshTest, TermOrderFollowsRtiViewer) {
  // Overhead: only the m = 0 terms survive, at their x = 2c - 1 = 1 values.
  const Eigen::VectorXd top = HshLightBasis(16).Coefficients(LightDirection::FromVector(0, 0, 1));
  EXPECT_NEAR(top[0], 1 / std::sqrt(2 * M_PI), 1e-12);
  EXPECT_NEAR(top[2], std::sqrt(3 / (2 * M_PI)), 1e-12);
  EXPECT_NEAR(top[6], std::sqrt(5 / (2 * M_PI)), 1e-12);
  EXPECT_NEAR(top[12], std::sqrt(7 / (2 * M_PI)), 1e-12);
  for (int j : {1, 3, 4, 5, 7, 8, 9, 10, 11, 13, 14, 15}) EXPECT_NEAR(top[j], 0, 1e-12) << j;
  // A light along +x has phi = 0: cosine terms (m < 0) only; along +y the sine terms.
  const auto x = HshLightBasis(9).Coefficients(LightDirection::FromSlantTilt(60, 0));
  const auto y = HshLightBasis(9).Coefficients(LightDirection::FromSlantTilt(60, 90));
  const double c = 0.5, s = std::sqrt(c - c * c);
  EXPECT_NEAR(x[1], std::sqrt(6 / M_PI) * s, 1e-12);
  EXPECT_NEAR(x[3], 0, 1e-12);
  EXPECT_NEAR(y[3], std::sqrt(6 / M_PI) * s, 1e-12);
  EXPECT_NEAR(x[4], std::sqrt(30 / M_PI) * (c * c - c), 1e-12);
  EXPECT_NEAR(y[4], -std::sqrt(30 / M_PI) * (c * c - c), 1e-12);  // cos(2 phi) = -1
  // Below the horizon the light is evaluated at the horizon.
  EXPECT_TRUE(HshLightBasis(9)
                  .Coefficients(LightDirection::FromVector(1, 0, -0.3))
                  .isApprox(HshLightBasis(9).Coefficients(LightDirection::FromVector(1, 0, 0))));
  EXPECT_THROW(HshLightBasis(6), Error);
}

TEST(HshTest, BasisSurvivesJson) {
  const nlohmann::json json = HshLightBasis(9).ToJson();
  const auto basis = LightBasisFromJson(JsonReader(json, "stack.exr", "basis"));
  EXPECT_EQ(basis->kind(), "hsh");
  EXPECT_EQ(basis->size(), 9);
  const nlohmann::json bad = {{"kind", "hsh"}, {"terms", 7}};
  EXPECT_THAT([&] { LightBasisFromJson(JsonReader(bad, "stack.exr", "basis")); },
              ThrowsMessage<Error>(HasSubstr("stack.exr: basis: hemispherical harmonics have 4, "
                                             "9 or 16 terms, not 7")));
}

// Images whose pixels are known HSH combinations: the fit must return the coefficients.
TEST(HshTest, FitRecoversKnownCoefficientsForEveryOrder) {
  const auto lights = FiveRingDome();
  for (int terms : {4, 9, 16}) {
    Eigen::VectorXd truth(terms);
    for (int j = 0; j < terms; ++j) truth[j] = 0.3 * std::sin(1.7 * j + 0.4) + (j == 0 ? 1 : 0);
    std::vector<Image> images;
    for (const auto& light : lights) {
      Image image(3, 2, 3);
      const double value = truth.dot(HshLightBasis(terms).Coefficients(light));
      for (std::size_t p = 0; p < image.pixel_count(); ++p) {
        for (int c = 0; c < 3; ++c) image.pixel(p)[c] = static_cast<float>(value * (1 + 0.2 * c));
      }
      images.push_back(image);
    }
    const Method method = Method::Parse(fmt::format("hsh{}", terms));
    const Representation hsh = Fit(PhotometricSet(images, lights), method);
    EXPECT_EQ(hsh.method(), method.Name());
    EXPECT_EQ(hsh.maps().channel_names()[3 * 2 + 1], "hsh.h2.G");
    for (int j = 0; j < terms; ++j) {
      for (int c = 0; c < 3; ++c) {
        EXPECT_NEAR(hsh.maps().at(2, 1, j * 3 + c), truth[j] * (1 + 0.2 * c), 2e-5)
            << terms << " terms, term " << j;
      }
    }
    // Relighting at a light that was not captured evaluates the same function.
    const auto light = LightDirection::FromSlantTilt(52, 200);
    EXPECT_NEAR(hsh.Relight(light).at(0, 0, 0), truth.dot(HshLightBasis(terms).Coefficients(light)),
                2e-5);
  }
}

TEST(HshTest, SixteenTermsNeedFourSlants) {
  // The thesis grid has three slants: the four m = 0 terms of 16-term HSH depend on the slant
  // only and cannot be separated.
  std::vector<Image> images(36, Image(2, 2, 1));
  for (std::size_t i = 0; i < images.size(); ++i) {
    for (float& v : images[i].values()) v = 0.4f + 0.01f * static_cast<float>(i);
  }
  const PhotometricSet set(images, ThesisLightGrid(), {}, "grid.lp");
  EXPECT_THAT([&] { Fit(set, Method::Parse("hsh16")); },
              ThrowsMessage<Error>(HasSubstr("grid.lp: hsh16: the 36 lights do not determine the "
                                             "16 hemispherical-harmonic coefficients")));
  EXPECT_NO_THROW(Fit(set, Method::Parse("hsh9")));
}

TEST(HshTest, EvaluateScoresEveryOrder) {
  // A shadowed, glossy sample under the five-ring dome: more terms fit the captured images better,
  // and leave-one-out prediction works for every order.
  SyntheticMaterialOptions material;
  material.width = material.height = 24;
  material.max_slope_degrees = 45;
  SyntheticRenderOptions render;
  render.shadows = true;
  render.specular = 0.3;
  const PhotometricSet set =
      RenderSyntheticCapture(MakeSyntheticMaterial(material), FiveRingDome(), render);
  const Observations observations(set);
  double previous = INFINITY;
  for (const char* name : {"hsh4", "hsh9", "hsh16"}) {
    const MethodEvaluation evaluation =
        EvaluateMethod(set, observations, Method::Parse(name), nullptr);
    EXPECT_LT(evaluation.eta_reconstruction, previous) << name;
    ASSERT_TRUE(evaluation.eta_prediction) << name;
    EXPECT_GT(*evaluation.eta_prediction, evaluation.eta_reconstruction) << name;
    EXPECT_LT(*evaluation.eta_prediction, 1.0) << name;
    previous = evaluation.eta_reconstruction;
    ::testing::Test::RecordProperty(
        std::string(name) + "_eta",
        fmt::format("{:.4f} / {:.4f}", evaluation.eta_reconstruction, *evaluation.eta_prediction));
  }
}

}  // namespace
}  // namespace photomat
