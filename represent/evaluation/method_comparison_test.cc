#include "represent/evaluation/method_comparison.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>

#include "core/error.h"
#include "tests/support/synthetic_sets.h"

namespace photomat {
namespace {

MethodEvaluation Predicted(const char* method, std::vector<int> images,
                           std::vector<double> errors) {
  MethodEvaluation e;
  e.method = Method::Parse(method);
  e.prediction_images = std::move(images);
  e.prediction_per_image = std::move(errors);
  double sum = 0.0;
  for (double v : e.prediction_per_image) sum += v;
  e.eta_prediction = sum / e.prediction_per_image.size();
  return e;
}

TEST(MethodComparisonTest, RanksMethodsImageByImage) {
  // Five held-out images: ptm is best in four and second in one; gradient last in all.
  const std::vector<int> images = {0, 4, 8, 12, 16};
  const std::vector<MethodEvaluation> evaluations = {
      Predicted("gradient", images, {0.9, 0.8, 0.95, 0.7, 0.85}),
      Predicted("ptm", images, {0.1, 0.2, 0.15, 0.3, 0.35}),
      Predicted("hsh9", images, {0.2, 0.3, 0.10, 0.4, 0.45})};
  const MethodComparison c = CompareMethods(evaluations);
  EXPECT_EQ(c.methods, (std::vector<std::string>{"gradient", "ptm", "hsh9"}));
  EXPECT_EQ(c.images, images);
  EXPECT_NEAR(c.friedman.mean_ranks[0], 3.0, 1e-12);
  EXPECT_NEAR(c.friedman.mean_ranks[1], 6.0 / 5.0, 1e-12);
  EXPECT_NEAR(c.friedman.mean_ranks[2], 9.0 / 5.0, 1e-12);
  EXPECT_EQ(c.RankOrder(), (std::vector<int>{1, 2, 0}));
  // By hand: rank sums 15, 6, 9; 12/(5*3*4) * (225 + 36 + 81) - 3*5*4 = 8.4, no ties.
  EXPECT_NEAR(c.friedman.chi_square, 8.4, 1e-12);
  EXPECT_NEAR(c.friedman.p_value, std::exp(-4.2), 1e-12);
  EXPECT_NEAR(c.friedman.kendalls_w, 0.84, 1e-12);
  EXPECT_NEAR(c.mean_values[1], 0.22, 1e-12);
  // Nemenyi at k = 3, n = 5: 2.343 * sqrt(12 / 30) (Demsar's q_0.05 for three).
  EXPECT_NEAR(c.critical_difference, 2.343 * std::sqrt(0.4), 1e-3);
  EXPECT_LT(c.pairwise_p(0, 1), 0.05);  // 1.8 mean ranks apart, above the difference
  EXPECT_GT(c.pairwise_p(1, 2), 0.05);

  const nlohmann::json json = c.ToJson();
  EXPECT_EQ(json["measure"], "eta_prediction_per_image");
  EXPECT_EQ(json["lower_is_better"], true);
  EXPECT_NEAR(json["methods"][0]["mean_eta_prediction"].get<double>(), 0.22, 1e-12);
  EXPECT_EQ(json["images"].size(), 5u);
  ASSERT_EQ(json["methods"].size(), 3u);
  EXPECT_EQ(json["methods"][0]["method"], "ptm");
  EXPECT_NEAR(json["methods"][0]["mean_rank"].get<double>(), 1.2, 1e-12);
  EXPECT_EQ(json["methods"][2]["method"], "gradient");
  EXPECT_NEAR(json["friedman"]["chi_square"].get<double>(), 8.4, 1e-12);
  EXPECT_EQ(json["friedman"]["degrees_of_freedom"], 2);
  EXPECT_NEAR(json["nemenyi"]["p_values"]["ptm"]["gradient"].get<double>(), c.pairwise_p(1, 0),
              1e-15);
  EXPECT_FALSE(json["nemenyi"]["p_values"]["ptm"].contains("ptm"));

  const std::string table = FormatComparisonTable(c);
  EXPECT_NE(table.find("Friedman chi-square 8.40 (2 df"), std::string::npos) << table;
  EXPECT_LT(table.find("ptm"), table.find("gradient")) << table;
}

TEST(MethodComparisonTest, RanksBySsimHighestFirstAndByColourDifferenceLowestFirst) {
  // The eta ranking of the test above, with SSIM and Delta E 2000 that order the methods the
  // other way round in every image: ranking by them reverses the mean ranks.
  const std::vector<int> images = {0, 4, 8, 12, 16};
  std::vector<MethodEvaluation> evaluations = {
      Predicted("gradient", images, {0.9, 0.8, 0.95, 0.7, 0.85}),
      Predicted("ptm", images, {0.1, 0.2, 0.15, 0.3, 0.35}),
      Predicted("hsh9", images, {0.2, 0.3, 0.10, 0.4, 0.45})};
  evaluations[0].ssim_prediction_per_image = {0.99, 0.98, 0.97, 0.99, 0.98};
  evaluations[1].ssim_prediction_per_image = {0.50, 0.60, 0.55, 0.50, 0.40};
  evaluations[2].ssim_prediction_per_image = {0.70, 0.70, 0.60, 0.80, 0.90};
  evaluations[0].delta_e2000_prediction_per_image = {1.0, 1.5, 1.2, 1.1, 1.0};
  evaluations[1].delta_e2000_prediction_per_image = {9.0, 8.0, 7.0, 9.5, 8.5};
  evaluations[2].delta_e2000_prediction_per_image = {5.0, 4.0, 3.0, 2.0, 2.5};

  const MethodComparison by_eta = CompareMethods(evaluations);
  EXPECT_EQ(by_eta.RankOrder(), (std::vector<int>{1, 2, 0}));
  for (RankingMeasure measure : {RankingMeasure::kSsim, RankingMeasure::kDeltaE2000}) {
    const MethodComparison c = CompareMethods(evaluations, measure);
    SCOPED_TRACE(std::string(RankingMeasureName(measure)));
    EXPECT_EQ(c.measure, measure);
    EXPECT_EQ(c.RankOrder(), (std::vector<int>{0, 2, 1}));
    EXPECT_NEAR(c.friedman.mean_ranks[0], 1.0, 1e-12);
    EXPECT_NEAR(c.friedman.mean_ranks[1], 3.0, 1e-12);
    EXPECT_NEAR(c.friedman.mean_ranks[2], 2.0, 1e-12);
    // Unanimous images: rank sums 5, 15, 10; 12/60 * 350 - 60 = 10.
    EXPECT_NEAR(c.friedman.chi_square, 10.0, 1e-12);
  }
  const MethodComparison ssim = CompareMethods(evaluations, RankingMeasure::kSsim);
  EXPECT_NEAR(ssim.mean_values[0], 0.982, 1e-12);  // the measure's own mean, not negated
  const nlohmann::json json = ssim.ToJson();
  EXPECT_EQ(json["measure"], "ssim_prediction_per_image");
  EXPECT_EQ(json["lower_is_better"], false);
  EXPECT_EQ(json["methods"][0]["method"], "gradient");
  EXPECT_NEAR(json["methods"][0]["mean_ssim_prediction"].get<double>(), 0.982, 1e-12);
  const std::string table = FormatComparisonTable(ssim);
  EXPECT_NE(table.find("the highest SSIM ranks 1"), std::string::npos) << table;
  EXPECT_NE(table.find("mean SSIM"), std::string::npos) << table;
  EXPECT_EQ(CompareMethods(evaluations, RankingMeasure::kDeltaE2000)
                .ToJson()["methods"][2]["mean_delta_e2000_prediction"],
            8.4);

  // A method without the measure (a streamed evaluation) cannot be ranked by it.
  evaluations[2].ssim_prediction_per_image.clear();
  try {
    CompareMethods(evaluations, RankingMeasure::kSsim);
    ADD_FAILURE() << "no error";
  } catch (const Error& e) {
    EXPECT_NE(std::string(e.what()).find("hsh9 has none"), std::string::npos) << e.what();
  }
  EXPECT_EQ(ParseRankingMeasure("delta-e2000"), RankingMeasure::kDeltaE2000);
  EXPECT_EQ(ParseRankingMeasure(RankingMeasureName(RankingMeasure::kSsim)), RankingMeasure::kSsim);
  EXPECT_THROW(ParseRankingMeasure("psnr"), Error);
}

TEST(MethodComparisonTest, UnanimousImagesHaveNoFiniteImanDavenportFInTheJson) {
  const std::vector<int> images = {1, 2, 3};
  const MethodComparison c =
      CompareMethods({Predicted("ptm", images, {1, 2, 3}), Predicted("hsh9", images, {2, 3, 4})});
  EXPECT_NEAR(c.friedman.kendalls_w, 1.0, 1e-12);
  EXPECT_TRUE(c.ToJson()["friedman"]["iman_davenport_f"].is_null());
}

TEST(MethodComparisonTest, RefusesWhatCannotBeRanked) {
  const std::vector<int> images = {0, 4, 8};
  const MethodEvaluation ptm = Predicted("ptm", images, {1, 2, 3});
  EXPECT_THROW(CompareMethods({ptm}), Error);
  MethodEvaluation reconstruction_only;
  reconstruction_only.method = Method::Parse("hsh9");
  EXPECT_THROW(CompareMethods({ptm, reconstruction_only}), Error);
  try {
    CompareMethods({ptm, Predicted("hsh9", {0, 5, 8}, {1, 2, 3})});
    FAIL() << "no error";
  } catch (const Error& e) {
    EXPECT_NE(std::string(e.what()).find("predicted different images"), std::string::npos);
  }
  EXPECT_THROW(CompareMethods({Predicted("ptm", {0}, {1}), Predicted("hsh9", {0}, {2})}), Error);
  try {
    CompareMethods({ptm, Predicted("hsh9", images, {1, std::nan(""), 3})});
    FAIL() << "no error";
  } catch (const Error& e) {
    EXPECT_NE(std::string(e.what()).find("hsh9's prediction error of image 4 is nan"),
              std::string::npos)
        << e.what();
  }
}

// Known truth: a Lambertian sample is exactly the gradient's model, so the gradient predicts every
// held-out light best, while PTM and Eigen-6 only approximate the cosine.
TEST(MethodComparisonTest, TheExactModelOfALambertianSampleRanksFirstInEveryHeldOutImage) {
  const auto synthetic = testing::LambertianSet(SurfacePattern::kBumps, 32);
  const Observations observations(synthetic.set);
  EvaluationOptions options;
  options.hold_out_every = 3;
  std::vector<MethodEvaluation> evaluations;
  for (const char* name : {"ptm", "gradient", "eigen6"}) {
    evaluations.push_back(
        EvaluateMethod(synthetic.set, observations, Method::Parse(name), nullptr, options));
  }
  const MethodComparison c = CompareMethods(evaluations);
  EXPECT_EQ(c.images.size(), (synthetic.set.size() + 2) / 3u);
  EXPECT_EQ(c.friedman.mean_ranks[1], 1.0) << FormatComparisonTable(c);
  // Gradient first in all 12 images, the others 2.5 apart on average: chi-square at least
  // 12/(12*3*4) (12^2 + 2 * 30^2) - 144 = 18 (its value when they split evenly), p <= exp(-9).
  EXPECT_GE(c.friedman.chi_square, 18.0 - 1e-9) << FormatComparisonTable(c);
  EXPECT_LT(c.friedman.p_value, 1.3e-4) << FormatComparisonTable(c);
  EXPECT_LT(std::max(c.pairwise_p(1, 0), c.pairwise_p(1, 2)), 0.05) << FormatComparisonTable(c);
}

}  // namespace
}  // namespace photomat
