// `photomat relight` and `photomat export` stream a stack (README, "Streamed relighting and
// export"): these run the built executable.
#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include <cstdio>
#include <filesystem>
#include <string>

#include "core/image_io.h"
#include "core/json_file.h"
#include "core/light_direction.h"
#include "represent/stack/map_stack.h"
#include "tests/support/test_support.h"

namespace photomat {
namespace {

namespace fs = std::filesystem;

using ::testing::HasSubstr;
using testing::RunPhotomat;
using testing::RunResult;
using testing::TempDir;

// A PTM stack of side x side pixels: the maps of a 64 x 64 fit repeated, written uncompressed
// (quick to write and read back). 1536 x 1536 x 18 float maps: 170 MB.
fs::path WriteLargePtmStack(const TempDir& dir, int side) {
  const std::string capture = (dir / "capture").string();
  EXPECT_EQ(RunPhotomat("generate --out " + capture + " --size 64x64 --seed 3").exit_code, 0);
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

// Under a hard address-space limit that the whole stack does not fit in beside the program (the
// stack's 170 MB as read and its interleaved copy, plus about 0.65 GB of libraries, against 900
// MB), relighting streams in bands with the default budget (half the room the limit leaves, less
// the threads' stacks and arenas) and gives the in-memory relighting's values bit for bit; the
// in-memory export of the same stack, which loads it whole, runs out of memory under the limit.
TEST(RelightStreamCliTest, RelightUnderAnAddressSpaceLimitBelowTheWholeStackMatches) {
  const TempDir dir;
  const fs::path stack = WriteLargePtmStack(dir, 1536);
  const std::size_t limit = std::size_t{900} << 20;
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
  ASSERT_EQ(RunPhotomat("generate --out " + capture + " --size 48x40 --shadows --seed 4").exit_code,
            0);
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

}  // namespace
}  // namespace photomat
