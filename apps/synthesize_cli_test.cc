// End-to-end tests of `photomat synthesize`, `evaluate --synthesised` and the demo's synthesis
// step: each runs the built executable.
#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include <set>
#include <vector>

#include "capture/io/load_photometric_set.h"
#include "core/image_io.h"
#include "core/json_file.h"
#include "represent/stack/map_stack.h"
#include "synthesize/texture/source_map.h"
#include "tests/support/test_support.h"

namespace photomat {
namespace {

using testing::RunPhotomat;
using testing::RunResult;

using ::testing::HasSubstr;
using testing::TempDir;

// A fitted 40 x 40 capture: DIR/stacks holds gradient and ptm.
void MakeStacks(const TempDir& dir) {
  const std::string capture = (dir / "capture").string();
  testing::GenerateCapture(capture, "--size 40x40 --pattern bumps");
  const RunResult fit =
      RunPhotomat("fit " + capture + " --method gradient,ptm --out " + (dir / "stacks").string());
  ASSERT_EQ(fit.exit_code, 0) << fit.output;
}

TEST(SynthesizeCliTest, GrowsAStackAndReappliesItsSourceMapToAnother) {
  TempDir dir;
  MakeStacks(dir);
  const std::string stacks = (dir / "stacks").string();
  const RunResult ptm = RunPhotomat("synthesize " + stacks + " --stack ptm --size 64x56 --seed 3 " +
                                    "--save-source-map " + (dir / "map.exr").string() + " --out " +
                                    (dir / "ptm.exr").string());
  ASSERT_EQ(ptm.exit_code, 0) << ptm.output;
  const LoadedStack grown = LoadRepresentation(dir / "ptm.exr");
  EXPECT_EQ(grown.representation.method(), "ptm");
  EXPECT_EQ(grown.representation.width(), 64);
  EXPECT_EQ(grown.representation.height(), 56);
  EXPECT_EQ(grown.representation.details()["synthesis"]["seed"], 3);

  // The same placement on the gradient stack, projected onto an integrable field.
  const RunResult gradient =
      RunPhotomat("synthesize " + stacks + " --stack gradient --size 64x56 --source-map " +
                  (dir / "map.exr").string() + " --integrable --height " +
                  (dir / "height.exr").string() + " --out " + (dir / "gradient.exr").string());
  ASSERT_EQ(gradient.exit_code, 0) << gradient.output;
  const SourceMap map = LoadSourceMap(dir / "map.exr");
  const Image sample = LoadRepresentation(dir / "stacks" / "gradient.exr").representation.maps();
  const LoadedStack grown_gradient = LoadRepresentation(dir / "gradient.exr");
  const Image& maps = grown_gradient.representation.maps();
  for (int y = 0; y < 56; ++y) {
    for (int x = 0; x < 64; ++x) {
      const SamplePixel from = map.at(x, y);
      for (int c = 3; c < 6; ++c) {  // albedo copied from the mapped pixel
        ASSERT_EQ(maps.at(x, y, c), sample.at(from.x, from.y, c)) << x << "," << y;
      }
    }
  }
  EXPECT_EQ(grown_gradient.representation.details()["integrable_projection"], true);
  EXPECT_EQ(ReadImage(dir / "height.exr").image.width(), 64);

  const RunResult relit = RunPhotomat("relight " + (dir / "ptm.exr").string() +
                                      " --light 60,120 --out " + (dir / "relit.png").string());
  ASSERT_EQ(relit.exit_code, 0) << relit.output;
  EXPECT_EQ(ReadImage(dir / "relit.png").image.width(), 64);

  const RunResult evaluate = RunPhotomat(
      "evaluate " + stacks + " --synthesised " + (dir / "ptm.exr").string() + " --source-map " +
      (dir / "map.exr").string() + " --json " + (dir / "quality.json").string());
  ASSERT_EQ(evaluate.exit_code, 0) << evaluate.output;
  EXPECT_THAT(evaluate.output, HasSubstr("nearest-patch distance"));
  const nlohmann::json quality = ReadJsonFile(dir / "quality.json");
  // Measured: nearest-patch distance 0.0311, seams 1.228 (1183 pairs). Blocks chosen at random
  // (--tolerance 1000) give 0.0713 and 3.29.
  EXPECT_GE(quality["nearest_patch_distance"].get<double>(), 0.0);
  EXPECT_LT(quality["nearest_patch_distance"].get<double>(), 0.047);  // 0.0311 * 1.5
  EXPECT_GT(quality["seams"]["pairs"].get<double>(), 0.0);
  EXPECT_LT(quality["seams"]["ratio"].get<double>(), 1.47);  // 1.228 * 1.2
}

TEST(SynthesizeCliTest, VarietyPresetTakesSmallerBlocksAndMoreCandidates) {
  TempDir dir;
  MakeStacks(dir);
  const std::string stacks = (dir / "stacks").string();
  auto quilt = [&](const std::string& flags) {
    const RunResult run = RunPhotomat("synthesize " + stacks + " --stack ptm --size 64x64 " +
                                      flags + " --out " + (dir / "out.exr").string());
    EXPECT_EQ(run.exit_code, 0) << run.output;
    return LoadRepresentation(dir / "out.exr").representation.details()["synthesis"]["quilt"];
  };
  const nlohmann::json defaults = quilt("");
  EXPECT_EQ(defaults["block"], 13);  // a third of the 40-pixel sample
  EXPECT_EQ(defaults["tolerance"], 0.0);
  EXPECT_EQ(defaults["error_floor"], 0.5);
  const nlohmann::json preset = quilt("--variety");
  EXPECT_EQ(preset["block"], 10);  // a quarter
  EXPECT_EQ(preset["tolerance"], 0.1);
  EXPECT_EQ(preset["error_floor"], 1.0);
  const nlohmann::json overridden = quilt("--variety --block 16 --tolerance 0.05");
  EXPECT_EQ(overridden["block"], 16);
  EXPECT_EQ(overridden["tolerance"], 0.05);
  EXPECT_EQ(overridden["error_floor"], 1.0);
}

TEST(SynthesizeCliTest, GrowsPlainImagesPixelByPixel) {
  TempDir dir;
  Image image(30, 24, std::vector<std::string>{"R", "G", "B"});
  for (int y = 0; y < 24; ++y) {
    for (int x = 0; x < 30; ++x) {
      image.at(x, y, 0) = static_cast<float>(x) / 29.0f;
      image.at(x, y, 1) = static_cast<float>((x * y) % 7) / 6.0f;
      image.at(x, y, 2) = static_cast<float>(y) / 23.0f;
    }
  }
  ImageWriteOptions png;
  png.sample_type = SampleType::kUint8;
  png.encoding = ColourSpace::kSrgb;
  WriteImage(dir / "in.png", image, png);
  const Image input = ReadImage(dir / "in.png").image;
  std::set<std::vector<float>> pixels;
  for (std::size_t i = 0; i < input.pixel_count(); ++i) {
    pixels.insert({input.pixel(i).begin(), input.pixel(i).end()});
  }
  for (const std::string method : {"quilt", "pixel"}) {
    const RunResult run = RunPhotomat("synthesize " + (dir / "in.png").string() +
                                      " --size 50x40 --tileable --block 8 --levels 1 --method " +
                                      method + " --out " + (dir / "out.png").string());
    ASSERT_EQ(run.exit_code, 0) << run.output;
    const Image out = ReadImage(dir / "out.png").image;
    ASSERT_EQ(out.width(), 50);
    ASSERT_EQ(out.height(), 40);
    for (std::size_t i = 0; i < out.pixel_count(); ++i) {
      ASSERT_TRUE(pixels.count({out.pixel(i).begin(), out.pixel(i).end()}))
          << method << ": output pixel " << i << " is no input pixel";
    }
  }
}

TEST(SynthesizeCliTest, ErrorsAreOneLineAndNonZero) {
  TempDir dir;
  MakeStacks(dir);
  const std::string stacks = (dir / "stacks").string();
  const RunResult size = RunPhotomat("synthesize " + stacks + " --stack ptm --size 0x10 --out " +
                                     (dir / "x.exr").string());
  EXPECT_EQ(size.exit_code, 1);
  EXPECT_THAT(size.output, HasSubstr("photomat: error: \"0x10\": expected a size"));
  const RunResult integrable =
      RunPhotomat("synthesize " + stacks + " --stack ptm --size 60x60 --integrable --out " +
                  (dir / "x.exr").string());
  EXPECT_EQ(integrable.exit_code, 1);
  EXPECT_THAT(integrable.output, HasSubstr("needs normal maps"));
  EXPECT_FALSE(std::filesystem::exists(dir / "x.exr")) << "nothing half-written";
  const RunResult block = RunPhotomat("synthesize " + stacks + " --stack ptm --size 60x60 " +
                                      "--block 41 --out " + (dir / "x.exr").string());
  EXPECT_EQ(block.exit_code, 1);
  EXPECT_THAT(block.output, HasSubstr("block size 41 does not fit in the 40x40 sample"));

  Image other(20, 20, 3);
  WriteImage(dir / "other.exr", other);
  const RunResult map = RunPhotomat(
      "synthesize " + (dir / "other.exr").string() + " --size 30x30 --save-source-map " +
      (dir / "map.exr").string() + " --out " + (dir / "o.exr").string());
  ASSERT_EQ(map.exit_code, 0) << map.output;
  const RunResult height =
      RunPhotomat("synthesize " + (dir / "other.exr").string() + " --size 30x30 --height " +
                  (dir / "h.exr").string() + " --out " + (dir / "o2.exr").string());
  EXPECT_EQ(height.exit_code, 1);
  EXPECT_THAT(height.output, HasSubstr("--height needs a map stack that gives normals"));
  const RunResult mismatch =
      RunPhotomat("synthesize " + stacks + " --stack ptm --size 30x30 " + "--source-map " +
                  (dir / "map.exr").string() + " --out " + (dir / "x.exr").string());
  EXPECT_EQ(mismatch.exit_code, 1);
  EXPECT_THAT(mismatch.output, HasSubstr((dir / "map.exr").string() +
                                         ": the source map was made for a 20x20 sample"));
  EXPECT_EQ(std::count(mismatch.output.begin(), mismatch.output.end(), '\n'), 1);
  EXPECT_EQ(RunPhotomat("synthesize --help").exit_code, 0);
}

TEST(SynthesizeCliTest, DemoGrowsEveryStackAndRelightsIt) {
  TempDir dir;
  const RunResult demo = RunPhotomat("demo --size 24 --sweep 2 --out " + dir.path().string());
  ASSERT_EQ(demo.exit_code, 0) << demo.output;
  EXPECT_THAT(demo.output, HasSubstr("+ synthesize: 6 stacks grown from 24x24 to 48x48"));
  for (const char* method : {"3i", "gradient", "ptm", "ptm-lrgb", "eigen3", "eigen6"}) {
    const LoadedStack grown =
        LoadRepresentation(dir / "synthesis" / (std::string(method) + ".exr"));
    EXPECT_EQ(grown.representation.width(), 48) << method;
    EXPECT_EQ(LoadPhotometricSet(dir / "synthesis" / "relit" / method).set.size(), 2) << method;
  }
}

}  // namespace
}  // namespace photomat
