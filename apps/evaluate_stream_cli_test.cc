// `photomat evaluate INPUT --stream` fits the prediction's folds band by band too (README,
// "Streamed relighting and export"): these run the built executable.
#include <fmt/format.h>
#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include <cstdio>
#include <filesystem>
#include <string>
#include <vector>

#include "core/atomic_file.h"
#include "core/json_file.h"
#include "tests/support/layouts.h"
#include "tests/support/test_support.h"

namespace photomat {
namespace {

namespace fs = std::filesystem;

using ::testing::ElementsAre;
using ::testing::HasSubstr;
using ::testing::Not;
using testing::RunPhotomat;
using testing::RunResult;
using testing::TempDir;

// The prediction's figures of two evaluations' JSON agree: the predicted images, eta and PSNR of
// every method (mean and per image) within `relative` (eta) and `decibels` (PSNR), and the SSIM
// and colour difference per image, where measured, within `appearance`.
void ExpectSamePrediction(const nlohmann::json& a, const nlohmann::json& b,
                          const std::vector<std::string>& methods, double relative, double decibels,
                          double appearance = 1e-9) {
  for (const std::string& method : methods) {
    ASSERT_TRUE(a[method].contains("eta_prediction")) << method;
    EXPECT_EQ(a[method]["prediction_images"], b[method]["prediction_images"]) << method;
    const double eta = b[method]["eta_prediction"].get<double>();
    std::printf("%s: eta of prediction %.12g streamed, %.12g in memory; PSNR %.12g, %.12g\n",
                method.c_str(), a[method]["eta_prediction"].get<double>(), eta,
                a[method]["psnr_prediction"].get<double>(),
                b[method]["psnr_prediction"].get<double>());
    EXPECT_GT(eta, b[method]["eta_reconstruction"].get<double>()) << method;
    EXPECT_NEAR(a[method]["eta_prediction"].get<double>(), eta, relative * eta) << method;
    EXPECT_NEAR(a[method]["psnr_prediction"].get<double>(),
                b[method]["psnr_prediction"].get<double>(), decibels)
        << method;
    const auto& per_image = b[method]["eta_prediction_per_image"];
    for (std::size_t j = 0; j < per_image.size(); ++j) {
      const double expected = per_image[j].get<double>();
      EXPECT_NEAR(a[method]["eta_prediction_per_image"][j].get<double>(), expected,
                  relative * expected)
          << method << ", prediction " << j;
    }
    // The SSIM and colour difference: of held-out images both (streamed band by band,
    // MaskedDisplayComparison), of leave-one-out neither (in memory only with --appearance).
    // Measured: equal to the 12 digits printed (the fits are equal to float rounding).
    for (const char* key : {"ssim_prediction", "delta_e2000_prediction"}) {
      ASSERT_EQ(a[method].contains(key), b[method].contains(key)) << method << " " << key;
      if (!b[method].contains(key)) continue;
      const auto& streamed = a[method][std::string(key) + "_per_image"];
      const auto& whole = b[method][std::string(key) + "_per_image"];
      ASSERT_EQ(streamed.size(), whole.size()) << method << " " << key;
      for (std::size_t j = 0; j < whole.size(); ++j) {
        std::printf("%s %s %zu: %.12g streamed, %.12g in memory\n", method.c_str(), key, j,
                    streamed[j].get<double>(), whole[j].get<double>());
        EXPECT_NEAR(streamed[j].get<double>(), whole[j].get<double>(), appearance)
            << method << " " << key << ", prediction " << j;
      }
    }
  }
}

// The 48 x 40 capture with shadows that the tests evaluate, in `dir`/capture.
std::string WriteShadowedCapture(const TempDir& dir) {
  return testing::GenerateCapture(dir / "capture", "--size 48x40 --shadows --seed 4");
}

// `photomat evaluate CAPTURE ARGUMENTS --json FILE` in memory and streamed in bands of a few rows
// (--stream --memory 1, its JSON alone in `dir`/out: the scratch stacks are gone): both JSONs.
struct InMemoryAndStreamed {
  nlohmann::json whole;
  nlohmann::json streamed;
};
InMemoryAndStreamed EvaluateInMemoryAndStreamed(const TempDir& dir, const std::string& capture,
                                                const std::string& arguments) {
  const RunResult whole =
      RunPhotomat("evaluate " + capture + arguments + " --json " + (dir / "whole.json").string());
  EXPECT_EQ(whole.exit_code, 0) << whole.output;
  fs::create_directories(dir / "out");
  const RunResult streamed =
      RunPhotomat("evaluate " + capture + arguments + " --stream --memory 1 --json " +
                  (dir / "out" / "streamed.json").string());
  EXPECT_EQ(streamed.exit_code, 0) << streamed.output;
  EXPECT_THAT(streamed.output, HasSubstr("(streamed)"));
  EXPECT_THAT(testing::EntriesOf(dir / "out"), ElementsAre("streamed.json"));
  if (whole.exit_code != 0 || streamed.exit_code != 0) return {};
  return {ReadJsonFile(dir / "whole.json"), ReadJsonFile(dir / "out" / "streamed.json")};
}

// The eta of reconstruction of `methods` in two evaluations' JSON: the fits equal to float
// rounding (StreamedFitTest), bound 1e-6 relative.
void ExpectSameReconstruction(const nlohmann::json& a, const nlohmann::json& b,
                              const std::vector<std::string>& methods) {
  for (const std::string& method : methods) {
    const double eta = b[method]["eta_reconstruction"].get<double>();
    std::printf("%s: eta %.9g streamed, %.9g in memory\n", method.c_str(),
                a[method]["eta_reconstruction"].get<double>(), eta);
    EXPECT_NEAR(a[method]["eta_reconstruction"].get<double>(), eta, 1e-6 * eta) << method;
  }
}

// `photomat evaluate INPUT --stream` fits the methods in bands into scratch stacks and evaluates
// those streamed: the eta of reconstruction of the in-memory evaluation to float rounding and its
// normal errors; the scratch is gone afterwards.
TEST(EvaluateStreamCliTest, ReconstructionStreamedGivesTheInMemoryEtaAndNormalErrors) {
  const TempDir dir;
  const auto [b, a] = EvaluateInMemoryAndStreamed(dir, WriteShadowedCapture(dir),
                                                  " --methods gradient,ptm,eigen6 --no-prediction");
  ASSERT_FALSE(a.is_null());
  ExpectSameReconstruction(a, b, {"gradient", "ptm", "eigen6"});
  for (const char* method : {"gradient", "ptm", "eigen6"}) {
    EXPECT_EQ(a[method].contains("normals"), b[method].contains("normals")) << method;
  }
  EXPECT_FALSE(a["eigen6"].contains("normals"));
  for (const char* method : {"gradient", "ptm"}) {
    const nlohmann::json& n = a[method]["normals"];
    EXPECT_EQ(n["pixels"], b[method]["normals"]["pixels"]) << method;
    EXPECT_NEAR(n["mean_angular_error_deg"].get<double>(),
                b[method]["normals"]["mean_angular_error_deg"].get<double>(), 1e-6)
        << method;
    EXPECT_NEAR(n["median_angular_error_deg"].get<double>(),
                b[method]["normals"]["median_angular_error_deg"].get<double>(), 1e-6)
        << method;
  }
}

// Leave-one-out and held-out prediction streamed in bands (--memory 1: bands of a few rows) give
// the in-memory evaluation's figures, and --compare ranks the methods from them as in memory.
// The fold fits are the in-memory ones (StreamedEvaluationTest.BandsGiveTheInMemoryPrediction,
// 1e-14); measured here: the same printed digits. Bounds 1e-9 relative and 1e-8 dB.
TEST(EvaluateStreamCliTest, PredictionStreamedGivesTheInMemoryFiguresAndRanking) {
  const TempDir dir;
  const std::string capture = WriteShadowedCapture(dir);
  const std::vector<std::string> methods = {"gradient", "ptm", "eigen6", "rbf"};
  for (const std::string held_out :
       {"", " --hold-out-every 4", " --hold-out-every 4 --rank-by delta-e2000"}) {
    SCOPED_TRACE(held_out.empty() ? "leave-one-out" : held_out);
    const auto [b, a] = EvaluateInMemoryAndStreamed(
        dir, capture, held_out + " --methods gradient,ptm,eigen6,rbf --compare");
    ASSERT_FALSE(a.is_null());
    ExpectSamePrediction(a, b, methods, 1e-9, 1e-8);
    // The same ranking: methods in the same order with the same mean ranks, the same statistic.
    const auto& ranked = a["comparison"]["methods"];
    ASSERT_EQ(ranked.size(), methods.size());
    for (std::size_t m = 0; m < ranked.size(); ++m) {
      EXPECT_EQ(ranked[m]["method"], b["comparison"]["methods"][m]["method"]);
      EXPECT_EQ(ranked[m]["mean_rank"], b["comparison"]["methods"][m]["mean_rank"]);
    }
    EXPECT_EQ(a["comparison"]["friedman"]["chi_square"], b["comparison"]["friedman"]["chi_square"]);
  }
}

// Robust fits stream too, prediction included, for the methods fitted per pixel from the robust
// weights and for those fitted on imputed profiles (Eigen-k's EM, rbf): the in-memory robust
// figures (the fold fits are the same, StreamedEvaluationTest).
TEST(EvaluateStreamCliTest, RobustPredictionStreamedGivesTheInMemoryFigures) {
  const TempDir dir;
  const std::vector<std::string> methods = {"gradient", "ptm", "eigen6", "rbf"};
  const auto [b, a] = EvaluateInMemoryAndStreamed(
      dir, WriteShadowedCapture(dir),
      " --robust --loss tukey --methods gradient,ptm,eigen6,rbf --hold-out-every 4");
  ASSERT_FALSE(a.is_null());
  ExpectSamePrediction(a, b, methods, 1e-9, 1e-8);
  ExpectSameReconstruction(a, b, methods);
}

TEST(EvaluateStreamCliTest, StreamingRefusesTooSmallFolds) {
  const TempDir dir;
  const std::string capture = testing::GenerateCapture(dir / "capture", "--size 24x20 --seed 4");
  // Holding out every image leaves none to fit: refused before anything is fitted or written.
  fs::create_directories(dir / "out");
  const RunResult small =
      RunPhotomat("evaluate " + capture + " --stream --methods ptm --hold-out-every 1 --json " +
                  (dir / "out" / "e.json").string());
  EXPECT_EQ(small.exit_code, 1) << small.output;
  EXPECT_THAT(small.output, HasSubstr("a prediction fold fits 0 images; ptm needs 6"));
  EXPECT_TRUE(testing::EntriesOf(dir / "out").empty());
}

// What streaming is for: under a hard address-space limit far below what holding the set needs
// (1536 x 1536 x 36 lights x RGB: 3.4 GB at kWholeSetBytesPerPixelImage), `evaluate` with held-out
// prediction streams by itself (the whole set does not fit the default budget) and gives the
// figures of the in-memory evaluation without the limit, which fails under it (measured: 8e-12
// relative in PTM's eta, the sums over 40-row bands against one; bound 1e-9).
TEST(EvaluateStreamCliTest, UnderAnAddressSpaceLimitPredictionStreamsByItselfAndMatches) {
  const TempDir dir;
  const std::string lights =
      testing::WriteLargeLambertianCapture(dir / "capture", 1536, 1536).string();
  // 1000 MiB where the program starts in 453 (testing::StartupAddressSpace).
  const std::size_t limit = testing::StartupAddressSpace("evaluate") + (std::size_t{547} << 20);
  const std::string common = " --methods gradient,ptm --hold-out-every 4 --json ";
  const RunResult limited =
      RunPhotomat("evaluate " + lights + common + (dir / "limited.json").string(), {limit});
  ASSERT_EQ(limited.exit_code, 0) << limited.output;
  std::printf("%s", limited.output.c_str());
  EXPECT_THAT(limited.output, HasSubstr("(streamed)"));
  const RunResult refused = RunPhotomat(
      "evaluate " + lights + common + (dir / "refused.json").string() + " --memory 100000",
      {limit});
  EXPECT_NE(refused.exit_code, 0) << refused.output;
  EXPECT_THAT(refused.output, HasSubstr("out of memory"));
  EXPECT_FALSE(fs::exists(dir / "refused.json"));
  const RunResult whole = RunPhotomat("evaluate " + lights + common +
                                      (dir / "whole.json").string() + " --memory 100000");
  ASSERT_EQ(whole.exit_code, 0) << whole.output;
  EXPECT_THAT(whole.output, Not(HasSubstr("(streamed)")));
  ExpectSamePrediction(ReadJsonFile(dir / "limited.json"), ReadJsonFile(dir / "whole.json"),
                       {"gradient", "ptm"}, 1e-9, 1e-8);
}

// `evaluate --stream --report`: the report's pictures drawn band by band from the scratch stacks,
// the photographs and the shown images' prediction folds
// (relight/web/evaluation_report.h, WriteEvaluationReportStreamed): the in-memory report's
// pictures byte for byte (measured), the same images shown, the same eta to float rounding;
// least squares and robust (Eigen-k's robust folds by their EM passes).
TEST(EvaluateStreamCliTest, AReportStreamsAndShowsTheInMemoryPictures) {
  const TempDir dir;
  const std::string capture = testing::GenerateCapture(dir / "capture", "--size 40x36 --seed 5");
  for (const std::string fit : {"least-squares", "robust"}) {
    SCOPED_TRACE(fit);
    const fs::path out = dir / fit;
    const std::string evaluate = "evaluate " + capture + " --methods gradient,ptm,eigen6" +
                                 (fit == "robust" ? " --robust" : "") + " --report ";
    const RunResult whole = RunPhotomat(evaluate + (out / "whole").string());
    ASSERT_EQ(whole.exit_code, 0) << whole.output;
    const RunResult streamed =
        RunPhotomat(evaluate + (out / "streamed").string() + " --stream --memory 1");
    ASSERT_EQ(streamed.exit_code, 0) << streamed.output;
    EXPECT_THAT(streamed.output, HasSubstr("(streamed)"));
    const nlohmann::json a = ReadJsonFile(out / "streamed" / "report.json");
    const nlohmann::json b = ReadJsonFile(out / "whole" / "report.json");
    EXPECT_EQ(a["images_shown"], b["images_shown"]);
    ASSERT_EQ(a["evaluation"].size(), 3u);
    for (const char* method : {"gradient", "ptm", "eigen6"}) {
      for (const char* eta : {"eta_reconstruction", "eta_prediction"}) {
        const double x = a["evaluation"][method][eta], y = b["evaluation"][method][eta];
        EXPECT_NEAR(x, y, 1e-9 * y) << method << " " << eta;
      }
    }
    const std::vector<std::string> files = testing::EntriesOf(out / "whole" / "images");
    ASSERT_EQ(testing::EntriesOf(out / "streamed" / "images"), files);
    // Captured, relit and predicted; the heat maps of Gradient and PTM (Eigen-k gives no
    // normals).
    EXPECT_EQ(files.size(), 3u * (1 + 2 * 3) + 2);
    for (const std::string& file : files) {
      EXPECT_EQ(ReadTextFile(out / "streamed" / "images" / file),
                ReadTextFile(out / "whole" / "images" / file))
          << file;
    }
    // Nothing beside the report: the scratch stacks are gone.
    EXPECT_THAT(testing::EntriesOf(out), ::testing::ElementsAre("streamed", "whole"));
  }
}

// A photograph truncated part-way: the streamed evaluation with a report fails naming it, and
// leaves neither report, JSON nor scratch stacks.
TEST(EvaluateStreamCliTest, AnImageTruncatedMidwayLeavesNoReport) {
  const TempDir dir;
  const std::string capture = testing::GenerateCapture(dir / "capture", "--size 64x256 --seed 6");
  const fs::path victim = dir / "capture" / "img_030.png";
  fs::resize_file(victim, fs::file_size(victim) / 2);
  fs::create_directories(dir / "out");
  const RunResult evaluated = RunPhotomat(
      "evaluate " + capture + " --stream --memory 1 --methods gradient --hold-out-every 6 --json " +
      (dir / "out" / "e.json").string() + " --report " + (dir / "out" / "report").string());
  EXPECT_EQ(evaluated.exit_code, 1) << evaluated.output;
  EXPECT_THAT(evaluated.output, HasSubstr("img_030.png"));
  EXPECT_TRUE(testing::EntriesOf(dir / "out").empty()) << evaluated.output;
}

// pbr evaluates streamed too: fitted as `fit` fits it (robustly, with its --pbr-* options) in
// passes of its own, reconstruction, held-out prediction and the report's pictures; the
// in-memory evaluation's numbers to float rounding and its report's pictures byte for byte.
TEST(EvaluateStreamCliTest, PbrStreamsWithItsOwnFitOptions) {
  const TempDir dir;
  const std::string capture = testing::GenerateCapture(
      dir / "capture", "--size 24x20 --pattern bumps --ggx --roughness 0.4,0.6 --seed 7");
  const std::string evaluate =
      "evaluate " + capture + " --methods gradient,pbr --hold-out-every 6 --pbr-iterations 20 ";
  const RunResult whole = RunPhotomat(evaluate + "--json " + (dir / "whole.json").string() +
                                      " --report " + (dir / "whole").string());
  if (whole.output.find("built without") != std::string::npos) {
    GTEST_SKIP() << whole.output;  // PHOTOMAT_WITH_CERES=OFF: no pbr fit
  }
  ASSERT_EQ(whole.exit_code, 0) << whole.output;
  const RunResult streamed =
      RunPhotomat(evaluate + "--stream --memory 1 --json " + (dir / "streamed.json").string() +
                  " --report " + (dir / "streamed").string());
  ASSERT_EQ(streamed.exit_code, 0) << streamed.output;
  EXPECT_THAT(streamed.output, HasSubstr("(streamed)"));
  const nlohmann::json a = ReadJsonFile(dir / "streamed.json");
  const nlohmann::json b = ReadJsonFile(dir / "whole.json");
  for (const char* method : {"gradient", "pbr"}) {
    for (const char* eta : {"eta_reconstruction", "eta_prediction"}) {
      const double x = a[method][eta], y = b[method][eta];
      EXPECT_NEAR(x, y, 1e-9 * y) << method << " " << eta;
    }
  }
  const std::vector<std::string> files = testing::EntriesOf(dir / "whole" / "images");
  ASSERT_EQ(testing::EntriesOf(dir / "streamed" / "images"), files);
  for (const std::string& file : files) {
    EXPECT_EQ(ReadTextFile(dir / "streamed" / "images" / file),
              ReadTextFile(dir / "whole" / "images" / file))
        << file;
  }
}

}  // namespace
}  // namespace photomat
