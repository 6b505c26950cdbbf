#include "represent/fitting/robust_fit.h"

#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <numeric>

#include "capture/io/load_photometric_set.h"
#include "capture/synthetic/synthetic_capture.h"
#include "core/error.h"
#include "core/image_io.h"
#include "represent/fitting/fit.h"
#include "represent/model/normal_error.h"
#include "tests/support/synthetic_sets.h"
#include "tests/support/test_support.h"

namespace photomat {
namespace {

double MeanNormalError(const Representation& representation, const Image& truth, const Mask& mask) {
  return CompareNormals(*EstimateNormals(representation), truth, mask).mean_degrees;
}

TEST(RobustLossTest, WeightsAndNames) {
  EXPECT_DOUBLE_EQ(RobustWeight(RobustLoss::kHuber, 0.5), 1.0);
  EXPECT_DOUBLE_EQ(RobustWeight(RobustLoss::kHuber, -4.0), 0.25);
  EXPECT_DOUBLE_EQ(RobustWeight(RobustLoss::kCauchy, 1.0), 0.5);
  EXPECT_DOUBLE_EQ(RobustWeight(RobustLoss::kTukey, 0.5), 0.5625);
  EXPECT_DOUBLE_EQ(RobustWeight(RobustLoss::kTukey, 1.5), 0.0);
  EXPECT_EQ(ParseRobustLoss("Tukey"), RobustLoss::kTukey);
  EXPECT_EQ(ParseRobustLoss("l2"), std::nullopt);
  EXPECT_EQ(ToString(RobustLoss::kCauchy), "cauchy");
}

// A streamed fit sums its bands' summaries: counts add, the means weigh by the observations.
TEST(RobustFitSummaryTest, BandsAddIntoTheWholeSetsSummary) {
  RobustFitSummary top{.observations = 100,
                       .not_measured = 3,
                       .attached_shadow = 5,
                       .down_weighted = 7,
                       .mean_weight = 0.5,
                       .normal_inlier_fraction = 1.0};
  const RobustFitSummary bottom{.observations = 300,
                                .not_measured = 11,
                                .attached_shadow = 13,
                                .down_weighted = 17,
                                .mean_weight = 0.9,
                                .normal_inlier_fraction = 0.5};
  RobustFitSummary whole;
  whole.Add(top);
  EXPECT_EQ(whole.ToJson(), top.ToJson());  // an empty summary adds nothing
  whole.Add(bottom);
  EXPECT_EQ(whole.observations, 400u);
  EXPECT_EQ(whole.not_measured, 14u);
  EXPECT_EQ(whole.attached_shadow, 18u);
  EXPECT_EQ(whole.down_weighted, 24u);
  EXPECT_NEAR(whole.mean_weight, (100 * 0.5 + 300 * 0.9) / 400, 1e-15);             // 0.8
  EXPECT_NEAR(whole.normal_inlier_fraction, (100 * 1.0 + 300 * 0.5) / 400, 1e-15);  // 0.625
  EXPECT_EQ(RobustFitSummary::FromJson(whole.ToJson()).ToJson(), whole.ToJson());
  EXPECT_THROW(RobustFitSummary::FromJson(nlohmann::json{{"observations", 1}}),
               nlohmann::json::exception);
}

// Without outliers the robust fit is the least-squares fit.
TEST(RobustFitTest, LambertianDataGiveTheLeastSquaresNormals) {
  const auto synthetic = testing::LambertianSet(SurfacePattern::kBumps, 32);
  const Mask all = synthetic.set.MaskOrAll();
  for (RobustLoss loss : {RobustLoss::kHuber, RobustLoss::kCauchy, RobustLoss::kTukey}) {
    RobustFitOptions options;
    options.loss = loss;
    const Representation robust = FitRobust(synthetic.set, Method::Parse("gradient"), options);
    EXPECT_LT(MeanNormalError(robust, synthetic.material.normals, all), 0.01) << ToString(loss);
    // The albedo too.
    const Image& maps = robust.maps();
    for (std::size_t p = 0; p < maps.pixel_count(); p += 97) {
      for (int c = 0; c < 3; ++c) {
        EXPECT_NEAR(maps.pixel(p)[3 + c], synthetic.material.albedo.pixel(p)[c], 1e-3);
      }
    }
  }
}

TEST(RobustFitTest, ShadowsAndHighlightsHurtLeastSquaresNotTheRobustFit) {
  const auto synthetic = testing::ShadowedSpecularSet(48);
  const Mask all = synthetic.set.MaskOrAll();
  const double least_squares = MeanNormalError(Fit(synthetic.set, Method::Parse("gradient")),
                                               synthetic.material.normals, all);
  for (RobustLoss loss : {RobustLoss::kHuber, RobustLoss::kCauchy, RobustLoss::kTukey}) {
    RobustFitOptions options;
    options.loss = loss;
    const double robust =
        MeanNormalError(FitRobust(synthetic.set, Method::Parse("gradient"), options),
                        synthetic.material.normals, all);
    std::printf("shadowed specular set: least squares %.2f, robust %s %.2f degrees\n",
                least_squares, std::string(ToString(loss)).c_str(), robust);
    EXPECT_LT(robust, 0.25 * least_squares) << ToString(loss);
  }
}

TEST(RobustFitTest, UnmeasuredObservationsTakeNoPart) {
  const auto synthetic = testing::LambertianSet(SurfacePattern::kGrooves, 24);
  // Ruin a third of the observations of every pixel, and say so in the measured masks.
  std::vector<Image> images = synthetic.set.images();
  std::vector<Mask> measured;
  for (int i = 0; i < synthetic.set.size(); ++i) {
    Mask mask(24, 24, true);
    for (std::size_t p = 0; p < images[i].pixel_count(); ++p) {
      if ((p + i) % 3 == 0) {
        for (float& v : images[i].pixel(p)) v = 1.0f;
        mask.Set(p, false);
      }
    }
    measured.push_back(std::move(mask));
  }
  const PhotometricSet ruined(std::move(images), synthetic.set.lights());
  RobustFitOptions options;
  options.measured = measured;
  const Representation fit = FitRobust(ruined, Method::Parse("gradient"), options);
  EXPECT_LT(MeanNormalError(fit, synthetic.material.normals, ruined.MaskOrAll()), 0.01);
  options.measured = std::span<const Mask>(measured).first(3);
  EXPECT_THROW(FitRobust(ruined, Method::Parse("gradient"), options), Error);
}

TEST(RobustFitTest, CoplanarLightsAreRejected) {
  std::vector<LightDirection> ring;
  for (int k = 0; k < 8; ++k) ring.push_back(LightDirection::FromSlantTilt(90, 45.0 * k));
  const PhotometricSet set(std::vector<Image>(8, Image(4, 4, 3)), ring, {}, "ring.lp");
  try {
    FitRobust(set, Method::Parse("gradient"));
    FAIL() << "expected an error";
  } catch (const Error& error) {
    EXPECT_NE(std::string(error.what()).find("ring.lp: robust fit: the 8 lights are coplanar"),
              std::string::npos)
        << error.what();
  }
}

// DiLiGenT, all 96 images (README of the data: least squares 4.10 ball, 8.41 cat; photomat's
// least squares measures 4.29 and 8.45). Targets of issue 5: robust at most 3.0 and 6.5.
void ExpectRobustBeatsLeastSquares(const std::string& object, double target) {
  PHOTOMAT_TEST_DATA_OR_SKIP(folder, "diligent/" + object);
  const LoadedSet loaded = LoadPhotometricSet(folder);
  ASSERT_EQ(loaded.set.size(), 96);
  const Image truth = ReadImage(*loaded.ground_truth_normals).image;
  const Mask& mask = *loaded.set.mask();
  const double least_squares =
      MeanNormalError(Fit(loaded.set, Method::Parse("gradient")), truth, mask);
  const double robust =
      MeanNormalError(FitRobust(loaded.set, Method::Parse("gradient")), truth, mask);
  std::printf("DiLiGenT %s: least squares %.3f, robust %.3f degrees mean\n", object.c_str(),
              least_squares, robust);
  ::testing::Test::RecordProperty("least_squares_deg", std::to_string(least_squares));
  ::testing::Test::RecordProperty("robust_deg", std::to_string(robust));
  EXPECT_LT(robust, least_squares);
  EXPECT_LE(robust, target);
}

TEST(RobustDiligentTest, BallRobustBeatsLeastSquares) {
  ExpectRobustBeatsLeastSquares("ball", 3.0);
}

TEST(RobustDiligentTest, CatRobustBeatsLeastSquares) { ExpectRobustBeatsLeastSquares("cat", 6.5); }

}  // namespace
}  // namespace photomat
