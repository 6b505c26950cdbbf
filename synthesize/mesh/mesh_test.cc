#include "synthesize/mesh/mesh.h"

#include <assimp/scene.h>
#include <gtest/gtest.h>

#include <assimp/Importer.hpp>
#include <cmath>
#include <numbers>

#include "core/colour.h"
#include "core/error.h"
#include "synthesize/mesh/field_colours.h"
#include "synthesize/mesh/loop_subdivision.h"
#include "synthesize/mesh/mesh_io.h"
#include "synthesize/mesh/mesh_render.h"
#include "tests/support/test_support.h"

namespace photomat {
namespace {

constexpr double kPi = std::numbers::pi;

TEST(MeshTest, IcosphereIsClosedOutwardAndOnTheSphere) {
  const TriangleMesh sphere = MakeIcosphere(2.0, 3);
  EXPECT_EQ(sphere.vertex_count(), 10 * 64 + 2);
  EXPECT_EQ(sphere.triangle_count(), 20 * 64);
  EXPECT_EQ(CountBoundaryEdges(sphere), 0);
  for (const auto& p : sphere.positions) EXPECT_NEAR(p.norm(), 2.0, 1e-12);
  // Outward orientation: positive enclosed volume, a little under the sphere's (inscribed).
  const double volume = EnclosedVolume(sphere);
  EXPECT_GT(volume, 0.97 * 4.0 / 3.0 * kPi * 8.0);
  EXPECT_LT(volume, 4.0 / 3.0 * kPi * 8.0);
  const auto normals = VertexNormals(sphere);
  for (int v = 0; v < sphere.vertex_count(); ++v) {
    EXPECT_GT(normals[v].dot(sphere.positions[v].normalized()), 0.999);
  }
}

TEST(MeshTest, TorusAreaAndVolumeMatchTheFormulas) {
  const TriangleMesh torus = MakeTorus(3.0, 1.0, 160, 80);
  EXPECT_EQ(CountBoundaryEdges(torus), 0);
  EXPECT_NEAR(SurfaceArea(torus), 4.0 * kPi * kPi * 3.0, 0.005 * 4.0 * kPi * kPi * 3.0);
  EXPECT_NEAR(EnclosedVolume(torus), 2.0 * kPi * kPi * 3.0, 0.005 * 2.0 * kPi * kPi * 3.0);
}

TEST(MeshTest, NormalisationByBoundingBoxAndByArea) {
  TriangleMesh torus = MakeTorus(3.0, 1.0, 40, 20);
  for (auto& p : torus.positions) p += Eigen::Vector3d(5, -2, 1);
  NormalizeMesh(torus, MeshNormalization::kBoundingBox, 10.0);
  EXPECT_NEAR(ComputeBoundingBox(torus).Diagonal(), 10.0, 1e-9);
  EXPECT_NEAR(ComputeBoundingBox(torus).Centre().norm(), 0.0, 1e-9);
  NormalizeMesh(torus, MeshNormalization::kArea, 7.0);
  EXPECT_NEAR(SurfaceArea(torus), 49.0, 1e-9);
  EXPECT_THROW(ParseMeshNormalization("volume"), Error);
  EXPECT_THROW(NormalizeMesh(torus, MeshNormalization::kArea, -1.0), Error);
}

TEST(MeshTest, ValidationNamesTheFault) {
  TriangleMesh mesh;
  mesh.positions = {{0, 0, 0}, {1, 0, 0}, {0, 1, 0}};
  mesh.triangles = {{0, 1, 3}};
  EXPECT_THROW(ValidateMesh(mesh, "m.obj"), Error);
  mesh.triangles = {{0, 1, 1}};
  EXPECT_THROW(ValidateMesh(mesh, "m.obj"), Error);
  mesh.triangles = {{0, 1, 2}};
  EXPECT_NO_THROW(ValidateMesh(mesh, "m.obj"));
}

TEST(LoopSubdivisionTest, CountsClosednessAndPlanarity) {
  const TriangleMesh sphere = MakeIcosphere(1.0, 1);
  const TriangleMesh once = LoopSubdivide(sphere, 1);
  const int edges = static_cast<int>(UniqueEdges(sphere).size());
  EXPECT_EQ(once.vertex_count(), sphere.vertex_count() + edges);
  EXPECT_EQ(once.triangle_count(), 4 * sphere.triangle_count());
  EXPECT_EQ(CountBoundaryEdges(once), 0);
  // Loop's masks are affine combinations: a flat patch stays flat and a linear function of the
  // positions is reproduced, boundary included (the boundary rules keep the outline's line).
  TriangleMesh patch;
  for (int y = 0; y < 5; ++y) {
    for (int x = 0; x < 5; ++x) patch.positions.emplace_back(x, y, 0.5 * x - 0.25 * y);
  }
  for (int y = 0; y < 4; ++y) {
    for (int x = 0; x < 4; ++x) {
      const int a = y * 5 + x;
      patch.triangles.push_back({a, a + 1, a + 6});
      patch.triangles.push_back({a, a + 6, a + 5});
    }
  }
  const TriangleMesh fine = LoopSubdivide(patch, 2);
  EXPECT_EQ(CountBoundaryEdges(fine), 4 * CountBoundaryEdges(patch));
  for (const auto& p : fine.positions) EXPECT_NEAR(p.z(), 0.5 * p.x() - 0.25 * p.y(), 1e-12);
  // The original vertices converge to their limit positions: each level moves them about a
  // quarter as far as the one before.
  const TriangleMesh two = LoopSubdivide(sphere, 2), three = LoopSubdivide(sphere, 3);
  double move12 = 0.0, move23 = 0.0;
  for (int v = 0; v < sphere.vertex_count(); ++v) {
    move12 = std::max(move12, (two.positions[v] - once.positions[v]).norm());
    move23 = std::max(move23, (three.positions[v] - two.positions[v]).norm());
  }
  EXPECT_GT(move12, 0.0);
  EXPECT_LT(move23, 0.35 * move12);
}

TEST(MeshIoTest, ReadsTheSharedMeshes) {
  PHOTOMAT_TEST_DATA_OR_SKIP(folder, "meshes");
  // The bunny's OBJ lists 35,947 vertices; 34,834 are used by its 69,451 triangles.
  const TriangleMesh bunny = ReadMesh(folder / "stanford-bunny.obj");
  EXPECT_EQ(bunny.vertex_count(), 34834);
  EXPECT_EQ(bunny.triangle_count(), 69451);
  EXPECT_GT(CountBoundaryEdges(bunny), 0);  // holes at the base
  // spot's UV seams split vertices in the file's corners; merging restores the closed surface.
  const TriangleMesh spot = ReadMesh(folder / "spot.obj");
  EXPECT_EQ(spot.vertex_count(), 2930);
  EXPECT_EQ(spot.triangle_count(), 5856);
  EXPECT_EQ(CountBoundaryEdges(spot), 0);
  EXPECT_GT(EnclosedVolume(spot), 0.0);
  const TriangleMesh fandisk = ReadMesh(folder / "fandisk.obj");
  EXPECT_EQ(fandisk.vertex_count(), 6475);
  EXPECT_EQ(fandisk.triangle_count(), 12946);
  const TriangleMesh cow = ReadMesh(folder / "cow.obj");
  EXPECT_EQ(cow.vertex_count(), 2903);
}

TEST(MeshIoTest, BadFilesAreErrorsNamingTheFile) {
  testing::TempDir dir;
  try {
    ReadMesh(dir / "missing.obj");
    FAIL() << "no error";
  } catch (const Error& error) {
    EXPECT_EQ(error.file(), dir / "missing.obj");
  }
  testing::WriteFile(dir / "garbage.ply", "ply\nformat nonsense\n");
  EXPECT_THROW(ReadMesh(dir / "garbage.ply"), Error);
  testing::WriteFile(dir / "empty.obj", "# nothing\nv 0 0 0\n");
  EXPECT_THROW(ReadMesh(dir / "empty.obj"), Error);
  const TriangleMesh sphere = MakeIcosphere(1.0, 1);
  EXPECT_THROW(WriteMesh(dir / "out.stl", sphere), Error);
  const std::vector<Eigen::Vector3f> too_few(3, Eigen::Vector3f::Zero());
  EXPECT_THROW(WriteMesh(dir / "out.ply", sphere, too_few), Error);
  EXPECT_FALSE(std::filesystem::exists(dir / "out.ply"));
}

// Reads the first mesh's vertex colours back with assimp.
std::vector<Eigen::Vector4f> ReadColours(const std::filesystem::path& path) {
  Assimp::Importer importer;
  const aiScene* scene = importer.ReadFile(path.string(), 0);
  std::vector<Eigen::Vector4f> colours;
  if (scene == nullptr || scene->mNumMeshes == 0 || !scene->mMeshes[0]->HasVertexColors(0)) {
    return colours;
  }
  const aiMesh* mesh = scene->mMeshes[0];
  for (unsigned v = 0; v < mesh->mNumVertices; ++v) {
    const aiColor4D& c = mesh->mColors[0][v];
    colours.emplace_back(c.r, c.g, c.b, c.a);
  }
  return colours;
}

TEST(MeshIoTest, PlyAndGlbRoundTripPositionsAndColours) {
  testing::TempDir dir;
  TriangleMesh torus = MakeTorus(2.0, 0.5, 24, 12);
  Eigen::VectorXd field(torus.vertex_count());
  for (int v = 0; v < torus.vertex_count(); ++v) field[v] = torus.positions[v].z();
  const auto colours = FieldColours(field, {ColourMap::kViridis, {}, {}});
  for (const char* name : {"torus.ply", "torus.glb"}) {
    WriteMesh(dir / name, torus, colours);
    const TriangleMesh back = ReadMesh(dir / name);
    ASSERT_EQ(back.vertex_count(), torus.vertex_count()) << name;
    ASSERT_EQ(back.triangle_count(), torus.triangle_count()) << name;
    EXPECT_NEAR(SurfaceArea(back), SurfaceArea(torus), 1e-5 * SurfaceArea(torus)) << name;
    EXPECT_GT(EnclosedVolume(back), 0.0) << name;  // orientation kept
    const auto read = ReadColours(dir / name);
    ASSERT_EQ(read.size(), colours.size()) << name;
    // PLY stores 8-bit sRGB; glTF stores linear floats.
    const bool srgb = std::string(name).ends_with(".ply");
    for (std::size_t v = 0; v < read.size(); ++v) {
      for (int c = 0; c < 3; ++c) {
        const double expected = srgb ? LinearToSrgb(colours[v][c]) : colours[v][c];
        EXPECT_NEAR(read[v][c], expected, srgb ? 0.5 / 255 + 1e-6 : 1e-6) << name << " " << v;
      }
    }
  }
}

TEST(FieldColoursTest, MapsTheRangeToTheColourMapEnds) {
  Eigen::VectorXd field(3);
  field << -1.0, 0.0, 1.0;
  const auto grey = FieldColours(field, {ColourMap::kGrey, {}, {}});
  EXPECT_NEAR(grey[0].x(), 0.0, 1e-6);
  EXPECT_NEAR(grey[2].x(), 1.0, 1e-6);
  EXPECT_NEAR(LinearToSrgb(grey[1].x()), 128.0 / 255.0, 1e-6);
  const auto clamped = FieldColours(field, {ColourMap::kGrey, 0.0, 0.5});
  EXPECT_NEAR(clamped[0].x(), 0.0, 1e-6);
  EXPECT_NEAR(clamped[2].x(), 1.0, 1e-6);
  EXPECT_THROW(ParseColourMap("rainbow"), Error);
}

TEST(MeshRenderTest, ASphereRendersAsAShadedDiscOfTheRightSize) {
  const TriangleMesh sphere = MakeIcosphere(1.0, 4);
  const std::vector<Eigen::Vector3f> red(sphere.vertex_count(), Eigen::Vector3f(1, 0, 0));
  PreviewOptions options;
  options.size = 200;
  const Image image = RenderPreview(sphere, red, {"front", 0, 0}, options);
  ASSERT_EQ(image.width(), 200);
  int covered = 0;
  for (std::size_t i = 0; i < image.pixel_count(); ++i) {
    const auto p = image.pixel(i);
    if (p[1] < 0.5f) {  // not the white background
      ++covered;
      EXPECT_NEAR(p[1], 0.0f, 1e-6f);
      EXPECT_GE(p[0], options.ambient - 1e-6f);
    }
  }
  // The bounding box diagonal (2 sqrt 3) spans 90 % of the frame: radius 0.9 * 200 / (2 sqrt 3).
  const double radius = 0.9 * 200 / (2.0 * std::sqrt(3.0));
  EXPECT_NEAR(covered, kPi * radius * radius, 0.02 * kPi * radius * radius);
  // Lit from the upper left: the upper-left of the disc is brighter than the lower right.
  EXPECT_GT(image.at(80, 80, 0), image.at(120, 120, 0) + 0.2f);
  testing::TempDir dir;
  const auto written = WritePreviews(dir.path(), "sphere", sphere, red, DefaultPreviewViews());
  EXPECT_EQ(written.size(), 5u);
  for (const auto& path : written) EXPECT_TRUE(std::filesystem::exists(path)) << path;
}

}  // namespace
}  // namespace photomat
