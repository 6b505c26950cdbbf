// End-to-end tests of `photomat evaluate --compare`: the ranking of methods over held-out images
// (Friedman test, Nemenyi p-values) in the printed table, the JSON and the HTML report.
#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include <cmath>
#include <filesystem>
#include <string>

#include "core/atomic_file.h"
#include "core/json_file.h"
#include "tests/support/test_support.h"

namespace photomat {
namespace {

namespace fs = std::filesystem;
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
  // Every method is still a key of its own beside "comparison", with the appearance of its
  // predictions (an RGB capture: SSIM and colour difference), one value per predicted image.
  for (const char* method : {"gradient", "ptm", "eigen6"}) {
    ASSERT_TRUE(json.contains(method));
    const nlohmann::json& m = json[method];
    EXPECT_EQ(m["ssim_prediction_per_image"].size(), 9u) << method;
    EXPECT_EQ(m["delta_e2000_prediction_per_image"].size(), 9u) << method;
    EXPECT_GT(m["ssim_prediction"].get<double>(), 0.5) << method;
    EXPECT_LE(m["ssim_prediction"].get<double>(), 1.0) << method;
    EXPECT_GE(m["delta_e2000_prediction"].get<double>(), 0.0) << method;
  }
  // The bumps are Lambertian and unshadowed: gradient predicts them best on every measure.
  EXPECT_GT(json["gradient"]["ssim_prediction"], json["eigen6"]["ssim_prediction"]);
  EXPECT_LT(json["gradient"]["delta_e2000_prediction"], json["eigen6"]["delta_e2000_prediction"]);
  EXPECT_THAT(evaluate.output, HasSubstr("psnr_dB    ssim  dE2000"));
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
  EXPECT_THAT(html, HasSubstr("<th>PSNR (dB)</th><th>SSIM</th><th>&#916;E 2000</th>"));
  // Each predicted picture's caption gives its own scores.
  EXPECT_THAT(html, ::testing::ContainsRegex("e/&#963; [0-9.e-]+, SSIM [01][.][0-9]{3}, "
                                             "&#916;E [0-9]+[.][0-9]{2}</td>"));
  const nlohmann::json report = ReadJsonFile(dir / "report" / "report.json");
  EXPECT_EQ(report["comparison"], c);
  // With held-out images the report shows held-out images by default, with their predictions.
  for (const auto& shown : report["images_shown"]) EXPECT_EQ(shown.get<int>() % 4, 0) << shown;
  EXPECT_THAT(html, HasSubstr("images/predicted-eigen6-"));
}

TEST(EvaluateCompareCliTest, RanksByTheAppearanceOfThePredictions) {
  TempDir dir;
  const std::string capture = (dir / "capture").string();
  testing::GenerateCapture(capture, "--size 24x20 --pattern bumps --seed 5");
  for (const std::string measure : {"ssim", "delta-e2000"}) {
    SCOPED_TRACE(measure);
    const fs::path json_file = dir / (measure + ".json");
    const RunResult evaluate = RunPhotomat(
        "evaluate " + capture + " --methods gradient,ptm,eigen6 --hold-out-every 4 --compare " +
        "--rank-by " + measure + " --json " + json_file.string());
    ASSERT_EQ(evaluate.exit_code, 0) << evaluate.output;
    const nlohmann::json json = ReadJsonFile(json_file);
    const nlohmann::json& c = json["comparison"];
    const std::string key = measure == "ssim" ? "ssim_prediction" : "delta_e2000_prediction";
    EXPECT_EQ(c["measure"], key + "_per_image");
    EXPECT_EQ(c["lower_is_better"], measure != "ssim");
    // The Lambertian bumps: gradient predicts every held-out image best by either measure, as
    // by eta (the test above).
    EXPECT_EQ(c["methods"][0]["method"], "gradient") << c.dump(1);
    EXPECT_EQ(c["methods"][0]["mean_rank"], 1.0) << c.dump(1);
    for (const auto& m : c["methods"]) {
      const std::string name = m["method"];
      EXPECT_NEAR(m["mean_" + key].get<double>(), json[name][key].get<double>(), 1e-12) << name;
    }
    EXPECT_THAT(evaluate.output, HasSubstr(measure == "ssim" ? "the highest SSIM ranks 1"
                                                             : "the lowest mean Delta E 2000"));
  }
}

TEST(EvaluateCompareCliTest, RefusesARankingByAMeasureItCannotHave) {
  TempDir dir;
  const std::string capture = (dir / "capture").string();
  testing::GenerateCapture(capture, "--size 12x10 --seed 1");
  const std::string evaluate =
      "evaluate " + capture + " --methods gradient,ptm --hold-out-every 4 ";
  const RunResult unknown = RunPhotomat(evaluate + "--compare --rank-by psnr");
  EXPECT_EQ(unknown.exit_code, 1);
  EXPECT_THAT(unknown.output, HasSubstr("unknown ranking measure 'psnr'"));
  const RunResult without_compare = RunPhotomat(evaluate + "--rank-by ssim");
  EXPECT_EQ(without_compare.exit_code, 1);
  EXPECT_THAT(without_compare.output, HasSubstr("add --compare"));
  // Streamed, only held-out images are compared so: a streamed leave-one-out is refused before
  // any fit, nothing written.
  const std::string leave_one_out = "evaluate " + capture + " --methods gradient,ptm ";
  const RunResult streamed = RunPhotomat(leave_one_out + "--compare --rank-by ssim --stream " +
                                         "--json " + (dir / "out" / "e.json").string());
  EXPECT_EQ(streamed.exit_code, 1);
  EXPECT_THAT(streamed.output, HasSubstr("--rank-by ssim: the streamed evaluation (--stream)"));
  EXPECT_FALSE(fs::exists(dir / "out"));
  const RunResult appearance = RunPhotomat(leave_one_out + "--appearance always --stream --json " +
                                           (dir / "out" / "e.json").string());
  EXPECT_EQ(appearance.exit_code, 1);
  EXPECT_THAT(appearance.output,
              HasSubstr("--appearance always: the streamed evaluation (--stream)"));
  EXPECT_FALSE(fs::exists(dir / "out"));
  const RunResult never = RunPhotomat(evaluate + "--compare --rank-by ssim --appearance never");
  EXPECT_EQ(never.exit_code, 1);
  EXPECT_THAT(never.output, HasSubstr("not with --appearance never"));
}

// Leave-one-out measures the SSIM and colour difference when asked (--appearance always) or when
// the ranking needs them; held-out predictions have them unless --appearance never.
TEST(EvaluateCompareCliTest, LeaveOneOutMeasuresAppearanceWhenAskedOrRankedByIt) {
  TempDir dir;
  const std::string capture = (dir / "capture").string();
  testing::GenerateCapture(capture, "--size 12x10 --seed 1");
  const std::string evaluate = "evaluate " + capture + " --methods gradient,ptm --json ";
  for (const std::string extra : {"", " --appearance always", " --compare --rank-by delta-e2000"}) {
    SCOPED_TRACE(extra);
    const fs::path json_file = dir / "e.json";
    const RunResult run = RunPhotomat(evaluate + json_file.string() + extra);
    ASSERT_EQ(run.exit_code, 0) << run.output;
    const nlohmann::json json = ReadJsonFile(json_file);
    EXPECT_EQ(json["ptm"]["eta_prediction_per_image"].size(), 36u);
    EXPECT_EQ(json["ptm"].contains("ssim_prediction"), !extra.empty());
    EXPECT_EQ(json["ptm"].contains("delta_e2000_prediction_per_image"), !extra.empty());
    if (!extra.empty()) {
      EXPECT_EQ(json["ptm"]["ssim_prediction_per_image"].size(), 36u);
    }
  }
  for (const std::string appearance : {"auto", "never"}) {
    const fs::path json_file = dir / (appearance + ".json");
    const RunResult run = RunPhotomat(evaluate + json_file.string() + " --hold-out-every 4 " +
                                      "--appearance " + appearance);
    ASSERT_EQ(run.exit_code, 0) << run.output;
    const nlohmann::json json = ReadJsonFile(json_file);
    EXPECT_EQ(json["ptm"]["eta_prediction_per_image"].size(), 9u);
    EXPECT_EQ(json["ptm"].contains("ssim_prediction"), appearance == "auto") << appearance;
  }
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
