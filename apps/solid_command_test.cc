// End-to-end tests of `photomat solid`: each runs the built executable.
#include <fmt/format.h>
#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include <algorithm>
#include <cstring>

#include "core/atomic_file.h"
#include "core/image_io.h"
#include "core/json_file.h"
#include "synthesize/mesh/mesh_io.h"
#include "synthesize/volume/volume_io.h"
#include "synthesize/volume/voxel_hash.h"
#include "tests/support/test_support.h"

namespace photomat {
namespace {

using ::testing::HasSubstr;
using testing::RunPhotomat;
using testing::RunResult;
using testing::TempDir;

bool SameBytes(const Volume& a, const Volume& b) {
  return a.SameShape(b) &&
         std::memcmp(a.values().data(), b.values().data(), a.values().size_bytes()) == 0;
}

TEST(SolidCommandTest, ExemplarThenGrowWithAFieldAndACache) {
  TempDir dir;
  const std::string exemplar = (dir / "cells.vdb").string();
  const RunResult made = RunPhotomat("solid exemplar --pattern cells --size 12 --out " + exemplar);
  ASSERT_EQ(made.exit_code, 0) << made.output;
  EXPECT_EQ(ReadVolume(exemplar).size(), VolumeSize::Cube(12));

  const std::string grow = "solid grow " + exemplar + " --size 16 --field circular --cache " +
                           (dir / "cache").string() + " --report " + (dir / "r.json").string() +
                           " --slices " + (dir / "slices").string();
  const RunResult first = RunPhotomat(grow + " --threads 1 --out " + (dir / "a.vdb").string());
  ASSERT_EQ(first.exit_code, 0) << first.output;
  EXPECT_THAT(first.output, HasSubstr("similarity set built"));
  const RunResult second = RunPhotomat(grow + " --threads 2 --out " + (dir / "b.vdb").string());
  ASSERT_EQ(second.exit_code, 0) << second.output;
  EXPECT_THAT(second.output, HasSubstr("read from"));
  const Volume a = ReadVolume(dir / "a.vdb");
  EXPECT_EQ(a.size(), VolumeSize::Cube(16));
  EXPECT_TRUE(SameBytes(a, ReadVolume(dir / "b.vdb")));
  EXPECT_TRUE(std::filesystem::exists(dir / "slices" / "xz.png"));
  const nlohmann::json report = ReadJsonFile(dir / "r.json");
  EXPECT_TRUE(report["similarity_from_cache"].get<bool>());
  EXPECT_GT(report["passes"].size(), 0u);
  EXPECT_GE(report["histogram_distance"].get<double>(), 0.0);
  EXPECT_LE(report["histogram_distance"].get<double>(), 2.0);  // L1 of two distributions
  EXPECT_GE(report["earth_mover_distance"].get<double>(), 0.0);
  EXPECT_LE(report["earth_mover_distance"].get<double>(), 1.0);  // in units of the range
  EXPECT_GE(report["spectrum_distance_db"].get<double>(), 0.0);
}

TEST(SolidCommandTest, GrowsAProceduralExemplarIntoASliceStack) {
  TempDir dir;
  const RunResult run = RunPhotomat(
      "solid grow procedural:marble --exemplar-size 12 --size 8x12x16 "
      "--no-cache --field slant --angle 20 --out " +
      (dir / "stack").string() + " --coordinates " + (dir / "coords.vdb").string());
  ASSERT_EQ(run.exit_code, 0) << run.output;
  EXPECT_EQ(ReadVolume(dir / "stack").size(), (VolumeSize{8, 12, 16}));
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
  EXPECT_EQ(ReadVolume(dir / "solid.vdb").size(), VolumeSize::Cube(16));
  EXPECT_EQ(ReadJsonFile(dir / "report.json")["iterations"].size(), 2u);
}

// A regular octahedron of circumradius 1 as OBJ text.
constexpr const char* kOctahedron =
    "v 1 0 0\nv -1 0 0\nv 0 1 0\nv 0 -1 0\nv 0 0 1\nv 0 0 -1\n"
    "f 1 3 5\nf 3 2 5\nf 2 4 5\nf 4 1 5\nf 3 1 6\nf 2 3 6\nf 4 2 6\nf 1 4 6\n";

TEST(SolidCommandTest, CarvesAMeshOutOfASolid) {
  TempDir dir;
  const std::string solid = (dir / "marble.vdb").string();
  ASSERT_EQ(RunPhotomat("solid exemplar --pattern marble --size 16 --out " + solid).exit_code, 0);
  testing::WriteFile(dir / "octahedron.obj", kOctahedron);
  const RunResult run =
      RunPhotomat("solid carve " + solid + " --mesh " + (dir / "octahedron.obj").string() +
                  " --preview-size 64" + " --out " + (dir / "carved").string());
  ASSERT_EQ(run.exit_code, 0) << run.output;
  // Edges of sqrt 2 on a 2-wide box in 16 voxels: 11.3 voxels, halved 4 times to 0.71.
  const nlohmann::json summary = ReadJsonFile(dir / "carved" / "carve.json");
  EXPECT_EQ(summary["input_vertices"].get<int>(), 6);
  EXPECT_EQ(summary["subdivision_levels"].get<int>(), 4);
  EXPECT_EQ(summary["triangles"].get<int>(), 8 * 256);
  const int vertices = summary["vertices"].get<int>();
  EXPECT_EQ(vertices, 2 + 8 * 256 / 2);  // closed genus-0 surface: V = F / 2 + 2
  EXPECT_LE(summary["mean_edge_voxels"].get<double>(), 1.0);
  const std::string ply = ReadTextFile(dir / "carved" / "carved.ply");
  EXPECT_THAT(ply, HasSubstr(fmt::format("element vertex {}", vertices)));
  EXPECT_THAT(ply, HasSubstr("property uchar red"));
  // Both meshes read back whole (positions on the octahedron's surface: |x| + |y| + |z| = 1).
  for (const char* file : {"carved.ply", "carved.glb"}) {
    const TriangleMesh mesh = ReadMesh(dir / "carved" / file);
    EXPECT_EQ(mesh.vertex_count(), vertices) << file;
    EXPECT_EQ(mesh.triangle_count(), 8 * 256) << file;
    for (const Eigen::Vector3d& p : mesh.positions) ASSERT_NEAR(p.cwiseAbs().sum(), 1.0, 1e-5);
  }
  const std::string table = ReadTextFile(dir / "carved" / "vertex_values.csv");
  EXPECT_EQ(table.substr(0, 6), "R,G,B\n");
  EXPECT_EQ(std::count(table.begin(), table.end(), '\n'), vertices + 1);
  for (const char* view : {"front", "right", "back", "left", "top"}) {
    const Image preview = ReadImage(dir / "carved" / fmt::format("preview_{}.png", view)).image;
    EXPECT_EQ(preview.width(), 64) << view;
  }

  const RunResult missing =
      RunPhotomat("solid carve " + solid + " --mesh " + (dir / "none.obj").string() + " --out " +
                  (dir / "x").string());
  EXPECT_EQ(missing.exit_code, 1);
  EXPECT_THAT(missing.output, HasSubstr("none.obj"));
  const RunResult repeat =
      RunPhotomat("solid carve " + solid + " --mesh " + (dir / "octahedron.obj").string() +
                  " --periods 2 --clamp --out " + (dir / "x").string());
  EXPECT_EQ(repeat.exit_code, 1);
  EXPECT_THAT(repeat.output, HasSubstr("tileable"));
  EXPECT_FALSE(std::filesystem::exists(dir / "x"));
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
