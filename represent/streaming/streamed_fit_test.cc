#include "represent/streaming/streamed_fit.h"

#include <gtest/gtest.h>
#include <sys/resource.h>
#include <tbb/task_arena.h>

#include <algorithm>
#include <cmath>
#include <cstdlib>
#include <filesystem>
#include <numeric>
#include <string>

#include "calibrate/radiometry/exposure.h"
#include "capture/io/capture_manifest.h"
#include "capture/io/load_photometric_set.h"
#include "capture/io/streamed_set.h"
#include "core/error.h"
#include "core/memory_limits.h"
#include "represent/fitting/fit.h"
#include "represent/fitting/pbr_fit_summary.h"
#include "represent/fitting/robust_fit.h"
#include "represent/stack/map_stack.h"
#include "tests/support/synthetic_sets.h"
#include "tests/support/test_support.h"

namespace photomat {
namespace {

namespace fs = std::filesystem;

// The methods that stream (pbr too, but its Ceres fit is slow: it shares the robust path and is
// covered by the robust forms' per-band fit).
std::vector<Method> StreamedMethods() {
  std::vector<Method> methods;
  for (const char* name :
       {"3i", "gradient", "ptm", "ptm-lrgb", "hsh9", "eigen3", "eigen6", "rbf", "bilinear"}) {
    methods.push_back(Method::Parse(name));
  }
  return methods;
}

// A 48 x 40 capture with shadows and highlights (so the robust weights matter), unequal light
// intensities (applied when read) and a mask that leaves the first 7 rows empty (bands with no
// pixel to fit), saved as 16-bit PNGs.
// Unmasked, every band takes the least-squares fit's direct decoding into the image data matrix
// (with the intensities divided out there); masked, bands the mask covers in part have their
// selected pixels gathered into it from each image's decoded band, and robust fits read band
// sets and copy.
fs::path WriteCapture(const fs::path& folder, bool masked = true) {
  const auto synthetic = testing::ShadowedSpecularSet(48);
  const PhotometricSet& full = synthetic.set;
  std::vector<Image> images;
  for (const Image& image : full.images()) images.emplace_back(image.Rows(0, 40));
  PhotometricSet set(std::move(images), full.lights());
  Mask mask(48, 40, false);
  for (int y = 7; y < 40; ++y) {
    for (int x = 0; x < 48; ++x) mask.Set(x, y, (x - 24) * (x - 24) + (y - 22) * (y - 22) < 300);
  }
  set.set_mask(mask);
  const auto intensities = testing::UnequalRgbIntensities(set.size());
  PhotometricSet scaled = testing::ScaleByIntensities(set, intensities);
  if (masked) scaled.set_mask(mask);
  scaled.set_intensities(intensities);
  SavePhotometricSet(folder, scaled);
  return folder;
}

// In memory, as `photomat fit` did before streaming: the whole set loaded, then fitted.
Representation FitInMemory(const fs::path& input, const Method& method, bool robust) {
  if (!robust) return Fit(LoadPhotometricSet(input).set, method);
  LoadOptions raw;
  raw.apply_intensities = false;
  LoadedSet loaded = LoadPhotometricSet(input, raw);
  const std::vector<Mask> measured = MeasuredPixelMasks(loaded.set);
  loaded.set.ApplyIntensities();
  const Observations observations(loaded.set);
  std::vector<int> all(loaded.set.size());
  std::iota(all.begin(), all.end(), 0);
  RobustFitOptions options;
  options.measured = measured;
  const RobustFit fit(observations, loaded.set.lights(), all, options, loaded.set.source());
  return fit.Fit(method);
}

std::vector<fs::path> FitToFolder(const fs::path& input, const fs::path& out,
                                  std::span<const Method> methods, bool robust, int band_rows) {
  fs::create_directories(out);
  StreamedSet set = OpenStreamedSet(input);
  StreamedFitOptions options;
  options.band_rows = band_rows;
  options.robust = robust;
  std::vector<fs::path> paths;
  for (const Method& method : methods) paths.push_back(out / (method.Name() + ".exr"));
  const StreamedFitReport report = FitStreamed(set, methods, paths, options);
  EXPECT_EQ(report.band_rows, band_rows);
  return paths;
}

void ExpectStreamedEqualsInMemory(bool robust, double bound, bool masked = true) {
  const testing::TempDir dir;
  const fs::path input = WriteCapture(dir / "capture", masked);
  const std::vector<Method> methods = StreamedMethods();
  const auto banded = FitToFolder(input, dir / "bands3", methods, robust, 3);
  const auto whole = FitToFolder(input, dir / "whole", methods, robust, 40);
  const auto again = FitToFolder(input, dir / "again", methods, robust, 3);
  for (std::size_t i = 0; i < methods.size(); ++i) {
    const Representation memory = FitInMemory(input, methods[i], robust);
    const LoadedStack streamed = LoadRepresentation(banded[i]);
    const LoadedStack one_band = LoadRepresentation(whole[i]);
    EXPECT_EQ(streamed.representation.method(), memory.method());
    EXPECT_EQ(streamed.representation.maps().channel_names(), memory.maps().channel_names());
    const double to_memory =
        testing::LargestDifferenceOverLargestValue(streamed.representation.maps(), memory.maps());
    const double to_one_band = testing::LargestDifferenceOverLargestValue(
        streamed.representation.maps(), one_band.representation.maps());
    std::printf("%s%s: bands of 3 rows vs in memory %.3g, vs one band %.3g\n",
                robust ? "robust " : "", methods[i].Name().c_str(), to_memory, to_one_band);
    EXPECT_LE(to_memory, bound) << methods[i].Name();
    EXPECT_LE(to_one_band, bound) << methods[i].Name();
    // Outside the mask (the first 7 rows hold none of it) every map is 0.
    for (int c = 0; masked && c < streamed.representation.maps().channels(); ++c) {
      for (int y = 0; y < 7; ++y) {
        for (float v : streamed.representation.maps().row(c, y)) ASSERT_EQ(v, 0.0f);
      }
    }
    // The same bits run after run.
    EXPECT_TRUE(testing::SameBits(streamed.representation.maps(),
                                  LoadRepresentation(again[i]).representation.maps()))
        << methods[i].Name();
  }
}

// Float rounding at most (the guarantee): products of more than 16 columns are Eigen's,
// whose kernels block rows differently for different row counts; the Gram matrix of Eigen-k, rbf
// and bilinear is RowGram's on both paths. Measured (largest difference over the largest value)
// 2026-12-05: 0 for every method, least squares and robust, since every product here is
// ParallelProduct's few-column kernel (a row's bits do not depend on its block); before it, up to
// 3.03e-7 (ptm). Bound 1e-6 = 3.3x that.
TEST(StreamedFitTest, BandsOfThreeRowsEqualTheInMemoryFit) {
  ExpectStreamedEqualsInMemory(false, 1e-6);
}

// The same bound; measured 0 for every method here too.
TEST(StreamedFitTest, UnmaskedBandsOfThreeRowsEqualTheInMemoryFit) {
  ExpectStreamedEqualsInMemory(false, 1e-6, false);
  ExpectStreamedEqualsInMemory(true, 1e-6, false);
}

TEST(StreamedFitTest, RobustBandsOfThreeRowsEqualTheInMemoryFit) {
  ExpectStreamedEqualsInMemory(true, 1e-6);
}

// pbr streams as the other robust fits do (every pixel solved alone from the band's robust
// start), and the report and the stack hold the whole set's pbr summary: the bands' summed.
TEST(StreamedFitTest, PbrBandsSumToTheWholeSetsSummary) {
  const testing::TempDir dir;
  const fs::path input = WriteCapture(dir / "capture");
  const std::vector<Method> pbr = {Method::Parse("pbr")};
  StreamedSet set = OpenStreamedSet(input);
  StreamedFitOptions options;
  options.band_rows = 3;
  options.robust = true;
  const std::vector<fs::path> paths = {dir / "pbr.exr"};
  StreamedFitReport report;
  try {
    report = FitStreamed(set, pbr, paths, options);
  } catch (const Error& error) {
    // A build without Ceres (PHOTOMAT_WITH_CERES=OFF) has no pbr fit, and says so.
    if (std::string(error.what()).find("built without") != std::string::npos) {
      GTEST_SKIP() << error.what();
    }
    throw;
  }
  const Representation memory = FitInMemory(input, pbr[0], true);
  const PbrFitSummary whole = PbrFitSummary::FromJson(memory.details().at("pbr_summary"));
  ASSERT_TRUE(report.pbr_summary);
  const PbrFitSummary& banded = *report.pbr_summary;
  std::printf("pbr: %zu pixels, %zu lobe sampled; mean cost in bands %.9g, in memory %.9g\n",
              banded.pixels, banded.lobe_sampled, banded.total_cost / banded.pixels,
              whole.total_cost / whole.pixels);
  EXPECT_GT(whole.pixels, 0u);
  EXPECT_EQ(banded.pixels, whole.pixels);
  EXPECT_EQ(banded.lobe_sampled, whole.lobe_sampled);
  EXPECT_EQ(banded.lobe_unsampled, whole.lobe_unsampled);
  EXPECT_EQ(banded.regularised, whole.regularised);
  EXPECT_NEAR(banded.total_cost, whole.total_cost, 1e-9 * whole.total_cost);
  const Representation stored = LoadRepresentation(paths[0]).representation;
  EXPECT_LE(testing::LargestDifferenceOverLargestValue(stored.maps(), memory.maps()), 1e-6);
  // The stack carries the whole set's summaries, as the in-memory fit's details do.
  const PbrFitSummary kept = PbrFitSummary::FromJson(stored.details().at("pbr_summary"));
  EXPECT_EQ(kept.pixels, whole.pixels);
  EXPECT_EQ(kept.lobe_sampled, whole.lobe_sampled);
  EXPECT_EQ(kept.lobe_unsampled, whole.lobe_unsampled);
  EXPECT_EQ(kept.regularised, whole.regularised);
  EXPECT_NEAR(kept.total_cost, whole.total_cost, 1e-9 * whole.total_cost);
  const nlohmann::json& robust = stored.details().at("robust_summary");
  const nlohmann::json& robust_in_memory = memory.details().at("robust_summary");
  for (const char* count : {"observations", "not_measured", "attached_shadow", "down_weighted"}) {
    EXPECT_EQ(robust.at(count), robust_in_memory.at(count)) << count;
  }
  EXPECT_NEAR(robust.at("mean_weight").get<double>(),
              robust_in_memory.at("mean_weight").get<double>(), 1e-9);
}

// The streamed stack records how each image was decoded, as the in-memory load decides it
// (photomat fit passes StreamedSet::encodings() into the provenance).
TEST(StreamedFitTest, StackRecordsEachImagesEncodingAsTheInMemoryLoad) {
  const testing::TempDir dir;
  const fs::path input = WriteCapture(dir / "capture");
  const LoadedSet memory = LoadPhotometricSet(input);
  StreamedSet set = OpenStreamedSet(input);
  const std::vector<ImageEncodingRecord> streamed = set.encodings();
  ASSERT_EQ(streamed.size(), memory.encodings.size());
  ASSERT_EQ(streamed.size(), static_cast<std::size_t>(memory.set.size()));
  for (std::size_t i = 0; i < streamed.size(); ++i) {
    EXPECT_EQ(streamed[i].file, memory.encodings[i].file);
    EXPECT_EQ(streamed[i].encoding, memory.encodings[i].encoding);
    EXPECT_EQ(streamed[i].decided_by, memory.encodings[i].decided_by);
    EXPECT_EQ(streamed[i].evidence, memory.encodings[i].evidence);
  }
  // 16-bit PNGs written linear: OpenImageIO stores a gAMA chunk of 1.0, which decides.
  EXPECT_EQ(streamed.front().encoding, "linear");
  EXPECT_EQ(streamed.front().decided_by, "png-gama");
  fs::create_directories(dir / "out");
  StreamedFitOptions options;
  options.band_rows = 3;
  options.provenance = {set.lights(), "linear", input.string(), streamed};
  const std::vector<Method> methods = {Method::Parse("3i")};
  const std::vector<fs::path> paths = {dir / "out" / "3i.exr"};
  FitStreamed(set, methods, paths, options);
  const LoadedStack stack = LoadRepresentation(paths.front());
  ASSERT_EQ(stack.provenance.images.size(), streamed.size());
  for (std::size_t i = 0; i < streamed.size(); ++i) {
    EXPECT_EQ(stack.provenance.images[i].file, streamed[i].file);
    EXPECT_EQ(stack.provenance.images[i].encoding, streamed[i].encoding);
    EXPECT_EQ(stack.provenance.images[i].decided_by, streamed[i].decided_by);
  }
}

// No file is left behind, temporary or final, when a fault stops the fit.
void ExpectNoOutput(const fs::path& out) {
  for (const auto& entry : fs::directory_iterator(out)) {
    ADD_FAILURE() << "left behind: " << entry.path();
  }
}

TEST(StreamedFitTest, ImageOfAnotherSizeIsNamedBeforeAnythingIsWritten) {
  const testing::TempDir dir;
  const fs::path input = WriteCapture(dir / "capture");
  WriteImage(input / "img_005.png", Image(48, 39, 3), testing::Linear16Bit());
  try {
    OpenStreamedSet(input);
    FAIL() << "a set with one image of another size opened";
  } catch (const Error& error) {
    EXPECT_NE(std::string(error.what()).find("img_005.png is 48x39 but"), std::string::npos)
        << error.what();
  }
}

TEST(StreamedFitTest, ImageTruncatedMidwayFailsNamingItAndLeavesNoStack) {
  const testing::TempDir dir;
  const fs::path input = WriteCapture(dir / "capture");
  const fs::path victim = input / "img_020.png";
  fs::resize_file(victim, fs::file_size(victim) * 6 / 10);
  const fs::path out = dir / "out";
  fs::create_directories(out);
  StreamedSet set = OpenStreamedSet(input);  // the header is intact
  const std::vector<Method> methods = StreamedMethods();
  std::vector<fs::path> paths;
  for (const Method& method : methods) paths.push_back(out / (method.Name() + ".exr"));
  StreamedFitOptions options;
  options.band_rows = 2;
  try {
    FitStreamed(set, methods, paths, options);
    FAIL() << "a truncated image was fitted";
  } catch (const Error& error) {
    // The header was intact (the set opened): the damage shows only while bands are decoded.
    EXPECT_NE(std::string(error.what()).find("img_020.png"), std::string::npos) << error.what();
  }
  ExpectNoOutput(out);
}

TEST(StreamedFitTest, BandRowsFollowTheBudget) {
  const testing::TempDir dir;
  const fs::path input = WriteCapture(dir / "capture");
  const StreamedSet set = OpenStreamedSet(input);
  const std::vector<Method> methods = StreamedMethods();
  EXPECT_EQ(StreamedBandRows(1, set, methods, false), 1);
  EXPECT_EQ(StreamedBandRows(std::size_t{1} << 30, set, methods, true), 40);
  // Least squares decodes straight into the image data matrix: two bands of 36 images x 3
  // channels x 4 bytes + 9 x 3 maps (hsh9, rbf, bilinear: the largest) x 12 bytes = 1188 bytes
  // per pixel, 57024 per row of 48, after the decoders' 36 x 16 x 48 x 4 x 4 = 442368 bytes;
  // masked, each decoding thread's scratch band adds 3 x 4 bytes per pixel and thread.
  const std::size_t masked_row =
      57024 + 48 * 12 * static_cast<std::size_t>(tbb::this_task_arena::max_concurrency());
  EXPECT_EQ(StreamedBandRows(442368 + 5 * masked_row + 100, set, methods, false), 5);
  EXPECT_EQ(StreamedBandRows(442368 + 5 * masked_row - 100, set, methods, false), 4);
  const StreamedSet unmasked = OpenStreamedSet(WriteCapture(dir / "unmasked", false));
  EXPECT_EQ(StreamedBandRows(442368 + 5 * 57024 + 100, unmasked, methods, false), 5);
  EXPECT_EQ(StreamedBandRows(442368 + 5 * 57024 - 100, unmasked, methods, false), 4);
  // Robust fits decode into band images and copy (8 bytes per sample, 2052 per pixel, 98496
  // per row) and keep weights and masks: fewer rows than least squares.
  EXPECT_LT(StreamedBandRows(442368 + 5 * 98496 + 100, unmasked, methods, true),
            StreamedBandRows(442368 + 5 * 98496 + 100, unmasked, methods, false));
  if (!AddressSpaceRoom() && !CgroupMemoryLimit()) {
    EXPECT_GE(DefaultFitMemory(), std::size_t{256} << 20);
  }
  EXPECT_GE(DefaultFitMemory(), kMinimumFitMemory);
}

// In a child (the limit stays with the process that sets it): sets an address-space limit 1 GiB
// above what is mapped now and exits 0 if the default budget is at most half of what that
// leaves once the worker threads' stacks and arenas are set aside (AddressSpaceRoom itself:
// core/memory_limits_test.cc).
void ExitWithBudgetUnderAddressSpaceLimit() {
  const std::size_t used = MappedAddressSpace().value_or(0);
  const std::size_t given = std::size_t{1} << 30;
  const rlimit limit{used + given, used + given};
  setrlimit(RLIMIT_AS, &limit);
  const std::size_t threads = WorkerThreadsAddressSpace();
  const std::size_t budget = DefaultFitMemory();
  // Half of the room given, less the threads' share. DefaultFitMemory reads the mapped space
  // again: pages mapped since lower its budget (by up to 10 MB here), and pages unmapped since
  // (freed blocks given back to the system) raise it. The clean-root CI measured one page above
  // (478154752 against 478150656), so up to 1 MiB above counts as half too.
  const std::size_t expected = (given - threads) / 2;
  constexpr std::size_t kUnmappedSince = std::size_t{1} << 20;
  // A cgroup limit (a container's) below twice that would set the budget instead.
  const bool cgroup_binds = CgroupMemoryLimit() && *CgroupMemoryLimit() / 2 < expected;
  const bool half = threads < given && budget <= expected + kUnmappedSince &&
                    (cgroup_binds || budget + (std::size_t{10} << 20) >= expected);
  if (!half) {
    std::fprintf(stderr, "default budget %zu of %zu given, %zu for the threads\n", budget, given,
                 threads);
  }
  std::exit(half ? 0 : 1);
}

TEST(StreamedFitTest, DefaultBudgetIsHalfTheAddressSpaceLeftUnderALimit) {
  // A fresh process (re-executed): this one's threads would be gone in a forked copy.
  GTEST_FLAG_SET(death_test_style, "threadsafe");
  EXPECT_EXIT(ExitWithBudgetUnderAddressSpaceLimit(), ::testing::ExitedWithCode(0), "");
}

}  // namespace
}  // namespace photomat
