// The evaluation report made band by band (WriteEvaluationReportStreamed) against the in-memory
// report of the same evaluations: the same page and pictures, on a masked set with ground truth,
// wide enough to be shown reduced.
#include <fmt/format.h>
#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include <algorithm>
#include <cstdio>
#include <numeric>
#include <string>
#include <vector>

#include "calibrate/radiometry/exposure.h"
#include "capture/io/capture_manifest.h"
#include "capture/io/load_photometric_set.h"
#include "capture/io/streamed_set.h"
#include "core/atomic_file.h"
#include "core/error.h"
#include "core/image_io.h"
#include "core/json_file.h"
#include "relight/web/evaluation_report.h"
#include "relight/web/report_pictures.h"
#include "represent/fitting/fit.h"
#include "represent/stack/map_stack.h"
#include "tests/support/synthetic_sets.h"
#include "tests/support/test_support.h"

namespace photomat {
namespace {

namespace fs = std::filesystem;

// The 32 x 32 bumps set tiled to 1100 x 40 (shown at 1/2: ReportDisplayFactor), with a mask
// that leaves out a band of rows and a corner, saved to `folder` with its truth normals.
struct SavedSet {
  fs::path folder;
  fs::path truth;
};
SavedSet SaveWideMaskedSet(const fs::path& dir) {
  const auto synthetic = testing::LambertianSet(SurfacePattern::kBumps, 32);
  constexpr int kWidth = 1100, kHeight = 40;
  const auto tile = [&](const Image& source) {
    Image out(kWidth, kHeight, source.channel_names());
    for (int c = 0; c < source.channels(); ++c) {
      for (int y = 0; y < kHeight; ++y) {
        for (int x = 0; x < kWidth; ++x) out.at(x, y, c) = source.at(x % 32, y % 32, c);
      }
    }
    return out;
  };
  std::vector<Image> images;
  for (const Image& image : synthetic.set.images()) images.push_back(tile(image));
  PhotometricSet set(std::move(images), synthetic.set.lights());
  Mask mask(kWidth, kHeight, true);
  for (int y = 0; y < kHeight; ++y) {
    for (int x = 0; x < kWidth; ++x) {
      if ((y >= 10 && y < 21) || (x < 50 && y < 8)) mask.Set(x, y, false);
    }
  }
  set.set_mask(mask);
  SavedSet saved{dir / "capture", dir / "truth.exr"};
  SavePhotometricSet(saved.folder, set);
  WriteImage(saved.truth, tile(synthetic.material.normals));
  return saved;
}

// Every file of the two reports: the page and report.json the same bytes, the pictures the same
// size and, decoded, the same codes but for at most `predicted_codes` in predictions (the
// streamed folds round by band) on at most 0.5 % of their values.
void ExpectSameReports(const fs::path& streamed, const fs::path& whole, int predicted_codes) {
  EXPECT_EQ(ReadTextFile(streamed / "index.html"), ReadTextFile(whole / "index.html"));
  EXPECT_EQ(ReadJsonFile(streamed / "report.json"), ReadJsonFile(whole / "report.json"));
  const std::vector<std::string> files = testing::EntriesOf(whole / "images");
  ASSERT_EQ(testing::EntriesOf(streamed / "images"), files);
  for (const std::string& file : files) {
    const Image a = ReadImage(streamed / "images" / file).image;
    const Image b = ReadImage(whole / "images" / file).image;
    ASSERT_TRUE(a.SameShape(b)) << file;
    int largest = 0;
    std::size_t differing = 0;
    for (std::size_t i = 0; i < a.values().size(); ++i) {
      const int d = static_cast<int>(std::lround(255 * std::abs(a.values()[i] - b.values()[i])));
      largest = std::max(largest, d);
      differing += d > 0 ? 1 : 0;
    }
    std::printf("%s: largest difference %d codes, %zu of %zu values differ\n", file.c_str(),
                largest, differing, a.values().size());
    const bool predicted = file.starts_with("predicted-");
    EXPECT_LE(largest, predicted ? predicted_codes : 0) << file;
    EXPECT_LE(differing, a.values().size() / 200) << file;
  }
}

struct ReportCase {
  std::string name;
  int hold_out_every = 0;
  bool robust = false;
};

// Leave-one-out, held out and robust held out: evaluated in memory, reported in memory and
// streamed in bands of 3 rows (the display blocks of 2 rows straddle bands; the unmasked rows
// 10-20 make whole bands the streamed folds skip).
TEST(EvaluationReportStreamedTest, TheStreamedReportIsTheInMemoryReport) {
  const testing::TempDir dir;
  const SavedSet saved = SaveWideMaskedSet(dir.path());
  const LoadedSet loaded = LoadPhotometricSet(saved.folder);
  const Image truth = ReadImage(saved.truth).image;
  const Observations observations(loaded.set);
  // The robust fits leave out clipped and dark samples, as the streamed ones do per band.
  const std::vector<Mask> measured = MeasuredPixelMasks(loaded.set);
  std::vector<int> every_image(loaded.set.size());
  std::iota(every_image.begin(), every_image.end(), 0);
  for (const ReportCase& c :
       {ReportCase{"loo"}, ReportCase{"held-out", 4}, ReportCase{"robust", 4, true}}) {
    EvaluationOptions evaluation;
    evaluation.hold_out_every = c.hold_out_every;
    if (c.robust) {
      evaluation.robust.emplace();
      evaluation.robust->loss = RobustLoss::kTukey;
      evaluation.robust->measured = measured;
    }
    std::vector<MethodEvaluation> evaluations;
    std::vector<fs::path> stacks;
    for (const char* name : {"gradient", "ptm"}) {
      const Method method = Method::Parse(name);
      evaluations.push_back(EvaluateMethod(loaded.set, observations, method, &truth, evaluation));
      // The fit of every image, as the evaluation made it.
      const Representation fit = c.robust
                                     ? RobustFit(observations, loaded.set.lights(), every_image,
                                                 *evaluation.robust, loaded.set.source())
                                           .Fit(method)
                                     : Fit(loaded.set, method);
      stacks.push_back(dir / fmt::format("{}-{}.exr", c.name, name));
      SaveRepresentation(stacks.back(), fit);
    }
    EvaluationReportOptions options;
    options.robust = evaluation.robust;
    const fs::path whole = dir / (c.name + "-whole");
    WriteEvaluationReport(whole, loaded.set, evaluations, &truth, options);
    StreamedSet set = OpenStreamedSet(saved.folder);
    StreamedReportOptions bands;
    bands.band_rows = 3;
    const fs::path streamed = dir / (c.name + "-streamed");
    WriteEvaluationReportStreamed(streamed, set, stacks, evaluations, saved.truth, options, bands);
    SCOPED_TRACE(c.name);
    // Shown at 1/2 (550 x 20), as the page says.
    EXPECT_EQ(ReadJsonFile(whole / "report.json")["display_factor"], 2);
    EXPECT_THAT(ReadTextFile(whole / "index.html"), ::testing::HasSubstr("shown at 1/2"));
    const Image heat = ReadImage(whole / "images" / "normal-error-gradient.png").image;
    EXPECT_EQ(heat.width(), 550);
    EXPECT_EQ(heat.height(), 20);
    // Measured: no code differs in any picture (bound: one code in predictions).
    ExpectSameReports(streamed, whole, 1);
  }
}

// A stack of another size than the set is refused, naming it, and no report is left.
TEST(EvaluationReportStreamedTest, AStackOfAnotherSizeIsRefusedNamingIt) {
  const testing::TempDir dir;
  const SavedSet saved = SaveWideMaskedSet(dir.path());
  const LoadedSet loaded = LoadPhotometricSet(saved.folder);
  const Observations observations(loaded.set);
  EvaluationOptions evaluation;
  evaluation.prediction = false;
  const std::vector<MethodEvaluation> evaluations = {
      EvaluateMethod(loaded.set, observations, Method::Parse("gradient"), nullptr, evaluation)};
  const auto small = testing::LambertianSet(SurfacePattern::kBumps, 16);
  const std::vector<fs::path> stacks = {dir / "small.exr"};
  SaveRepresentation(stacks.front(), Fit(small.set, Method::Parse("gradient")));
  StreamedSet set = OpenStreamedSet(saved.folder);
  EXPECT_THAT([&] { WriteEvaluationReportStreamed(dir / "r", set, stacks, evaluations, {}); },
              ::testing::ThrowsMessage<Error>(::testing::HasSubstr("small.exr")));
  EXPECT_FALSE(fs::exists(dir / "r"));
}

}  // namespace
}  // namespace photomat
