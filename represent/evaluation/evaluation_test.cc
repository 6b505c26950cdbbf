#include "represent/evaluation/evaluation.h"

#include <fmt/format.h>
#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <numeric>

#include "capture/io/load_photometric_set.h"
#include "capture/synthetic/synthetic_capture.h"
#include "core/error.h"
#include "core/image_io.h"
#include "represent/fitting/fit.h"
#include "represent/fitting/robust_fit.h"
#include "tests/support/synthetic_sets.h"
#include "tests/support/test_support.h"

namespace photomat {
namespace {

std::map<std::string, MethodEvaluation> EvaluateAll(const PhotometricSet& set,
                                                    bool prediction = true) {
  const Observations observations(set);
  EvaluationOptions options;
  options.prediction = prediction;
  std::map<std::string, MethodEvaluation> results;
  for (const Method& method : AllMethods()) {
    results.emplace(method.Name(), EvaluateMethod(set, observations, method, nullptr, options));
  }
  return results;
}

TEST(EvaluationTest, LambertianMethodsReconstructALambertianSample) {
  const auto synthetic = testing::LambertianSet(SurfacePattern::kBumps, 64);
  const auto results = EvaluateAll(synthetic.set, /*prediction=*/false);
  for (const char* name : {"3i", "gradient", "eigen3"}) {
    EXPECT_LT(results.at(name).eta_reconstruction, 1e-3) << name;
  }
}

TEST(EvaluationTest, ShadowsAndHighlightsOrderTheMethodsAsTheThesisFound) {
  const auto synthetic = testing::ShadowedSpecularSet(64);
  const auto r = EvaluateAll(synthetic.set);
  const auto eta = [&](const char* name) { return r.at(name).eta_reconstruction; };
  EXPECT_LT(eta("eigen6"), eta("ptm"));
  EXPECT_LT(eta("eigen3"), eta("3i"));
  EXPECT_LT(eta("eigen6"), eta("eigen3"));
  for (const auto& [name, evaluation] : r) {
    ASSERT_TRUE(evaluation.eta_prediction) << name;
    EXPECT_GT(*evaluation.eta_prediction, evaluation.eta_reconstruction) << name;
  }
}

TEST(EvaluationTest, LeaveOneOutOfAnExactModelPredictsPerfectly) {
  // A Lambertian sample is exactly a 3-term model: leaving an image out changes nothing.
  const auto synthetic = testing::LambertianSet(SurfacePattern::kGrooves, 32);
  const Observations observations(synthetic.set);
  const MethodEvaluation gradient =
      EvaluateMethod(synthetic.set, observations, Method::Parse("gradient"), nullptr);
  ASSERT_TRUE(gradient.eta_prediction);
  EXPECT_LT(*gradient.eta_prediction, 1e-3);
}

TEST(EvaluationTest, NormalisedErrorIsRmsOverStandardDeviation) {
  std::vector<Image> images;
  Image image(2, 1, 1);
  image.values()[0] = 1.0f;
  image.values()[1] = 3.0f;  // mean 2, sigma 1
  images.push_back(image);
  const PhotometricSet set(images, {LightDirection::FromSlantTilt(0, 0)});
  const Observations observations(set);
  Eigen::VectorXf relit(2);
  relit << 1.5f, 3.5f;  // RMS error 0.5
  EXPECT_NEAR(NormalisedRmsError(observations, 0, relit), 0.5, 1e-7);
  EXPECT_NEAR(NormalisedRmsError(observations, 0, relit, /*literal_thesis_rms=*/true),
              std::sqrt(0.5) / 2.0, 1e-7);
}

TEST(EvaluationTest, PsnrIsPeakOverRootMeanSquareInDecibels) {
  std::vector<Image> images;
  Image image(2, 1, 1);
  image.values()[0] = 1.0f;
  image.values()[1] = 4.0f;  // peak 4
  images.push_back(image);
  const PhotometricSet set(images, {LightDirection::FromSlantTilt(0, 0)});
  const Observations observations(set);
  Eigen::VectorXf relit(2);
  relit << 1.5f, 3.5f;  // MSE 0.25: PSNR = 10 log10(16 / 0.25) = 18.0618 dB
  EXPECT_NEAR(PeakSignalToNoiseRatio(observations, 0, relit), 10.0 * std::log10(64.0), 1e-6);
  relit << 1.0f, 4.0f;
  EXPECT_TRUE(std::isinf(PeakSignalToNoiseRatio(observations, 0, relit)));
}

TEST(EvaluationTest, HoldingOutEveryKthImagePredictsThoseFromOneFit) {
  // The thesis grid's 36 lights, every 4th held out: images 0, 4, ..., 32 are predicted by a fit
  // of the other 27. A Lambertian sample is an exact 3-term model, so gradient predicts them as
  // well as leave-one-out does; a glossy, shadowed one is predicted worse than reconstructed.
  EvaluationOptions options;
  options.hold_out_every = 4;
  const auto exact = testing::LambertianSet(SurfacePattern::kGrooves, 32);
  const Observations exact_observations(exact.set);
  const MethodEvaluation gradient =
      EvaluateMethod(exact.set, exact_observations, Method::Parse("gradient"), nullptr, options);
  ASSERT_EQ(exact.set.size(), 36);
  EXPECT_EQ(gradient.prediction_images, (std::vector<int>{0, 4, 8, 12, 16, 20, 24, 28, 32}));
  ASSERT_EQ(gradient.prediction_per_image.size(), 9u);
  ASSERT_EQ(gradient.psnr_prediction_per_image.size(), 9u);
  ASSERT_TRUE(gradient.eta_prediction && gradient.psnr_prediction);
  EXPECT_LT(*gradient.eta_prediction, 1e-3);
  EXPECT_GT(*gradient.psnr_prediction, 60.0);  // float round-off only

  const auto glossy = testing::ShadowedSpecularSet(32);
  const Observations observations(glossy.set);
  const MethodEvaluation ptm =
      EvaluateMethod(glossy.set, observations, Method::Parse("ptm"), nullptr, options);
  ASSERT_TRUE(ptm.eta_prediction);
  EXPECT_GT(*ptm.eta_prediction, ptm.eta_reconstruction);
  // The held-out errors are the image's error from a fit that did not see it: each equals the
  // error of relighting the one held-out fit there.
  std::vector<int> kept;
  for (int i = 0; i < glossy.set.size(); ++i) {
    if (i % 4 != 0) kept.push_back(i);
  }
  const Representation fit =
      FitObservations(observations, glossy.set.lights(), Method::Parse("ptm"), kept);
  for (std::size_t j = 0; j < ptm.prediction_images.size(); ++j) {
    const int k = ptm.prediction_images[j];
    EXPECT_NEAR(ptm.prediction_per_image[j],
                NormalisedRmsError(observations, k,
                                   RelightObservedPixels(fit, observations, glossy.set.light(k))),
                1e-9)
        << k;
  }
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
      RenderSyntheticCapture(MakeSyntheticMaterial(material), testing::FiveRingDome(), render);
  const Observations observations(set);
  // Measured eta reconstruction / prediction: hsh4 0.3045 / 0.3287, hsh9 0.2223 / 0.2693, hsh16
  // 0.1418 / 0.2111; each bound is the measured value * 1.2.
  struct Bounds {
    const char* name;
    double reconstruction, prediction;
  };
  double previous = INFINITY;
  for (const Bounds& bound :
       {Bounds{"hsh4", 0.3045 * 1.2, 0.3287 * 1.2}, Bounds{"hsh9", 0.2223 * 1.2, 0.2693 * 1.2},
        Bounds{"hsh16", 0.1418 * 1.2, 0.2111 * 1.2}}) {
    const char* name = bound.name;
    const MethodEvaluation evaluation =
        EvaluateMethod(set, observations, Method::Parse(name), nullptr);
    EXPECT_LT(evaluation.eta_reconstruction, previous) << name;
    EXPECT_LT(evaluation.eta_reconstruction, bound.reconstruction) << name;
    ASSERT_TRUE(evaluation.eta_prediction) << name;
    EXPECT_GT(*evaluation.eta_prediction, evaluation.eta_reconstruction) << name;
    EXPECT_LT(*evaluation.eta_prediction, bound.prediction) << name;
    previous = evaluation.eta_reconstruction;
    ::testing::Test::RecordProperty(
        std::string(name) + "_eta",
        fmt::format("{:.4f} / {:.4f}", evaluation.eta_reconstruction, *evaluation.eta_prediction));
  }
}

TEST(RobustFitTest, EvaluationWithRobustFits) {
  const auto synthetic = testing::ShadowedSpecularSet(32);
  const Observations observations(synthetic.set);
  EvaluationOptions plain;
  plain.prediction = false;
  EvaluationOptions robust = plain;
  robust.robust = RobustFitOptions{};
  const Method gradient = Method::Parse("gradient");
  const MethodEvaluation a =
      EvaluateMethod(synthetic.set, observations, gradient, &synthetic.material.normals, plain);
  const MethodEvaluation b =
      EvaluateMethod(synthetic.set, observations, gradient, &synthetic.material.normals, robust);
  EXPECT_LT(b.normals->mean_degrees, 0.5 * a.normals->mean_degrees);
}

// Robust PTM, HSH and Eigen-k share the photometric-stereo weights: fitted to an image set with
// shadows and highlights, they relight closer to the same material without them (the part their
// models can represent) than the least-squares fits do.
TEST(RobustFitTest, RobustPtmAndEigenIgnoreTheSameOutliers) {
  SyntheticMaterialOptions material_options;
  material_options.width = material_options.height = 40;
  material_options.max_slope_degrees = 45.0;
  const SyntheticMaterial material = MakeSyntheticMaterial(material_options);
  SyntheticRenderOptions harsh;
  harsh.shadows = true;
  harsh.specular = 0.5;
  harsh.shininess = 60.0;
  const PhotometricSet captured = RenderSyntheticCapture(material, ThesisLightGrid(), harsh);
  SyntheticRenderOptions diffuse;
  diffuse.shadows = true;
  const PhotometricSet clean = RenderSyntheticCapture(material, ThesisLightGrid(), diffuse);
  const Observations observations(captured);
  const Observations clean_observations(clean);
  std::vector<int> all(captured.size());
  std::iota(all.begin(), all.end(), 0);
  const RobustFit robust(observations, captured.lights(), all, RobustFitOptions{});
  EXPECT_GT(robust.summary().down_weighted, 0u);
  EXPECT_GT(robust.summary().attached_shadow, 0u);
  for (const char* name : {"ptm", "ptm-lrgb", "hsh9", "eigen6"}) {
    const Method method = Method::Parse(name);
    const Representation plain = FitObservations(observations, captured.lights(), method, all);
    const Representation weighted = robust.Fit(method);
    EXPECT_TRUE(weighted.details().contains("robust")) << name;
    double plain_error = 0.0, robust_error = 0.0;
    for (int i = 0; i < captured.size(); ++i) {
      plain_error += NormalisedRmsError(
          clean_observations, i, RelightObservedPixels(plain, clean_observations, clean.light(i)));
      robust_error +=
          NormalisedRmsError(clean_observations, i,
                             RelightObservedPixels(weighted, clean_observations, clean.light(i)));
    }
    std::printf("%s relit against the diffuse images: least squares %.4f, robust %.4f\n", name,
                plain_error / captured.size(), robust_error / captured.size());
    EXPECT_LT(robust_error, 0.8 * plain_error) << name;
  }
  // 3I has no robust form: the same three images.
  const Representation three = robust.Fit(Method::Parse("3i"));
  EXPECT_EQ(three.maps().values()[5],
            FitObservations(observations, captured.lights(), Method::Parse("3i"), all)
                .maps()
                .values()[5]);
}

// Mean angular error of `method`'s normals on a DiLiGenT object, all 96 images.
double DiligentMeanError(const std::filesystem::path& folder, const char* method) {
  const LoadedSet loaded = LoadPhotometricSet(folder);
  EXPECT_EQ(loaded.set.size(), 96);
  EXPECT_TRUE(loaded.ground_truth_normals);
  const Image truth = ReadImage(*loaded.ground_truth_normals).image;
  const auto normals = EstimateNormals(Fit(loaded.set, Method::Parse(method)));
  const double mean = CompareNormals(*normals, truth, *loaded.set.mask()).mean_degrees;
  ::testing::Test::RecordProperty(std::string(method) + "_mean_angular_error_deg",
                                  std::to_string(mean));
  return mean;
}

// DiLiGenT's published least-squares baseline (README of the data): 4.10 (ball), 8.41 (cat).
void ExpectDiligentLeastSquares(const std::string& object, double published) {
  PHOTOMAT_TEST_DATA_OR_SKIP(folder, "diligent/" + object);
  EXPECT_NEAR(DiligentMeanError(folder, "gradient"), published, 0.5) << object;
}

TEST(DiligentTest, BallLeastSquaresMatchesThePublishedBaseline) {
  ExpectDiligentLeastSquares("ball", 4.10);
}

TEST(DiligentTest, CatLeastSquaresMatchesThePublishedBaseline) {
  ExpectDiligentLeastSquares("cat", 8.41);
}

// PTM's linear terms give normals at least as good as least squares on the specular ball (the
// biquadratic absorbs part of the highlight): measured 3.45 degrees against 4.29.
TEST(DiligentTest, PtmNormalsOnTheBallBeatLeastSquares) {
  PHOTOMAT_TEST_DATA_OR_SKIP(folder, "diligent/ball");
  EXPECT_LT(DiligentMeanError(folder, "ptm"), DiligentMeanError(folder, "gradient"));
}

}  // namespace
}  // namespace photomat
