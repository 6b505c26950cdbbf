// Fitting HSH (hemispherical harmonics, represent/model/hsh.h) to photometric sets.
#include <fmt/format.h>
#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include <cmath>

#include "core/error.h"
#include "core/photometric_set.h"
#include "represent/fitting/fit.h"
#include "represent/model/hsh.h"
#include "tests/support/synthetic_sets.h"

namespace photomat {
namespace {

using ::testing::HasSubstr;
using ::testing::ThrowsMessage;

// Images whose pixels are known HSH combinations: the fit must return the coefficients.
TEST(HshTest, FitRecoversKnownCoefficientsForEveryOrder) {
  const auto lights = testing::FiveRingDome();
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

// Four-term HSH written out by hand in the light's x, y, z (RTIViewer's order, as
// represent/model/hsh.h states it), independent of HshLightBasis: with c = z, sin(theta) cos(phi) =
// x and sqrt(c - c^2) = sin(theta) sqrt(c / (1 + c)), h1 = sqrt(6 / pi) x sqrt(c / (1 + c)),
// h2 = sqrt(3 / (2 pi)) (2c - 1), h3 = sqrt(6 / pi) y sqrt(c / (1 + c)), h0 = 1 / sqrt(2 pi).
double Hsh4ByHand(const Eigen::Vector4d& a, const LightDirection& light) {
  const double c = light.z(), k = std::sqrt(c / (1 + c));
  return a[0] / std::sqrt(2 * M_PI) + a[1] * std::sqrt(6 / M_PI) * light.x() * k +
         a[2] * std::sqrt(3 / (2 * M_PI)) * (2 * c - 1) +
         a[3] * std::sqrt(6 / M_PI) * light.y() * k;
}

TEST(HshTest, FourTermFitFollowsTheClosedForm) {
  const auto lights = testing::FiveRingDome();
  const Eigen::Vector4d truth(1.1, 0.3, -0.25, 0.15);
  std::vector<Image> images;
  for (const auto& light : lights) {
    Image image(2, 2, 1);
    for (float& v : image.values()) v = static_cast<float>(Hsh4ByHand(truth, light));
    images.push_back(image);
  }
  const Representation hsh = Fit(PhotometricSet(images, lights), Method::Parse("hsh4"));
  for (int j = 0; j < 4; ++j) EXPECT_NEAR(hsh.maps().at(1, 0, j), truth[j], 2e-5) << "term " << j;
  for (const auto& light :
       {LightDirection::FromSlantTilt(52, 200), LightDirection::FromSlantTilt(23, 71)}) {
    EXPECT_NEAR(hsh.Relight(light).at(0, 1, 0), Hsh4ByHand(truth, light), 2e-5);
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

}  // namespace
}  // namespace photomat
