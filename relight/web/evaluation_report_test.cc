#include "relight/web/evaluation_report.h"

#include <fmt/format.h>
#include <gtest/gtest.h>

#include <Eigen/Geometry>
#include <cmath>
#include <numbers>
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

std::size_t Count(const std::string& text, const std::string& pattern) {
  const std::regex re(pattern);
  return static_cast<std::size_t>(
      std::distance(std::sregex_iterator(text.begin(), text.end(), re), std::sregex_iterator()));
}

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
  EXPECT_EQ(Count(html, "<svg class=\"chart method-chart\""), methods.size());
  for (const auto& name : methods) {
    EXPECT_EQ(Count(html, "data-method=\"" + name + "\""), 1u) << name;
    // The table row holds the numbers the evaluation measured.
    const auto& e = evaluations[&name - methods.data()];
    EXPECT_NE(html.find(fmt::format("<tr><td>{}</td><td>{:.5f}</td><td>{:.5f}</td>", name,
                                    e.eta_reconstruction, *e.eta_prediction)),
              std::string::npos)
        << name;
  }
  EXPECT_EQ(Count(html, "class=\"chart summary-chart\""), 1u);
  EXPECT_EQ(Count(html, "class=\"chart normal-chart\""), 1u);
  EXPECT_EQ(html.find("<script"), std::string::npos);
  EXPECT_EQ(html.find("http"), std::string::npos);  // nothing from the network

  // Heat maps for the three methods with normals (not Eigen-k), images beside relit and predicted.
  for (const char* name : {"3i", "gradient", "ptm"}) {
    EXPECT_TRUE(fs::exists(dir / "report" / "images" / fmt::format("normal-error-{}.png", name)));
  }
  EXPECT_FALSE(fs::exists(dir / "report" / "images" / "normal-error-eigen3.png"));
  EXPECT_EQ(Count(html, "class=\"relit-row\""), 2u);
  EXPECT_EQ(Count(html, "class=\"predicted-row\""), 2u);
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
  EXPECT_EQ(Count(html, "<svg class=\"chart method-chart\""), 2u);
  EXPECT_EQ(Count(html, "normal-chart"), 0u);
  EXPECT_EQ(Count(html, "heat-map"), 0u);
  EXPECT_EQ(Count(html, "class=\"relit-row\""), 3u);  // three spread-out lights by default
  EXPECT_EQ(Count(html, "predicted-row"), 0u);
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

TEST(EvaluationReportTest, AngularErrorMapAndHeatMapShowAKnownRotation) {
  // Each true normal is the estimate turned by exactly 12 degrees (about an axis perpendicular to
  // it): every valid pixel errs by 12 degrees.
  const auto synthetic = testing::LambertianSet(SurfacePattern::kBricks, 16);
  const Image& estimated = synthetic.material.normals;
  Image truth = estimated;
  for (std::size_t p = 0; p < truth.pixel_count(); ++p) {
    const auto n = estimated.pixel(p);
    const Eigen::Vector3d v(n[0], n[1], n[2]);
    const Eigen::Vector3d axis = v.cross(Eigen::Vector3d(0.3, 0.5, 0.8));
    const Eigen::Vector3d r =
        Eigen::AngleAxisd(12.0 * std::numbers::pi / 180.0, axis.normalized()) * v;
    for (int c = 0; c < 3; ++c) truth.pixel(p)[c] = static_cast<float>(r[c]);
  }
  for (int c = 0; c < 3; ++c) truth.at(3, 4, c) = 0.0f;  // no truth at (3, 4)
  Mask mask(16, 16, true);
  mask.Set(5, 5, false);
  const Image errors = AngularErrorMap(estimated, truth, mask);
  const Image heat = HeatMap(errors, 24.0);
  const auto expected = HeatColour(0.5);
  for (int y = 0; y < 16; ++y) {
    for (int x = 0; x < 16; ++x) {
      const bool undefined = (x == 3 && y == 4) || (x == 5 && y == 5);
      if (undefined) {
        EXPECT_EQ(errors.at(x, y, 0), -1.0f);
        EXPECT_NEAR(heat.at(x, y, 0), heat.at(x, y, 2), 1e-6);  // grey
        continue;
      }
      ASSERT_NEAR(errors.at(x, y, 0), 12.0, 1e-3);
      for (int c = 0; c < 3; ++c) EXPECT_NEAR(heat.at(x, y, c), expected[c], 1e-4);
    }
  }
  // The scale runs from dark blue to red and clamps above.
  EXPECT_LT(HeatColour(0.0)[0], 0.1f);
  EXPECT_GT(HeatColour(0.0)[2], 0.3f);
  EXPECT_GT(HeatColour(1.0)[0], 0.8f);
  EXPECT_EQ(HeatColour(3.0), HeatColour(1.0));
}

