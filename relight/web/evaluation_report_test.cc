#include "relight/web/evaluation_report.h"

#include <fmt/format.h>
#include <gtest/gtest.h>

#include <cmath>
#include <regex>

#include "core/atomic_file.h"
#include "core/error.h"
#include "core/image_io.h"
#include "core/json_file.h"
#include "represent/fitting/fit.h"
#include "tests/support/synthetic_sets.h"
#include "tests/support/test_support.h"

namespace photomat {
namespace {

namespace fs = std::filesystem;
using testing::TempDir;

std::vector<MethodEvaluation> Evaluate(const PhotometricSet& set, const Image* truth,
                                       const std::vector<std::string>& methods, bool prediction) {
  const Observations observations(set);
  EvaluationOptions options;
  options.prediction = prediction;
  std::vector<MethodEvaluation> results;
  for (const auto& name : methods) {
    results.push_back(EvaluateMethod(set, observations, Method::Parse(name), truth, options));
  }
  return results;
}

TEST(EvaluationReportTest, ShowsTheTableAChartPerMethodHeatMapsAndRelitImages) {
  TempDir dir;
  const auto synthetic = testing::ShadowedSpecularSet(24);
  const std::vector<std::string> methods = {"3i", "gradient", "ptm", "eigen3"};
  const auto evaluations = Evaluate(synthetic.set, &synthetic.material.normals, methods, true);
  EvaluationReportOptions options;
  options.images = {0, 20};
  WriteEvaluationReport(dir / "report", synthetic.set, evaluations, &synthetic.material.normals,
                        options);

  const std::string html = ReadTextFile(dir / "report" / "index.html");
  EXPECT_EQ(testing::CountMatches(html, "<svg class=\"chart method-chart\""), methods.size());
  for (const auto& name : methods) {
    EXPECT_EQ(testing::CountMatches(html, "data-method=\"" + name + "\""), 1u) << name;
    // The table row holds the numbers the evaluation measured.
    const auto& e = evaluations[&name - methods.data()];
    EXPECT_NE(html.find(fmt::format("<tr><td>{}</td><td>{:.5f}</td><td>{:.5f}</td>", name,
                                    e.eta_reconstruction, *e.eta_prediction)),
              std::string::npos)
        << name;
  }
  EXPECT_EQ(testing::CountMatches(html, "class=\"chart summary-chart\""), 1u);
  EXPECT_EQ(testing::CountMatches(html, "class=\"chart normal-chart\""), 1u);
  EXPECT_EQ(html.find("<script"), std::string::npos);
  EXPECT_EQ(html.find("http"), std::string::npos);  // nothing from the network

  // Heat maps for the three methods with normals (not Eigen-k), images beside relit and predicted.
  for (const char* name : {"3i", "gradient", "ptm"}) {
    EXPECT_TRUE(fs::exists(dir / "report" / "images" / fmt::format("normal-error-{}.png", name)));
  }
  EXPECT_FALSE(fs::exists(dir / "report" / "images" / "normal-error-eigen3.png"));
  EXPECT_EQ(testing::CountMatches(html, "class=\"relit-row\""), 2u);
  EXPECT_EQ(testing::CountMatches(html, "class=\"predicted-row\""), 2u);
  for (int index : {0, 20}) {
    for (const auto& name : methods) {
      const fs::path relit =
          dir / "report" / "images" / fmt::format("relit-{}-{}.png", name, index);
      ASSERT_TRUE(fs::exists(relit));
      EXPECT_EQ(ReadImage(relit).image.width(), 24);
      EXPECT_TRUE(
          fs::exists(dir / "report" / "images" / fmt::format("predicted-{}-{}.png", name, index)));
    }
  }
  // Every image the page names exists.
  const std::regex src("src=\"([^\"]+)\"");
  for (auto it = std::sregex_iterator(html.begin(), html.end(), src); it != std::sregex_iterator();
       ++it) {
    EXPECT_TRUE(fs::exists(dir / "report" / (*it)[1].str())) << (*it)[1].str();
  }
  const nlohmann::json manifest = ReadJsonFile(dir / "report" / "report.json");
  EXPECT_EQ(manifest["format"], "photomat-report");
  EXPECT_EQ(manifest["evaluation"], EvaluationsToJson(evaluations));
}

TEST(EvaluationReportTest, WithoutTruthOrPredictionTheReportSaysLess) {
  TempDir dir;
  const auto synthetic = testing::LambertianSet(SurfacePattern::kBumps, 16);
  const auto evaluations = Evaluate(synthetic.set, nullptr, {"gradient", "eigen6"}, false);
  WriteEvaluationReport(dir / "report", synthetic.set, evaluations, nullptr);
  const std::string html = ReadTextFile(dir / "report" / "index.html");
  EXPECT_EQ(testing::CountMatches(html, "<svg class=\"chart method-chart\""), 2u);
  EXPECT_EQ(testing::CountMatches(html, "normal-chart"), 0u);
  EXPECT_EQ(testing::CountMatches(html, "heat-map"), 0u);
  EXPECT_EQ(testing::CountMatches(html, "class=\"relit-row\""),
            3u);  // three spread-out lights by default
  EXPECT_EQ(testing::CountMatches(html, "predicted-row"), 0u);
}

TEST(EvaluationReportTest, RejectsImagesOutsideTheSetAndMismatchedEvaluations) {
  TempDir dir;
  const auto synthetic = testing::LambertianSet(SurfacePattern::kBumps, 12);
  const auto evaluations = Evaluate(synthetic.set, nullptr, {"gradient"}, false);
  EvaluationReportOptions options;
  options.images = {36};
  EXPECT_THROW(WriteEvaluationReport(dir / "r", synthetic.set, evaluations, nullptr, options),
               Error);
  const PhotometricSet subset = synthetic.set.Subset(std::vector<int>{0, 5, 10, 15});
  EXPECT_THROW(WriteEvaluationReport(dir / "r", subset, evaluations, nullptr), Error);
  EXPECT_THROW(WriteEvaluationReport(dir / "r", synthetic.set, {}, nullptr), Error);
  EXPECT_FALSE(fs::exists(dir / "r"));
}

TEST(EvaluationReportTest, ChosenImagesAreSpreadOut) {
  const auto lights = ThesisLightGrid();
  const auto chosen = ChooseReportImages(lights, 3);
  ASSERT_EQ(chosen.size(), 3u);
  EXPECT_TRUE(std::find(chosen.begin(), chosen.end(), 12) != chosen.end());  // slant 45, tilt 0
  for (std::size_t a = 0; a < 3; ++a) {
    for (std::size_t b = 0; b < a; ++b) {
      EXPECT_GT(lights[chosen[a]].AngleToDegrees(lights[chosen[b]]), 60.0);
    }
  }
  EXPECT_EQ(
      ChooseReportImages(std::vector<LightDirection>(lights.begin(), lights.begin() + 2), 3).size(),
      2u);
}

TEST(EvaluationReportTest, HeldOutImagesShowTheirPredictionsByTheOneFitAndTheRanking) {
  TempDir dir;
  const auto synthetic = testing::LambertianSet(SurfacePattern::kBumps, 16);
  const Observations observations(synthetic.set);
  EvaluationOptions evaluation;
  evaluation.hold_out_every = 6;
  std::vector<MethodEvaluation> evaluations;
  for (const char* name : {"gradient", "ptm"}) {
    evaluations.push_back(
        EvaluateMethod(synthetic.set, observations, Method::Parse(name), nullptr, evaluation));
  }
  const auto held_out = static_cast<std::size_t>((synthetic.set.size() + 5) / 6);
  EvaluationReportOptions options;
  options.images = {0, 1};  // image 0 is held out, image 1 is not
  options.comparison = CompareMethods(evaluations);
  WriteEvaluationReport(dir / "report", synthetic.set, evaluations, nullptr, options);
  const std::string html = ReadTextFile(dir / "report" / "index.html");
  EXPECT_TRUE(fs::exists(dir / "report" / "images" / "predicted-ptm-0.png"));
  EXPECT_FALSE(fs::exists(dir / "report" / "images" / "predicted-ptm-1.png"));
  EXPECT_EQ(testing::CountMatches(html, "not held out"), 2u);  // one cell per method for image 1
  // The per-image charts draw a prediction bar for each held-out image only.
  EXPECT_EQ(testing::CountMatches(html, "<title>[0-9]+, prediction:"), 2 * held_out);
  EXPECT_EQ(testing::CountMatches(html, "<section id=\"ranking\">"), 1u);
  EXPECT_EQ(testing::CountMatches(html, "class=\"cd-method\""), 2u);
  const nlohmann::json report = ReadJsonFile(dir / "report" / "report.json");
  EXPECT_EQ(report["comparison"], options.comparison->ToJson());

  // By default the images shown are held-out ones.
  options.images.clear();
  WriteEvaluationReport(dir / "report2", synthetic.set, evaluations, nullptr, options);
  const nlohmann::json shown = ReadJsonFile(dir / "report2" / "report.json")["images_shown"];
  ASSERT_EQ(shown.size(), 3u);
  for (const auto& index : shown) EXPECT_EQ(index.get<int>() % 6, 0) << index;
}

}  // namespace
}  // namespace photomat
