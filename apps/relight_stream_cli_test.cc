// `photomat relight` and `photomat export` stream a stack (README, "Streamed relighting and
// export"): these run the built executable.
#include <fmt/format.h>
#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include <algorithm>
#include <cstdio>
#include <cstring>
#include <filesystem>
#include <string>
#include <vector>

#include "core/atomic_file.h"
#include "core/image_io.h"
#include "core/json_file.h"
#include "core/light_direction.h"
#include "represent/stack/map_stack.h"
#include "tests/support/test_support.h"

namespace photomat {
namespace {

namespace fs = std::filesystem;

using ::testing::HasSubstr;
using ::testing::Not;
using testing::RunPhotomat;
using testing::RunResult;
using testing::TempDir;

// A PTM stack of side x side pixels: the maps of a 64 x 64 fit repeated, written uncompressed
// (quick to write and read back). 1536 x 1536 x 18 float maps: 170 MB.
fs::path WriteLargePtmStack(const TempDir& dir, int side) {
  const std::string capture = (dir / "capture").string();
  testing::GenerateCapture(capture, "--size 64x64 --seed 3");
  EXPECT_EQ(
      RunPhotomat("fit " + capture + " --method ptm --out " + (dir / "small").string()).exit_code,
      0);
  const LoadedStack small = LoadRepresentation(dir / "small" / "ptm.exr");
  const Image& tile = small.representation.maps();
  Image maps(side, side, tile.channel_names());
  for (int c = 0; c < maps.channels(); ++c) {
    for (int y = 0; y < side; ++y) {
      const auto in = tile.row(c, y % 64);
      auto out = maps.row(c, y);
      for (int x = 0; x < side; ++x) out[x] = in[x % 64];
    }
  }
  const fs::path path = dir / "large.exr";
  SaveRepresentation(path, small.representation.WithMaps(std::move(maps)), small.provenance,
                     ExrCompression::kNone);
  return path;
}

// The address-space limit of the tests below: 900 MiB where the program starts in 453
// (testing::StartupAddressSpace), so 447 MiB of room beyond it, which the large stack read
// whole, its interleaved copy and the threads do not fit in.
std::size_t LimitBelowTheWholeStack() {
  return testing::StartupAddressSpace("relight") + (std::size_t{447} << 20);
}

// Under a hard address-space limit that the whole stack does not fit in beside the program (the
// stack's 170 MB as read and its interleaved copy, against the room LimitBelowTheWholeStack
// leaves), relighting streams in bands with the default budget (half the room the limit leaves,
// less the threads' stacks and arenas) and gives the in-memory relighting's values bit for bit; the
// in-memory export of the same stack, which loads it whole, runs out of memory under the limit.
TEST(RelightStreamCliTest, RelightUnderAnAddressSpaceLimitBelowTheWholeStackMatches) {
  const TempDir dir;
  const fs::path stack = WriteLargePtmStack(dir, 1536);
  const std::size_t limit = LimitBelowTheWholeStack();
  const RunResult relit = RunPhotomat(
      "relight " + stack.string() + " --light 45,30 --out " + (dir / "relit.exr").string(),
      {limit});
  ASSERT_EQ(relit.exit_code, 0) << relit.output;
  EXPECT_THAT(relit.output, HasSubstr("bands of"));
  std::printf("%s", relit.output.c_str());
  EXPECT_THAT(relit.output, ::testing::Not(HasSubstr("bands of 1536 rows")));
  const Image expected =
      LoadRepresentation(stack).representation.Relight(LightDirection::FromSlantTilt(45, 30));
  EXPECT_TRUE(testing::SameBits(ReadImage(dir / "relit.exr").image, expected));
  // The limit binds: the whole stack does not load under it.
  const RunResult whole = RunPhotomat(
      "export " + stack.string() + " --memory 100000 --no-gltf --out " + (dir / "whole").string(),
      {limit});
  EXPECT_NE(whole.exit_code, 0) << whole.output;
  EXPECT_THAT(whole.output, HasSubstr("out of memory"));
}

// `photomat evaluate INPUT --stack FIT` streams the set and the stack: the same eta of
// reconstruction as the in-memory evaluation of the same method, which refits.
TEST(RelightStreamCliTest, EvaluateAStackStreamedGivesTheInMemoryEta) {
  const TempDir dir;
  const std::string capture = (dir / "capture").string();
  testing::GenerateCapture(capture, "--size 48x40 --shadows --seed 4");
  ASSERT_EQ(
      RunPhotomat("fit " + capture + " --method ptm --out " + (dir / "fit").string()).exit_code, 0);
  const RunResult streamed =
      RunPhotomat("evaluate " + capture + " --stack " + (dir / "fit").string() +
                  " --memory 1 --json " + (dir / "streamed.json").string());
  ASSERT_EQ(streamed.exit_code, 0) << streamed.output;
  const RunResult whole =
      RunPhotomat("evaluate " + capture + " --methods ptm --no-prediction --json " +
                  (dir / "whole.json").string());
  ASSERT_EQ(whole.exit_code, 0) << whole.output;
  const double a = ReadJsonFile(dir / "streamed.json")["ptm"]["eta_reconstruction"].get<double>();
  const double b = ReadJsonFile(dir / "whole.json")["ptm"]["eta_reconstruction"].get<double>();
  EXPECT_GT(b, 0.0);
  EXPECT_NEAR(a, b, 1e-9 * b);
}

// Below the size threshold a viewer is made in memory, unless that would not fit the memory
// budget: a 512 x 512 PTM stack's viewer in memory takes about 57 MB (InMemoryViewerBytes: 18
// maps), so under --memory 30 it is tiled from the stack in bands (whose pyramid buffers need 19
// MB), and under --memory 1000 it is not.
TEST(RelightStreamCliTest, AViewerThatWouldNotFitTheBudgetInMemoryIsTiled) {
  const TempDir dir;
  const fs::path stack = WriteLargePtmStack(dir, 512);
  const RunResult small_budget = RunPhotomat("export " + stack.string() + " --viewer " +
                                             (dir / "tiled").string() + " --memory 30");
  ASSERT_EQ(small_budget.exit_code, 0) << small_budget.output;
  EXPECT_THAT(small_budget.output, HasSubstr("over the 30 MB budget: tiling it"));
  EXPECT_THAT(small_budget.output, HasSubstr("as deep-zoom tiles"));
  EXPECT_TRUE(
      ReadJsonFile(dir / "tiled" / "viewer.json")["methods"][0]["data"].contains("pyramid"));
  const RunResult large_budget = RunPhotomat("export " + stack.string() + " --viewer " +
                                             (dir / "whole").string() + " --memory 1000");
  ASSERT_EQ(large_budget.exit_code, 0) << large_budget.output;
  EXPECT_THAT(large_budget.output, Not(HasSubstr("deep-zoom")));
  EXPECT_FALSE(
      ReadJsonFile(dir / "whole" / "viewer.json")["methods"][0]["data"].contains("pyramid"));
}

// `export --viewer` of a stack the limit does not let load whole: the deep-zoom tiles are written
// from bands (README "Web viewer and evaluation report"), and the level-0 tiles hold the stack's
// maps bit for bit (tiles of 256 pixels with 1 of overlap, float32 RGBA layers).
TEST(RelightStreamCliTest, ViewerTilesUnderAnAddressSpaceLimitBelowTheWholeStackMatch) {
  const TempDir dir;
  const fs::path stack = WriteLargePtmStack(dir, 1536);
  const std::size_t limit = LimitBelowTheWholeStack();
  // The limit binds: the whole-texture viewer (--viewer-tiles never) loads the stack whole and
  // runs out of memory.
  const RunResult whole = RunPhotomat("export " + stack.string() + " --viewer " +
                                          (dir / "whole").string() + " --viewer-tiles never",
                                      {limit});
  EXPECT_NE(whole.exit_code, 0) << whole.output;
  EXPECT_THAT(whole.output, HasSubstr("bad_alloc"));
  EXPECT_FALSE(fs::exists(dir / "whole"));
  // By default (auto) the viewer is below the size threshold but would not fit the budget the
  // limit leaves: it is tiled by itself.
  const RunResult tiled =
      RunPhotomat("export " + stack.string() + " --viewer " + (dir / "viewer").string(), {limit});
  ASSERT_EQ(tiled.exit_code, 0) << tiled.output;
  EXPECT_THAT(tiled.output, HasSubstr("budget: tiling it"));
  EXPECT_THAT(tiled.output, HasSubstr("as deep-zoom tiles"));
  const nlohmann::json pyramid =
      ReadJsonFile(dir / "viewer" / "viewer.json")["methods"][0]["data"]["pyramid"];
  EXPECT_EQ(pyramid["levels"], 4);  // 1536, 768, 384, 192
  EXPECT_EQ(pyramid["tile_size"], 256);
  const Image maps = LoadRepresentation(stack).representation.maps();
  const int layers = (maps.channels() + 3) / 4;
  for (const auto& [column, row] : {std::pair{0, 0}, std::pair{2, 3}, std::pair{5, 5}}) {
    const std::string bytes = ReadTextFile(dir / "viewer" / pyramid["folder"].get<std::string>() /
                                           fmt::format("0/{}_{}.f32", column, row));
    const int x0 = std::max(column * 256 - 1, 0), y0 = std::max(row * 256 - 1, 0);
    const int width = std::min((column + 1) * 256 + 1, 1536) - x0;
    const int height = std::min((row + 1) * 256 + 1, 1536) - y0;
    ASSERT_EQ(bytes.size(), static_cast<std::size_t>(layers) * width * height * 16);
    std::size_t mismatches = 0;
    for (int map = 0; map < maps.channels(); ++map) {
      for (int y = 0; y < height; ++y) {
        for (int x = 0; x < width; ++x) {
          float value = 0.0f;
          std::memcpy(&value,
                      bytes.data() +
                          ((static_cast<std::size_t>(map / 4) * height + y) * width + x) * 16 +
                          4 * (map % 4),
                      4);  // the file is little-endian, as the hosts photomat builds on
          mismatches += value != maps.at(x0 + x, y0 + y, map);
        }
      }
    }
    EXPECT_EQ(mismatches, 0u) << column << "_" << row;
  }
}

}  // namespace
}  // namespace photomat
