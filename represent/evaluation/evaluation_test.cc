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
#include "represent/evaluation/image_comparison.h"
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

// A w x h image of `channels` channels with values in [0, scale): a smooth pattern and a
// checkerboard, so that the SSIM's windows see structure.
Image PatternImage(int width, int height, int channels, float scale) {
  Image image(width, height, channels);
  for (int c = 0; c < channels; ++c) {
    for (int y = 0; y < height; ++y) {
      for (int x = 0; x < width; ++x) {
        const float smooth = 0.5f + 0.3f * std::sin(0.4f * x + 0.7f * y + c);
        image.at(x, y, c) = scale * (((x / 3 + y / 3) % 2 ? 0.15f : 0.0f) + 0.8f * smooth);
      }
    }
  }
  return image;
}

// A one-image set of `captured` with a disc mask, and `predicted` at its masked pixels in the
// observations' row order.
struct OneImageCase {
  PhotometricSet set;
  Eigen::VectorXf relit;
};
OneImageCase DiscMaskedCase(const Image& captured, const Image& predicted) {
  OneImageCase out{PhotometricSet({captured}, {LightDirection::FromSlantTilt(0, 0)}), {}};
  Mask disc(captured.width(), captured.height(), false);
  for (int y = 0; y < captured.height(); ++y) {
    for (int x = 0; x < captured.width(); ++x) {
      const double dx = x - 0.5 * captured.width(), dy = y - 0.5 * captured.height();
      disc.Set(x, y, dx * dx + dy * dy < 0.16 * captured.width() * captured.width());
    }
  }
  out.set.set_mask(disc);
  const std::vector<std::size_t> pixels = disc.SetIndices();
  out.relit.resize(static_cast<Eigen::Index>(pixels.size()) * captured.channels());
  for (int c = 0; c < captured.channels(); ++c) {
    for (std::size_t k = 0; k < pixels.size(); ++k) {
      out.relit[static_cast<Eigen::Index>(c * pixels.size() + k)] = predicted.plane(c)[pixels[k]];
    }
  }
  return out;
}

TEST(EvaluationTest, PredictionScoresAreTheDisplayedComparisonsOverTheMask) {
  const Image captured = PatternImage(40, 32, 3, 0.6f);
  Image predicted = captured;
  for (int c = 0; c < 3; ++c) {
    auto plane = predicted.plane(c);
    for (std::size_t p = 0; p < plane.size(); ++p) plane[p] *= 1.0f + 0.05f * ((p * 7 + c) % 5);
  }
  const OneImageCase one = DiscMaskedCase(captured, predicted);
  const Observations observations(one.set);
  const PredictionScores scores = ScorePrediction(observations, 0, one.relit);
  // The same comparisons of the whole images over the mask, white at the captured maximum
  // inside it (pixels outside the mask differ between these images and those ScorePrediction
  // makes, which hold 0 there: the comparisons must not see them).
  const Mask& mask = *one.set.mask();
  float white = 0.0f;
  for (int c = 0; c < 3; ++c) {
    for (std::size_t p : mask.SetIndices()) white = std::max(white, captured.plane(c)[p]);
  }
  EXPECT_NEAR(*scores.ssim, MaskedSsim(predicted, captured, mask, white), 1e-12);
  ASSERT_TRUE(scores.delta_e2000);
  EXPECT_NEAR(*scores.delta_e2000, MaskedMeanDeltaE2000(predicted, captured, mask, white), 1e-12);
  EXPECT_NEAR(scores.eta, NormalisedRmsError(observations, 0, one.relit), 1e-15);
  EXPECT_NEAR(scores.psnr, PeakSignalToNoiseRatio(observations, 0, one.relit), 1e-12);
  EXPECT_LT(*scores.ssim, 0.999);
  EXPECT_GT(*scores.delta_e2000, 0.1);

  // The white follows the captured image: scaling both images (light intensities divided out,
  // another bit depth) changes no score.
  Image captured_3 = captured, predicted_3 = predicted;
  for (float& v : captured_3.values()) v *= 3.0f;
  for (float& v : predicted_3.values()) v *= 3.0f;
  const OneImageCase scaled = DiscMaskedCase(captured_3, predicted_3);
  const PredictionScores scaled_scores = ScorePrediction(Observations(scaled.set), 0, scaled.relit);
  EXPECT_NEAR(*scaled_scores.ssim, *scores.ssim, 1e-6);
  EXPECT_NEAR(*scaled_scores.delta_e2000, *scores.delta_e2000, 1e-4);
  EXPECT_NEAR(scaled_scores.psnr, scores.psnr, 1e-5);

  // Without the appearance measures: eta and PSNR alone, the same.
  const PredictionScores cheap = ScorePrediction(observations, 0, one.relit, false, false);
  EXPECT_EQ(cheap.eta, scores.eta);
  EXPECT_EQ(cheap.psnr, scores.psnr);
  EXPECT_FALSE(cheap.ssim || cheap.delta_e2000);

  // An exact prediction: SSIM 1, no colour difference.
  const OneImageCase exact = DiscMaskedCase(captured, captured);
  const PredictionScores perfect = ScorePrediction(Observations(exact.set), 0, exact.relit);
  EXPECT_NEAR(*perfect.ssim, 1.0, 1e-12);
  EXPECT_EQ(*perfect.delta_e2000, 0.0);
}

