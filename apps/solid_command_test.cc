// End-to-end tests of `photomat solid`: each runs the built executable.
#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include <algorithm>

#include "core/atomic_file.h"
#include "core/image_io.h"
#include "core/json_file.h"
#include "synthesize/volume/volume_io.h"
#include "synthesize/volume/voxel_hash.h"
#include "tests/support/test_support.h"

namespace photomat {
namespace {

using ::testing::HasSubstr;
using testing::RunPhotomat;
using testing::RunResult;
using testing::SameBits;
using testing::TempDir;

TEST(SolidCommandTest, ExemplarThenGrowWithAFieldAndACache) {
  TempDir dir;
  const std::string exemplar = (dir / "cells.vdb").string();
  const RunResult made = RunPhotomat("solid exemplar --pattern cells --size 12 --out " + exemplar);
  ASSERT_EQ(made.exit_code, 0) << made.output;
  EXPECT_EQ(ReadVolume(exemplar).extent(), ImageExtent::Cube(12));

  const std::string grow = "solid grow " + exemplar + " --size 16 --field circular --cache " +
                           (dir / "cache").string() + " --report " + (dir / "r.json").string() +
                           " --slices " + (dir / "slices").string();
  const RunResult first = RunPhotomat(grow + " --threads 1 --out " + (dir / "a.vdb").string());
  ASSERT_EQ(first.exit_code, 0) << first.output;
  EXPECT_THAT(first.output, HasSubstr("similarity set built"));
  const RunResult second = RunPhotomat(grow + " --threads 2 --out " + (dir / "b.vdb").string());
  ASSERT_EQ(second.exit_code, 0) << second.output;
  EXPECT_THAT(second.output, HasSubstr("read from"));
  const Image a = ReadVolume(dir / "a.vdb");
  EXPECT_EQ(a.extent(), ImageExtent::Cube(16));
  EXPECT_TRUE(SameBits(a, ReadVolume(dir / "b.vdb")));
  EXPECT_TRUE(std::filesystem::exists(dir / "slices" / "xz.png"));
  const nlohmann::json report = ReadJsonFile(dir / "r.json");
  EXPECT_TRUE(report["similarity_from_cache"].get<bool>());
  EXPECT_GT(report["passes"].size(), 0u);
  // The grown solid's statistics against the exemplar's (the same on 1 and 2 threads). Measured:
  // histogram 0.0126, earth mover 0.00145, spectrum 2.92 dB; jitter only (--passes 0) gives 0.140,
  // 0.0135, 3.60 dB, and without histogram matching 0.220, 0.0458, 2.61 dB.
  EXPECT_GE(report["histogram_distance"].get<double>(), 0.0);
  EXPECT_LT(report["histogram_distance"].get<double>(), 0.019);  // 0.0126 * 1.5
  EXPECT_GE(report["earth_mover_distance"].get<double>(), 0.0);
  EXPECT_LT(report["earth_mover_distance"].get<double>(), 0.0022);  // 0.00145 * 1.5
  EXPECT_GE(report["spectrum_distance_db"].get<double>(), 0.0);
  EXPECT_LT(report["spectrum_distance_db"].get<double>(), 3.5);  // 2.92 * 1.2
}

TEST(SolidCommandTest, GrowsAProceduralExemplarIntoASliceStack) {
  TempDir dir;
  const RunResult run = RunPhotomat(
      "solid grow procedural:marble --exemplar-size 12 --size 8x12x16 "
      "--no-cache --field slant --angle 20 --out " +
      (dir / "stack").string() + " --coordinates " + (dir / "coords.vdb").string());
  ASSERT_EQ(run.exit_code, 0) << run.output;
  EXPECT_EQ(ReadVolume(dir / "stack").extent(), (ImageExtent{8, 12, 16}));
  EXPECT_EQ(ReadVolume(dir / "coords.vdb").channels(), 3);
}

TEST(SolidCommandTest, FromViews) {
  TempDir dir;
  Image view(32, 32, 3);
  for (std::size_t i = 0; i < view.values().size(); ++i) {
    view.values()[i] =
        0.5f + 0.4f * HashToSigned(HashVoxel(1, 0, static_cast<std::int64_t>(i / 3 / 4), 0, 0));
  }
  WriteImage(dir / "view.png", view,
             {.sample_type = SampleType::kUint8, .encoding = ColourSpace::kSrgb, .attributes = {}});
  const RunResult run =
      RunPhotomat("solid from-views --view " + (dir / "view.png").string() +
                  " --size 16 --iterations 2 --out " + (dir / "solid.vdb").string() + " --report " +
                  (dir / "report.json").string());
  ASSERT_EQ(run.exit_code, 0) << run.output;
  EXPECT_THAT(run.output, HasSubstr("iteration 2"));
  EXPECT_EQ(ReadVolume(dir / "solid.vdb").extent(), ImageExtent::Cube(16));
  EXPECT_EQ(ReadJsonFile(dir / "report.json")["iterations"].size(), 2u);
}

TEST(SolidCommandTest, BadInputIsOneErrorLine) {
  TempDir dir;
  const RunResult missing = RunPhotomat("solid from-views --xy " + (dir / "none.png").string() +
                                        " --out " + (dir / "x.vdb").string());
  EXPECT_EQ(missing.exit_code, 1);
  EXPECT_THAT(missing.output, HasSubstr("none.png"));
  const RunResult field = RunPhotomat(
      "solid grow procedural:noise --exemplar-size 8 --size 8 "
      "--no-cache --field spiral --out " +
      (dir / "x.vdb").string());
  EXPECT_EQ(field.exit_code, 1);
  EXPECT_THAT(field.output, HasSubstr("spiral"));
  const RunResult pattern =
      RunPhotomat("solid grow procedural:plaid --out " + (dir / "x.vdb").string());
  EXPECT_EQ(pattern.exit_code, 1);
  EXPECT_THAT(pattern.output, HasSubstr("plaid"));
  EXPECT_FALSE(std::filesystem::exists(dir / "x.vdb"));
}

}  // namespace
}  // namespace photomat
