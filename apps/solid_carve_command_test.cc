// End-to-end tests of `photomat solid carve` (built with carving: solids and meshes): each runs the
// built executable.
#include <fmt/format.h>
#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include "core/atomic_file.h"
#include "core/image_io.h"
#include "core/json_file.h"
#include "synthesize/mesh/mesh_io.h"
#include "tests/support/test_support.h"

namespace photomat {
namespace {

using ::testing::HasSubstr;
using testing::RunPhotomat;
using testing::RunResult;
using testing::TempDir;

// A regular octahedron of circumradius 1 as OBJ text.
constexpr const char* kOctahedron =
    "v 1 0 0\nv -1 0 0\nv 0 1 0\nv 0 -1 0\nv 0 0 1\nv 0 0 -1\n"
    "f 1 3 5\nf 3 2 5\nf 2 4 5\nf 4 1 5\nf 3 1 6\nf 2 3 6\nf 4 2 6\nf 1 4 6\n";

TEST(SolidCarveCommandTest, CarvesAMeshOutOfASolid) {
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

}  // namespace
}  // namespace photomat
