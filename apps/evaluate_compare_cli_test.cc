// End-to-end tests of `photomat evaluate --compare`: the ranking of methods over held-out images
// (Friedman test, Nemenyi p-values) in the printed table, the JSON and the HTML report.
#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include <cmath>
#include <string>

#include "core/atomic_file.h"
#include "core/json_file.h"
#include "tests/support/test_support.h"

namespace photomat {
namespace {

using ::testing::HasSubstr;
using testing::RunPhotomat;
using testing::RunResult;
using testing::TempDir;

// Known truth: generate's default capture is Lambertian, exactly the gradient's model, which
// predicts every held-out light (every fourth of the 36) best.
TEST(EvaluateCompareCliTest, RanksTheMethodsInTheTableTheJsonAndTheReport) {
  TempDir dir;
  const std::string capture = (dir / "capture").string();
  testing::GenerateCapture(capture, "--size 24x20 --pattern bumps --seed 5");
  const RunResult evaluate = RunPhotomat(
      "evaluate " + capture + " --methods gradient,ptm,eigen6 --hold-out-every 4 --compare " +
      "--json " + (dir / "e.json").string() + " --report " + (dir / "report").string());
  ASSERT_EQ(evaluate.exit_code, 0) << evaluate.output;
  EXPECT_THAT(evaluate.output, HasSubstr("Ranking over 9 predicted images"));
  EXPECT_THAT(evaluate.output, HasSubstr("Friedman chi-square"));
  EXPECT_THAT(evaluate.output, HasSubstr("Nemenyi critical difference (alpha 0.05)"));

  const nlohmann::json json = ReadJsonFile(dir / "e.json");
  ASSERT_TRUE(json.contains("comparison")) << json.dump(1);
  const nlohmann::json& c = json["comparison"];
  EXPECT_EQ(c["images"], nlohmann::json({0, 4, 8, 12, 16, 20, 24, 28, 32}));
  ASSERT_EQ(c["methods"].size(), 3u);
  // Every method is still a key of its own beside "comparison".
  for (const char* method : {"gradient", "ptm", "eigen6"}) EXPECT_TRUE(json.contains(method));
  EXPECT_EQ(c["methods"][0]["method"], "gradient") << c.dump(1);
  EXPECT_EQ(c["methods"][0]["mean_rank"], 1.0) << c.dump(1);  // first in every image
  double rank_sum = 0.0;
  for (const auto& m : c["methods"]) rank_sum += m["mean_rank"].get<double>();
  EXPECT_NEAR(rank_sum, 6.0, 1e-9);  // k (k + 1) / 2 for three methods
  EXPECT_EQ(c["friedman"]["degrees_of_freedom"], 2);
  EXPECT_EQ(c["friedman"]["blocks"], 9);
  const double p = c["friedman"]["p_value"].get<double>();
  EXPECT_GT(p, 0.0);
  EXPECT_LT(p, 0.05);
  EXPECT_GE(c["friedman"]["kendalls_w"].get<double>(), 0.0);
  EXPECT_LE(c["friedman"]["kendalls_w"].get<double>(), 1.0);
  // Nemenyi, k = 3, n = 9: Demsar's q_0.05 = 2.343 times sqrt(12 / 54).
  EXPECT_NEAR(c["nemenyi"]["critical_difference"].get<double>(), 2.343 * std::sqrt(12.0 / 54.0),
              1e-3);
  EXPECT_EQ(c["nemenyi"]["p_values"]["ptm"]["gradient"],
            c["nemenyi"]["p_values"]["gradient"]["ptm"]);

  const std::string html = ReadTextFile(dir / "report" / "index.html");
  EXPECT_THAT(html, HasSubstr("<section id=\"ranking\">"));
  EXPECT_THAT(html, HasSubstr("<svg class=\"cd-diagram\""));
  EXPECT_THAT(html, HasSubstr("data-cd-method=\"eigen6\""));
  EXPECT_THAT(html, HasSubstr("<table class=\"pairwise\">"));
  const nlohmann::json report = ReadJsonFile(dir / "report" / "report.json");
  EXPECT_EQ(report["comparison"], c);
  // With held-out images the report shows held-out images by default, with their predictions.
  for (const auto& shown : report["images_shown"]) EXPECT_EQ(shown.get<int>() % 4, 0) << shown;
  EXPECT_THAT(html, HasSubstr("images/predicted-eigen6-"));
}

TEST(EvaluateCompareCliTest, RefusesAComparisonWithoutPredictionOrOfOneMethod) {
  TempDir dir;
  const std::string capture = (dir / "capture").string();
  testing::GenerateCapture(capture, "--size 12x10 --seed 1");
  const RunResult no_prediction =
      RunPhotomat("evaluate " + capture + " --methods gradient,ptm --no-prediction --compare");
  EXPECT_EQ(no_prediction.exit_code, 1);
  EXPECT_THAT(no_prediction.output, HasSubstr("--compare ranks two or more methods"));
  const RunResult one = RunPhotomat("evaluate " + capture + " --methods ptm --compare");
  EXPECT_EQ(one.exit_code, 1);
  EXPECT_THAT(one.output, HasSubstr("at least two methods"));
}

}  // namespace
}  // namespace photomat