TEST(EvaluationReportTest, BarChartBarsAreProportionalToTheirValues) {
  BarChart chart{"a <b> & c",     "eta",
                 {"x", "y", "z"}, {{"one", {0.5, 1.0, 2.0}}, {"two", {1.5, NAN, 0.25}}},
                 "chart",         ""};
  const std::string svg = BarChartSvg(chart);
  EXPECT_NE(svg.find("a &lt;b&gt; &amp; c"), std::string::npos);
  const std::regex bar(
      "<rect class=\"bar\"[^>]* height=\"([0-9.]+)\"[^>]* data-value=\"([0-9.e+-]+)\"");
  std::vector<std::pair<double, double>> bars;  // (height, value)
  for (auto it = std::sregex_iterator(svg.begin(), svg.end(), bar); it != std::sregex_iterator();
       ++it) {
    bars.emplace_back(std::stod((*it)[1].str()), std::stod((*it)[2].str()));
  }
  ASSERT_EQ(bars.size(), 5u);  // the NaN draws nothing
  const double per_unit = bars[0].first / bars[0].second;
  for (const auto& [height, value] : bars) EXPECT_NEAR(height, per_unit * value, 0.02);
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
  EXPECT_EQ(Count(html, "not held out"), 2u);  // one cell per method for image 1
  // The per-image charts draw a prediction bar for each held-out image only.
  EXPECT_EQ(Count(html, "<title>[0-9]+, prediction:"), 2 * held_out);
  EXPECT_EQ(Count(html, "<section id=\"ranking\">"), 1u);
  EXPECT_EQ(Count(html, "class=\"cd-method\""), 2u);
  const nlohmann::json report = ReadJsonFile(dir / "report" / "report.json");
  EXPECT_EQ(report["comparison"], options.comparison->ToJson());

  // By default the images shown are held-out ones.
  options.images.clear();
  WriteEvaluationReport(dir / "report2", synthetic.set, evaluations, nullptr, options);
  const nlohmann::json shown = ReadJsonFile(dir / "report2" / "report.json")["images_shown"];
  ASSERT_EQ(shown.size(), 3u);
  for (const auto& index : shown) EXPECT_EQ(index.get<int>() % 6, 0) << index;
}

// Demsar (2006), Figure 1(a): at alpha 0.10 (critical difference 1.12) the Nemenyi test joins
// C4.5+m+cf, C4.5+m and C4.5+cf in one group and C4.5+cf and C4.5 in another.
TEST(EvaluationReportTest, CriticalDifferenceDiagramJoinsDemsarsTwoGroups) {
  MethodComparison c;
  c.methods = {"C4.5", "C4.5+m", "C4.5+cf", "C4.5+m+cf"};
  c.friedman.mean_ranks = {3.143, 2.000, 2.893, 1.964};
  c.alpha = 0.10;
  c.critical_difference = 1.12;
  EXPECT_EQ(c.RankOrder(), (std::vector<int>{3, 1, 2, 0}));
  EXPECT_EQ(IndistinguishableRuns(c), (std::vector<std::pair<int, int>>{{0, 2}, {2, 3}}));
  const std::string svg = CriticalDifferenceDiagramSvg(c);
  EXPECT_EQ(Count(svg, "class=\"cd-group\""), 2u);
  EXPECT_EQ(Count(svg, "class=\"cd-method\""), 4u);
  EXPECT_NE(svg.find("CD = 1.12"), std::string::npos);
  // The best mean rank lies to the right of the worst.
  const auto x_of = [&](const std::string& name) {
    const std::regex mark("data-cd-method=\"" + std::regex_replace(name, std::regex("\\+"), "\\+") +
                          "\"[^>]*><polyline points=\"([0-9.]+),");
    std::smatch match;
    EXPECT_TRUE(std::regex_search(svg, match, mark)) << name;
    return std::stod(match[1].str());
  };
  EXPECT_GT(x_of("C4.5+m+cf"), x_of("C4.5"));
  // With a critical difference below every gap nothing is joined.
  c.critical_difference = 0.01;
  EXPECT_TRUE(IndistinguishableRuns(c).empty());
}

}  // namespace
}  // namespace photomat
