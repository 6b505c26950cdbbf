#include "relight/formats/compact_stack.h"

#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>

#include "core/atomic_file.h"
#include "core/error.h"
#include "core/image_io.h"
#include "core/json_file.h"
#include "relight/formats/stack_file.h"
#include "represent/fitting/fit.h"
#include "tests/support/synthetic_sets.h"
#include "tests/support/test_support.h"

namespace photomat {
namespace {

namespace fs = std::filesystem;
using ::testing::HasSubstr;
using ::testing::ThrowsMessage;

// A linear fit of the shadowed, glossy synthetic sample with the outer ring of pixels masked
// out, so that the fit stores 0 there (the mask the compact form derives).
LoadedStack MaskedFit(const std::string& method) {
  PhotometricSet set = testing::ShadowedSpecularSet(40).set;
  Mask mask(set.width(), set.height(), true);
  for (int y = 0; y < set.height(); ++y) {
    for (int x = 0; x < set.width(); ++x) {
      if (x < 4 || y < 4 || x >= set.width() - 4 || y >= set.height() - 4) mask.Set(x, y, false);
    }
  }
  set.set_mask(mask);
  return {Fit(set, Method::Parse(method)), StackProvenance(set.lights(), "linear", "shadowed")};
}

std::vector<LightDirection> TestLights() {
  return {LightDirection::FromSlantTilt(0, 0), LightDirection::FromSlantTilt(30, 45),
          LightDirection::FromSlantTilt(50, 200), LightDirection::FromSlantTilt(65, 300)};
}

TEST(CompactStackTest, MaskIsWhereAnyMapIsNonzero) {
  const LoadedStack fit = MaskedFit("ptm");
  const Mask mask = NonzeroMapsMask(fit.representation.maps());
  EXPECT_FALSE(mask(0, 0));
  EXPECT_FALSE(mask(3, 20));
  EXPECT_TRUE(mask(4, 4));
  EXPECT_EQ(mask.CountSet(), 32u * 32u);
}

// Every decoded value is within half a step (scale / 2) of the stored float inside the mask
// (min-max range: nothing clipped), and exactly 0 outside.
TEST(CompactStackTest, QuantisationIsWithinHalfAStep) {
  for (const std::string method : {"ptm", "hsh9", "rbf", "bilinear"}) {
    const LoadedStack fit = MaskedFit(method);
    const Image& maps = fit.representation.maps();
    const Mask mask = NonzeroMapsMask(maps);
    const CompactPlanes planes = QuantiseMaps(maps, mask);
    const Image decoded = DequantiseMaps(planes);
    ASSERT_EQ(decoded.channel_names(), maps.channel_names());
    double worst_in_steps = 0;
    for (int c = 0; c < maps.channels(); ++c) {
      for (std::size_t p = 0; p < maps.pixel_count(); ++p) {
        const double error = std::abs(decoded.plane(c)[p] - maps.plane(c)[p]);
        if (!mask[p]) {
          ASSERT_EQ(decoded.plane(c)[p], 0.0f);
          continue;
        }
        worst_in_steps = std::max(worst_in_steps, error / planes.scale[c]);
      }
    }
    // Measured 0.49996-0.49999 steps (ptm, hsh9, rbf, bilinear); bound 0.5 plus 1e-3 steps for
    // the float rounding of the decoded value.
    EXPECT_LE(worst_in_steps, 0.501) << method;
    EXPECT_GE(worst_in_steps, 0.45) << method;  // the bound is tight: it is reached
  }
}

// With a range quantile, values beyond it are clipped to the range's ends; the rest stay within
// half a step.
TEST(CompactStackTest, RangeQuantileClipsTheTails) {
  const LoadedStack fit = MaskedFit("ptm");
  const Image& maps = fit.representation.maps();
  const Mask mask = NonzeroMapsMask(maps);
  const CompactPlanes full = QuantiseMaps(maps, mask, 1.0);
  const CompactPlanes clipped = QuantiseMaps(maps, mask, 0.99);
  const Image decoded = DequantiseMaps(clipped);
  for (int c = 0; c < maps.channels(); ++c) {
    EXPECT_LE(clipped.scale[c], full.scale[c] * (1 + 1e-9));
    const double low = clipped.bias[c], high = low + 255 * clipped.scale[c];
    for (std::size_t p : mask.SetIndices()) {
      const double v = std::clamp<double>(maps.plane(c)[p], low, high);
      EXPECT_LE(std::abs(decoded.plane(c)[p] - v), 0.501 * clipped.scale[c]);
    }
  }
  EXPECT_THROW(QuantiseMaps(maps, mask, 0.4), Error);
}

// The folder read back (PNG: lossless) is the dequantised stack exactly, method, basis and
// provenance included, and relights identically.
TEST(CompactStackTest, PngFolderReadsAsTheDequantisedStack) {
  for (const std::string method : {"ptm", "rbf"}) {
    const LoadedStack fit = MaskedFit(method);
    testing::TempDir dir;
    const fs::path folder = dir / "compact";
    CompactStackOptions maps_only;
    maps_only.pca_planes = 0;
    WriteCompactStack(folder, fit, maps_only);
    ASSERT_TRUE(IsCompactStackFolder(folder));
    ASSERT_TRUE(IsStackInput(folder));
    ASSERT_TRUE(IsReadWholeStackInput(folder));
    const LoadedStack read = LoadStackFile(folder);
    const Representation& r = read.representation;
    EXPECT_EQ(r.method(), method);
    EXPECT_EQ(read.provenance.capture_lights.size(), fit.provenance.capture_lights.size());
    EXPECT_EQ(read.provenance.colour_space, "linear");
    const Image dequantised = DequantiseMaps(
        QuantiseMaps(fit.representation.maps(), NonzeroMapsMask(fit.representation.maps())));
    EXPECT_TRUE(testing::SameBits(r.maps(), dequantised)) << method;
    const Representation expected = fit.representation.WithMaps(dequantised);
    for (const LightDirection& light : TestLights()) {
      EXPECT_TRUE(testing::SameBits(r.Relight(light), expected.Relight(light))) << method;
    }
    EXPECT_THROW(LoadStackFile(folder, std::string("hsh9")), Error);
  }
}

// JPEG planes at quality 100: within a few steps of the PNG's bytes.
TEST(CompactStackTest, JpegPlanesStayCloseToTheBytes) {
  const LoadedStack fit = MaskedFit("ptm");
  testing::TempDir dir;
  CompactStackOptions options;
  options.coding = CompactPlaneCoding::kJpeg;
  options.jpeg_quality = 100;
  options.pca_planes = 0;
  WriteCompactStack(dir / "jpeg", fit, options);
  const Image jpeg = ReadCompactStack(dir / "jpeg").representation.maps();
  const CompactPlanes planes =
      QuantiseMaps(fit.representation.maps(), NonzeroMapsMask(fit.representation.maps()));
  const Image png = DequantiseMaps(planes);
  double worst_in_steps = 0;
  for (int c = 0; c < png.channels(); ++c) {
    for (std::size_t p : planes.mask.SetIndices()) {
      worst_in_steps =
          std::max(worst_in_steps, std::abs(jpeg.plane(c)[p] - png.plane(c)[p]) / planes.scale[c]);
    }
  }
  // Measured 1.0 step (JPEG's DCT rounding at quality 100); bound 2x that.
  EXPECT_LE(worst_in_steps, 2.0);
}

// PCA planes: at full rank the maps decode within the quantisation of the components, carried
// back through the axes and weights, |B_j - decoded_j| <= sum_c |V_jc| scale_c / 2 / w_j; fewer
// planes keep only the largest components.
TEST(CompactStackTest, PcaPlanesDecodeWithinTheirQuantisation) {
  const LoadedStack fit = MaskedFit("hsh9");
  const Image& maps = fit.representation.maps();
  const Mask mask = NonzeroMapsMask(maps);
  const CompactPca pca = FitMapPca(maps, mask, MapWeights(fit), -1);
  ASSERT_EQ(pca.axes.cols(), maps.channels());
  // Full rank, unquantised: the rotation is undone to float precision.
  const Image exact = ReconstructMaps(ProjectMaps(maps, mask, pca), mask, pca);
  EXPECT_LE(testing::LargestDifferenceOverLargestValue(exact, maps), 1e-5);
  testing::TempDir dir;
  CompactStackOptions options;
  options.pca_planes = -1;
  WriteCompactStack(dir / "pca", fit, options);
  const Image decoded = ReadCompactStack(dir / "pca").representation.maps();
  const nlohmann::json manifest = ReadJsonFile(dir / "pca" / kCompactStackManifest);
  std::vector<double> scale;
  for (const auto& plane : manifest["planes"]) scale.push_back(plane["scale"].get<double>());
  double worst_over_bound = 0;
  for (int j = 0; j < maps.channels(); ++j) {
    double bound = 0;
    for (int c = 0; c < pca.axes.cols(); ++c) bound += std::abs(pca.axes(j, c)) * scale[c] / 2;
    bound /= pca.weights[j];
    for (std::size_t p : mask.SetIndices()) {
      worst_over_bound =
          std::max(worst_over_bound, std::abs(decoded.plane(j)[p] - maps.plane(j)[p]) / bound);
    }
  }
  // Measured 0.90 of the bound (the components' errors partly cancel); bound plus 1e-3 for float
  // rounding.
  EXPECT_LE(worst_over_bound, 1.001);
  // And the folder relights exactly as the stack of the components' dequantised planes,
  // reconstructed, does (PNG: lossless).
  const Image expected_maps =
      ReconstructMaps(DequantiseMaps(QuantiseMaps(ProjectMaps(maps, mask, pca), mask)), mask, pca);
  const Representation expected = fit.representation.WithMaps(expected_maps);
  const Representation read = ReadCompactStack(dir / "pca").representation;
  for (const LightDirection& light : TestLights()) {
    EXPECT_TRUE(testing::SameBits(read.Relight(light), expected.Relight(light)));
  }
  // Damaged components: axes for other maps than the planes and channels.
  nlohmann::json damaged = manifest;
  damaged["pca"]["axes"].erase(damaged["pca"]["axes"].size() - 1);
  testing::WriteFile(dir / "pca" / kCompactStackManifest, damaged.dump());
  EXPECT_THAT([&] { ReadCompactStack(dir / "pca"); },
              ThrowsMessage<Error>(AllOf(HasSubstr(kCompactStackManifest), HasSubstr("axes"))));
  options.pca_planes = 6;
  WriteCompactStack(dir / "six", fit, options);
  EXPECT_TRUE(fs::exists(dir / "six" / "map_005.png"));
  EXPECT_FALSE(fs::exists(dir / "six" / "map_006.png"));
  EXPECT_EQ(ReadCompactStack(dir / "six").representation.maps().channels(), maps.channels());
}

TEST(CompactStackTest, RejectsMalformedFolders) {
  const LoadedStack fit = MaskedFit("ptm");
  testing::TempDir dir;
  const fs::path folder = dir / "compact";
  CompactStackOptions maps_only;
  maps_only.pca_planes = 0;
  WriteCompactStack(folder, fit, maps_only);
  const fs::path manifest = folder / kCompactStackManifest;
  const std::string good = ReadTextFile(manifest);
  // A missing plane.
  fs::rename(folder / "map_003.png", dir / "aside.png");
  EXPECT_THAT([&] { ReadCompactStack(folder); }, ThrowsMessage<Error>(HasSubstr("map_003.png")));
  // A plane of the wrong size.
  Image small(8, 8, 1);
  ImageWriteOptions bytes;
  bytes.sample_type = SampleType::kUint8;
  WriteImage(folder / "map_003.png", small, bytes);
  EXPECT_THAT([&] { ReadCompactStack(folder); },
              ThrowsMessage<Error>(AllOf(HasSubstr("map_003.png"), HasSubstr("8x8"))));
  fs::rename(dir / "aside.png", folder / "map_003.png");
  EXPECT_NO_THROW(ReadCompactStack(folder));
  // A bad manifest: not JSON, another format, a plane without its scale, a map the description
  // needs but no plane holds.
  testing::WriteFile(manifest, "{ not json");
  EXPECT_THAT([&] { ReadCompactStack(folder); },
              ThrowsMessage<Error>(HasSubstr(kCompactStackManifest)));
  nlohmann::json json = nlohmann::json::parse(good);
  json["format"] = "something-else";
  testing::WriteFile(manifest, json.dump());
  EXPECT_THAT([&] { ReadCompactStack(folder); },
              ThrowsMessage<Error>(HasSubstr("photomat-compact-stack")));
  json = nlohmann::json::parse(good);
  json["planes"][2].erase("scale");
  testing::WriteFile(manifest, json.dump());
  EXPECT_THAT([&] { ReadCompactStack(folder); }, ThrowsMessage<Error>(HasSubstr("scale")));
  json = nlohmann::json::parse(good);
  json["planes"].erase(json["planes"].size() - 1);
  testing::WriteFile(manifest, json.dump());
  EXPECT_THAT([&] { ReadCompactStack(folder); },
              ThrowsMessage<Error>(AllOf(HasSubstr(kCompactStackManifest), HasSubstr("ptm."))));
  json = nlohmann::json::parse(good);
  json["mask"] = "../elsewhere.png";
  testing::WriteFile(manifest, json.dump());
  EXPECT_THAT([&] { ReadCompactStack(folder); },
              ThrowsMessage<Error>(HasSubstr("not a file name in the folder")));
  // A missing mask.
  testing::WriteFile(manifest, good);
  fs::remove(folder / "mask.png");
  EXPECT_THAT([&] { ReadCompactStack(folder); }, ThrowsMessage<Error>(HasSubstr("mask.png")));
}

// The manifest holds no absolute local path: an absolute source is stored relative to the folder.
TEST(CompactStackTest, SourceIsRelativeToTheFolder) {
  LoadedStack fit = MaskedFit("ptm");
  testing::TempDir dir;
  fit.provenance.source = (dir / "captures" / "cat").string();
  WriteCompactStack(dir / "out" / "compact", fit);
  EXPECT_EQ(ReadCompactStack(dir / "out" / "compact").provenance.source, "../../captures/cat");
}

// Written whole or not at all: an unrelated folder is never replaced.
TEST(CompactStackTest, DoesNotReplaceUnrelatedFolders) {
  const LoadedStack fit = MaskedFit("ptm");
  testing::TempDir dir;
  testing::WriteFile(dir / "notes" / "keep.txt", "mine");
  EXPECT_THROW(WriteCompactStack(dir / "notes", fit), Error);
  EXPECT_TRUE(fs::exists(dir / "notes" / "keep.txt"));
  // Another compact stack is replaced.
  WriteCompactStack(dir / "compact", fit);
  EXPECT_NO_THROW(WriteCompactStack(dir / "compact", MaskedFit("hsh9")));
  EXPECT_EQ(ReadCompactStack(dir / "compact").representation.method(), "hsh9");
}

}  // namespace
}  // namespace photomat
