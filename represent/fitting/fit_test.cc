#include "represent/fitting/fit.h"

#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <numeric>

#include "capture/synthetic/synthetic_capture.h"
#include "core/error.h"
#include "represent/model/normal_error.h"
#include "tests/support/synthetic_sets.h"

namespace photomat {
namespace {

using ::testing::AllOf;
using ::testing::HasSubstr;
using ::testing::ThrowsMessage;

// StackMapCount (represent/model/method.h), which memory and disk estimates use, is the maps a fit
// makes.
TEST(FitTest, StackMapCountIsTheMapsOfTheFit) {
  const auto synthetic = testing::LambertianSet(SurfacePattern::kBumps, 12);
  for (const char* name :
       {"3i", "gradient", "ptm", "ptm-lrgb", "hsh4", "hsh9", "eigen6", "rbf", "bilinear"}) {
    const Method method = Method::Parse(name);
    EXPECT_EQ(Fit(synthetic.set, method).maps().channels(),
              StackMapCount(method, synthetic.set.size(), synthetic.set.channels()))
        << name;
  }
}

TEST(FitTest, GradientRecoversNormalsAndAlbedoOfALambertianSample) {
  const auto synthetic = testing::LambertianSet(SurfacePattern::kBricks, 128);
  const Representation gradient = Fit(synthetic.set, Method::Parse("gradient"));
  const auto normals = EstimateNormals(gradient);
  ASSERT_TRUE(normals);
  const NormalErrorStats stats =
      CompareNormals(*normals, synthetic.material.normals, synthetic.set.MaskOrAll());
  EXPECT_LT(stats.mean_degrees, 0.1);
  EXPECT_EQ(stats.pixels, 128u * 128u);
  const int albedo = gradient.maps().FindChannel("albedo.R");
  ASSERT_EQ(albedo, 3);
  double worst = 0.0;
  for (std::size_t p = 0; p < synthetic.material.albedo.pixel_count(); ++p) {
    for (int c = 0; c < 3; ++c) {
      const double truth = synthetic.material.albedo.pixel(p)[c];
      worst = std::max(worst, std::abs(gradient.maps().pixel(p)[albedo + c] - truth) / truth);
    }
  }
  EXPECT_LT(worst, 0.005);
}

// The PTM 1.2 evaluation written out by hand (file-formats.md, ".ptm"), independent of
// PtmLightBasis: C = a0 u^2 + a1 v^2 + a2 u v + a3 u + a4 v + a5, (u, v) the light's x and y.
double PtmByHand(const Eigen::VectorXd& a, const LightDirection& light) {
  const double u = light.x(), v = light.y();
  return a[0] * u * u + a[1] * v * v + a[2] * u * v + a[3] * u + a[4] * v + a[5];
}

TEST(FitTest, PtmRecoversAnExactBiquadratic) {
  // Images made from known coefficients in the spec's term order: the fit must return them, and
  // relight an uncaptured light as the spec's polynomial does.
  const auto lights = ThesisLightGrid();
  const Eigen::VectorXd truth =
      (Eigen::VectorXd(6) << -0.3, -0.2, 0.1, 0.25, -0.15, 0.6).finished();
  std::vector<Image> images;
  for (const auto& light : lights) {
    Image image(3, 2, 1);
    const double value = PtmByHand(truth, light);
    for (float& v : image.values()) v = static_cast<float>(value);
    images.push_back(image);
  }
  const Representation ptm = Fit(PhotometricSet(images, lights), Method::Parse("ptm"));
  for (int j = 0; j < 6; ++j) EXPECT_NEAR(ptm.maps().at(1, 1, j), truth[j], 1e-5) << "a" << j;
  EXPECT_EQ(ptm.maps().channel_names()[3], "ptm.a3.Y");
  const auto uncaptured = LightDirection::FromSlantTilt(37, 211);
  EXPECT_NEAR(ptm.Relight(uncaptured).at(2, 1, 0), PtmByHand(truth, uncaptured), 1e-5);
}

TEST(FitTest, PtmLrgbSeparatesLuminanceAndChroma) {
  const auto lights = ThesisLightGrid();
  const Eigen::VectorXd lum = (Eigen::VectorXd(6) << -0.3, -0.2, 0.1, 0.25, -0.15, 0.6).finished();
  const Eigen::Vector3d chroma(0.5, 1.0, 1.5);
  std::vector<Image> images;
  for (const auto& light : lights) {
    Image image(2, 2, 3);
    const double l = PtmByHand(lum, light);
    for (std::size_t p = 0; p < 4; ++p) {
      for (int c = 0; c < 3; ++c) image.pixel(p)[c] = static_cast<float>(chroma[c] * l);
    }
    images.push_back(image);
  }
  const PhotometricSet set(images, lights);
  const Representation lrgb = Fit(set, Method::Parse("ptm-lrgb"));
  for (int i = 0; i < set.size(); i += 7) {
    const Image relit = lrgb.Relight(set.light(i));
    for (int c = 0; c < 3; ++c) EXPECT_NEAR(relit.at(1, 0, c), set.image(i).at(1, 0, c), 1e-5);
  }
}

TEST(FitTest, EigenWithAllComponentsReproducesEveryImage) {
  const auto synthetic = testing::ShadowedSpecularSet(32);
  const Representation eigen = Fit(synthetic.set, Method::Parse("eigen36"));
  for (int i : {0, 13, 35}) {
    const Image relit = eigen.Relight(synthetic.set.light(i));
    for (std::size_t v = 0; v < relit.values().size(); v += 17) {
      EXPECT_NEAR(relit.values()[v], synthetic.set.image(i).values()[v], 2e-4);
    }
  }
  EXPECT_EQ(eigen.details().at("singular_values").size(), 36u);
  EXPECT_EQ(eigen.details().at("interpolation"), "slant-rings");
}

TEST(FitTest, EigenBasesAreOrderedBySingularValue) {
  const auto synthetic = testing::ShadowedSpecularSet(32);
  const Representation eigen = Fit(synthetic.set, Method::Parse("eigen6"));
  const auto singular = eigen.details().at("singular_values").get<std::vector<double>>();
  EXPECT_TRUE(std::is_sorted(singular.rbegin(), singular.rend()));
  const auto cumulative = eigen.details().at("cumulative_information").get<std::vector<double>>();
  EXPECT_GT(cumulative[5], 0.99);  // "the first few eigenvectors account for more than 99 %"
  EXPECT_NEAR(cumulative.back(), 1.0, 1e-12);
}

TEST(FitTest, ThreeImageUsesTheThesisLightsAndRotatesWhenOneIsMissing) {
  const auto grid = ThesisLightGrid();
  std::vector<int> all(36);
  std::iota(all.begin(), all.end(), 0);
  EXPECT_EQ(SelectThreeImageLights(grid, all), (std::array<int, 3>{12, 15, 18}));  // 0, 90, 180
  std::vector<int> without_90 = all;
  without_90.erase(without_90.begin() + 15);
  EXPECT_EQ(SelectThreeImageLights(grid, without_90), (std::array<int, 3>{13, 16, 19}));
}

TEST(FitTest, ThreeImageRelightsUncapturedLightsAsTheTrueSurface) {
  // At a captured light 3I returns its stored image whatever its light function does, so relight
  // between the fitted lights and compare with the surface rendered there: for a Lambertian
  // sample without shadows 3I is exact at every light.
  const auto synthetic = testing::LambertianSet(SurfacePattern::kBumps, 32);
  const Representation three = Fit(synthetic.set, Method::Parse("3i"));
  const std::vector<LightDirection> uncaptured = {LightDirection::FromSlantTilt(37, 211),
                                                  LightDirection::FromSlantTilt(8, 47),
                                                  LightDirection::FromSlantTilt(52, 118)};
  const PhotometricSet truth = RenderSyntheticCapture(synthetic.material, uncaptured);
  for (int i = 0; i < truth.size(); ++i) {
    const Image relit = three.Relight(uncaptured[i]);
    ASSERT_EQ(relit.values().size(), truth.image(i).values().size());
    double worst = 0.0;
    for (std::size_t v = 0; v < relit.values().size(); ++v) {
      worst = std::max(worst, std::abs(double{relit.values()[v]} - truth.image(i).values()[v]));
    }
    ::testing::Test::RecordProperty("worst_abs_error_" + std::to_string(i), std::to_string(worst));
    // measured WORST; bound BOUND (float rounding of a 3-term sum of values <= 1).
    // Measured 1.2e-7, 6.0e-8, 6.0e-8 (float rounding of a 3-term sum); bound 2.4e-7 = 1.2e-7 * 2.
    EXPECT_LT(worst, 2.4e-7) << "light " << i << ": worst error " << worst;
  }
}

// Degenerate light sets (the malformed-input classes the fit detects).
PhotometricSet FlatSet(const std::vector<LightDirection>& lights) {
  std::vector<Image> images;
  for (std::size_t i = 0; i < lights.size(); ++i) {
    Image image(4, 4, 1);
    for (float& v : image.values()) v = 0.5f + 0.01f * static_cast<float>(i);
    images.push_back(image);
  }
  return PhotometricSet(images, lights, {}, "lights.lp");
}

TEST(FitErrorTest, FewerLightsThanTheMethodNeeds) {
  const auto set =
      FlatSet({LightDirection::FromSlantTilt(30, 0), LightDirection::FromSlantTilt(30, 120),
               LightDirection::FromSlantTilt(45, 240), LightDirection::FromSlantTilt(60, 60),
               LightDirection::FromSlantTilt(60, 300)});
  EXPECT_THAT(
      [&] { Fit(set, Method::Parse("ptm")); },
      ThrowsMessage<Error>(HasSubstr("lights.lp: ptm needs at least 6 images; the set has 5")));
  EXPECT_THAT([&] { Fit(set, Method::Parse("eigen6")); },
              ThrowsMessage<Error>(HasSubstr("eigen6 needs at least 6 images")));
  const auto two =
      FlatSet({LightDirection::FromSlantTilt(30, 0), LightDirection::FromSlantTilt(30, 90)});
  EXPECT_THAT([&] { Fit(two, Method::Parse("gradient")); },
              ThrowsMessage<Error>(HasSubstr("gradient needs at least 3 images")));
}

TEST(FitErrorTest, CoplanarLightsForGradientAnd3I) {
  // All lights in the x-z plane (tilts 0 and 180 only).
  const auto set =
      FlatSet({LightDirection::FromSlantTilt(30, 0), LightDirection::FromSlantTilt(50, 0),
               LightDirection::FromSlantTilt(30, 180), LightDirection::FromSlantTilt(60, 180)});
  EXPECT_THAT([&] { Fit(set, Method::Parse("gradient")); },
              ThrowsMessage<Error>(HasSubstr("lights.lp: gradient: the 4 lights are coplanar")));
  EXPECT_THAT([&] { Fit(set, Method::Parse("3i")); },
              ThrowsMessage<Error>(HasSubstr("3i: every triple of the 4 lights is coplanar")));
}

TEST(FitErrorTest, SingleRingLeavesPtmDegenerate) {
  std::vector<LightDirection> ring;
  for (int t = 0; t < 360; t += 30) ring.push_back(LightDirection::FromSlantTilt(40, t));
  // The message names the circle the ring lies on: lu^2 + lv^2 = sin^2 40 deg = 0.413.
  EXPECT_THAT([&] { Fit(FlatSet(ring), Method::Parse("ptm")); },
              ThrowsMessage<Error>(AllOf(HasSubstr("do not determine the 6 PTM coefficients"),
                                         HasSubstr("on the conic lu^2 + lv^2 - 0.413 = 0"))));
  EXPECT_NO_THROW(Fit(FlatSet(ring), Method::Parse("gradient")));
}

TEST(FitErrorTest, LightsOnTheImageAxesLeavePtmsCrossTermUndetermined) {
  // Three rings, but only at tilts 0, 90, 180 and 270: lu * lv is 0 at every light.
  std::vector<LightDirection> axes;
  for (int slant : {30, 45, 60}) {
    for (int t = 0; t < 360; t += 90) axes.push_back(LightDirection::FromSlantTilt(slant, t));
  }
  EXPECT_THAT([&] { Fit(FlatSet(axes), Method::Parse("ptm")); },
              ThrowsMessage<Error>(HasSubstr("the 12 lights do not determine the 6 PTM "
                                             "coefficients: their directions' (lu, lv) all lie "
                                             "on the conic lu*lv = 0")));
}

// Representations as fits make them.

TEST(RepresentationTest, WithMapsKeepsTheLightFunction) {
  const auto synthetic = testing::LambertianSet(SurfacePattern::kBumps, 16);
  const Representation ptm = Fit(synthetic.set, Method::Parse("ptm"));
  Image shifted = ptm.maps();
  const Representation copy = ptm.WithMaps(shifted);
  const auto light = LightDirection::FromSlantTilt(37, 211);
  EXPECT_EQ(copy.Relight(light).values()[40], ptm.Relight(light).values()[40]);
  EXPECT_THROW(ptm.WithMaps(Image(16, 16, 3)), Error);
}

TEST(RepresentationTest, NormalsFromGradient3IAndPtmAgreeWithTheTruth) {
  const auto synthetic = testing::LambertianSet(SurfacePattern::kBumps, 32);
  for (const char* name : {"gradient", "3i", "ptm", "ptm-lrgb"}) {
    const auto normals = EstimateNormals(Fit(synthetic.set, Method::Parse(name)));
    ASSERT_TRUE(normals) << name;
    double sum = 0.0;
    for (std::size_t p = 0; p < normals->pixel_count(); ++p) {
      const auto e = normals->pixel(p), t = synthetic.material.normals.pixel(p);
      sum += AngleBetweenDegrees({e[0], e[1], e[2]}, {t[0], t[1], t[2]});
    }
    // Exact for the Lambertian methods; PTM's biquadratic approximates the cosine.
    const double mean = sum / normals->pixel_count();
    ::testing::Test::RecordProperty(std::string(name) + "_mean_deg", std::to_string(mean));
    EXPECT_LT(mean, std::string(name).starts_with("ptm") ? 0.5 : 0.01) << name;
  }
  EXPECT_FALSE(EstimateNormals(Fit(synthetic.set, Method::Parse("eigen3"))));
}

}  // namespace
}  // namespace photomat
