// End-to-end tests of `photomat rd` (runs the built binary).
#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include <cmath>
#include <string>

#include "core/image_io.h"
#include "represent/stack/map_stack.h"
#include "synthesize/mesh/mesh_io.h"
#include "tests/support/test_support.h"

namespace photomat {
namespace {

using ::testing::HasSubstr;

using testing::RunPhotomat;
using testing::RunResult;

TEST(RdCommandTest, GridWritesATileableRelightableMapStack) {
  testing::TempDir dir;
  const RunResult run = RunPhotomat("rd --grid 48x40 --model turk --steps 300 --tau 1 --out " +
                                    (dir / "grid").string());
  ASSERT_EQ(run.exit_code, 0) << run.output;
  EXPECT_THAT(run.output, HasSubstr("periodic grid"));
  const auto stack = LoadRepresentation(dir / "grid" / "rd.exr");
  EXPECT_EQ(stack.representation.method(), "gradient");
  EXPECT_EQ(stack.representation.width(), 48);
  EXPECT_EQ(stack.representation.height(), 40);
  EXPECT_EQ(ReadImage(dir / "grid" / "pattern.png").image.width(), 48);
  EXPECT_TRUE(std::filesystem::exists(dir / "grid" / "summary.json"));
  // The stack folder relights like a fitted one.
  const RunResult relit = RunPhotomat("relight " + (dir / "grid").string() +
                                      " --light 45,30 --out " + (dir / "relit.png").string());
  EXPECT_EQ(relit.exit_code, 0) << relit.output;
  EXPECT_TRUE(std::filesystem::exists(dir / "relit.png"));
}

TEST(RdCommandTest, MeshWritesColouredMeshesPreviewsAndFields) {
  testing::TempDir dir;
  const RunResult run =
      RunPhotomat("rd --mesh sphere:1:3 --size 40 --model fhn --steps 20 --preview-size 64 --out " +
                  (dir / "mesh").string());
  ASSERT_EQ(run.exit_code, 0) << run.output;
  EXPECT_THAT(run.output, HasSubstr("642 vertices"));
  EXPECT_EQ(ReadMesh(dir / "mesh" / "pattern.ply").vertex_count(), 642);
  EXPECT_EQ(ReadMesh(dir / "mesh" / "pattern.glb").vertex_count(), 642);
  EXPECT_TRUE(std::filesystem::exists(dir / "mesh" / "preview_front.png"));
  EXPECT_TRUE(std::filesystem::exists(dir / "mesh" / "fields.csv"));
  EXPECT_TRUE(std::filesystem::exists(dir / "mesh" / "history.csv"));
}

// --noise then --smooth-steps: the coupled loop smooths the sphere it grows the pattern on (the
// written mesh is rounder than the noisy one written without smoothing, same seed).
TEST(RdCommandTest, SmoothStepsDenoiseTheMeshTheyGrowOn) {
  testing::TempDir dir;
  const std::string common =
      "rd --mesh sphere:1:3 --size 40 --model turk --steps 10 --noise 0.2 "
      "--preview-size 32 --out ";
  const RunResult noisy = RunPhotomat(common + (dir / "noisy").string());
  ASSERT_EQ(noisy.exit_code, 0) << noisy.output;
  const RunResult smoothed =
      RunPhotomat(common + (dir / "smoothed").string() + " --smooth-steps 10");
  ASSERT_EQ(smoothed.exit_code, 0) << smoothed.output;
  auto radius_spread = [](const TriangleMesh& mesh) {
    Eigen::Vector3d centre = Eigen::Vector3d::Zero();
    for (const auto& p : mesh.positions) centre += p / mesh.vertex_count();
    double sum = 0.0, sum2 = 0.0;
    for (const auto& p : mesh.positions) {
      sum += (p - centre).norm();
      sum2 += (p - centre).squaredNorm();
    }
    const double n = mesh.vertex_count();
    return std::sqrt(sum2 / n - (sum / n) * (sum / n));
  };
  const double before = radius_spread(ReadMesh(dir / "noisy" / "pattern.ply"));
  const double after = radius_spread(ReadMesh(dir / "smoothed" / "pattern.ply"));
  EXPECT_LT(after, 0.5 * before) << before << " -> " << after;
}

TEST(RdCommandTest, BadArgumentsAreOneLineErrors) {
  testing::TempDir dir;
  const std::string out = " --out " + (dir / "x").string();
  const RunResult both = RunPhotomat("rd --mesh sphere --grid 8x8" + out);
  EXPECT_EQ(both.exit_code, 1);
  EXPECT_THAT(both.output, HasSubstr("exactly one of --mesh and --grid"));
  const RunResult model = RunPhotomat("rd --grid 8x8 --model schnakenberg" + out);
  EXPECT_EQ(model.exit_code, 1);
  EXPECT_THAT(model.output, HasSubstr("unknown model"));
  const RunResult missing = RunPhotomat("rd --mesh " + (dir / "none.obj").string() + out);
  EXPECT_EQ(missing.exit_code, 1);
  EXPECT_THAT(missing.output, HasSubstr("none.obj"));
  EXPECT_FALSE(std::filesystem::exists(dir / "x"));
}

}  // namespace
}  // namespace photomat