TEST(EvaluationTest, TwoChannelPredictionsHaveSsimButNoColourDifference) {
  const Image captured = PatternImage(24, 24, 2, 1.0f);
  const OneImageCase one = DiscMaskedCase(captured, PatternImage(24, 24, 2, 0.9f));
  const PredictionScores scores = ScorePrediction(Observations(one.set), 0, one.relit);
  ASSERT_TRUE(scores.ssim);
  EXPECT_GT(*scores.ssim, 0.5);
  EXPECT_LT(*scores.ssim, 1.0);
  EXPECT_FALSE(scores.delta_e2000.has_value());
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
  ASSERT_TRUE(gradient.ssim_prediction && gradient.delta_e2000_prediction);
  EXPECT_GT(*gradient.ssim_prediction, 1.0 - 1e-6);
  EXPECT_LT(*gradient.delta_e2000_prediction, 1e-2);

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
    const PredictionScores scores = ScorePrediction(
        observations, k, RelightObservedPixels(fit, observations, glossy.set.light(k)));
    EXPECT_NEAR(ptm.prediction_per_image[j], scores.eta, 1e-9) << k;
    EXPECT_NEAR(ptm.psnr_prediction_per_image[j], scores.psnr, 1e-9) << k;
    EXPECT_NEAR(ptm.ssim_prediction_per_image[j], *scores.ssim, 1e-9) << k;
    EXPECT_NEAR(ptm.delta_e2000_prediction_per_image[j], *scores.delta_e2000, 1e-9) << k;
  }
  // Without the appearance measures: the same eta and PSNR, and no SSIM or colour difference.
  EvaluationOptions cheap = options;
  cheap.appearance = false;
  const MethodEvaluation ptm_cheap =
      EvaluateMethod(glossy.set, observations, Method::Parse("ptm"), nullptr, cheap);
  EXPECT_EQ(ptm_cheap.prediction_per_image, ptm.prediction_per_image);
  EXPECT_EQ(ptm_cheap.psnr_prediction_per_image, ptm.psnr_prediction_per_image);
  EXPECT_FALSE(ptm_cheap.ssim_prediction || ptm_cheap.delta_e2000_prediction);
  EXPECT_TRUE(ptm_cheap.ssim_prediction_per_image.empty());
  EXPECT_FALSE(ptm_cheap.ToJson().contains("ssim_prediction"));
  // PTM cannot predict the shadows and highlights of a light it did not see exactly.
  ASSERT_TRUE(ptm.ssim_prediction && ptm.delta_e2000_prediction);
  EXPECT_LT(*ptm.ssim_prediction, *gradient.ssim_prediction);
  EXPECT_GT(*ptm.delta_e2000_prediction, *gradient.delta_e2000_prediction);
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
