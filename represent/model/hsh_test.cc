#include "represent/model/hsh.h"

#include <fmt/format.h>
#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include <cmath>

#include "core/error.h"
#include "core/json_file.h"
#include "represent/model/light_basis.h"

namespace photomat {
namespace {

using ::testing::HasSubstr;
using ::testing::ThrowsMessage;

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

TEST(HshTest, NineTermsMatchValuesComputedByHand) {
  // Lights where each of terms 4..8 is non-zero somewhere, with every value worked out by hand
  // from RTIViewer's formulas (c = cos(theta), s = sqrt(c - c^2)).
  const double k30 = std::sqrt(30 / M_PI), k6 = std::sqrt(6 / M_PI);
  // (0.6, 0, 0.8): c = 0.8, s = 0.4, phi = 0.
  const auto x = HshLightBasis(9).Coefficients(LightDirection::FromVector(0.6, 0, 0.8));
  const std::vector<double> x_by_hand = {1 / std::sqrt(2 * M_PI),
                                         0.4 * k6,
                                         0.6 * std::sqrt(3 / (2 * M_PI)),
                                         0,
                                         -0.16 * k30,
                                         0.24 * k30,
                                         0.04 * std::sqrt(5 / (2 * M_PI)),
                                         0,
                                         0};
  // (0, 0.6, 0.8): phi = 90 degrees, so cos(2 phi) = -1 and the sine terms take over.
  const auto y = HshLightBasis(9).Coefficients(LightDirection::FromVector(0, 0.6, 0.8));
  const std::vector<double> y_by_hand = {
      x_by_hand[0], 0, x_by_hand[2], 0.4 * k6, 0.16 * k30, 0, x_by_hand[6], 0.24 * k30, 0};
  // Slant 60, tilt 45: c = 0.5, s = 0.5, cos(phi) = sin(phi) = 1 / sqrt(2), sin(2 phi) = 1.
  const auto d = HshLightBasis(9).Coefficients(LightDirection::FromSlantTilt(60, 45));
  const std::vector<double> d_by_hand = {x_by_hand[0],
                                         0.5 * k6 / std::sqrt(2),
                                         0,
                                         0.5 * k6 / std::sqrt(2),
                                         0,
                                         0,
                                         -0.5 * std::sqrt(5 / (2 * M_PI)),
                                         0,
                                         -0.25 * k30};
  for (int j = 0; j < 9; ++j) {
    EXPECT_NEAR(x[j], x_by_hand[j], 1e-12) << "term " << j;
    EXPECT_NEAR(y[j], y_by_hand[j], 1e-12) << "term " << j;
    EXPECT_NEAR(d[j], d_by_hand[j], 1e-12) << "term " << j;
  }
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

}  // namespace
}  // namespace photomat
