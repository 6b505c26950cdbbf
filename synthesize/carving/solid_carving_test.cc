#include "synthesize/carving/solid_carving.h"

#include <gtest/gtest.h>

#include <cmath>
#include <numbers>

#include "core/error.h"
#include "core/image_io.h"
#include "synthesize/mesh/mesh_io.h"
#include "synthesize/mesh/mesh_render.h"
#include "synthesize/solid/procedural_exemplars.h"
#include "tests/support/test_support.h"

namespace photomat {
namespace {

constexpr double kTwoPi = 2.0 * std::numbers::pi;

// A volume whose three channels are the continuous coordinates of each voxel centre.
Image CoordinateVolume(ImageExtent size) {
  Image volume(size, std::vector<std::string>{"x", "y", "z"});
  for (int z = 0; z < size.depth; ++z) {
    for (int y = 0; y < size.height; ++y) {
      for (int x = 0; x < size.width; ++x) {
        volume.at(x, y, z, 0) = static_cast<float>(x) + 0.5f;
        volume.at(x, y, z, 1) = static_cast<float>(y) + 0.5f;
        volume.at(x, y, z, 2) = static_cast<float>(z) + 0.5f;
      }
    }
  }
  return volume;
}

// A tileable volume of one smooth periodic function, and that function.
double Wave(const Eigen::Vector3d& p, int n) {
  return 0.5 + 0.2 * std::sin(kTwoPi * p.x() / n) + 0.15 * std::cos(kTwoPi * 2 * p.y() / n) +
         0.1 * std::sin(kTwoPi * (p.z() + p.x()) / n);
}

Image WaveVolume(int n) {
  Image volume(ImageExtent::Cube(n), std::vector<std::string>{"R", "G", "B"});
  for (int z = 0; z < n; ++z) {
    for (int y = 0; y < n; ++y) {
      for (int x = 0; x < n; ++x) {
        const double value = Wave(Eigen::Vector3d(x + 0.5, y + 0.5, z + 0.5), n);
        for (int c = 0; c < 3; ++c) volume.at(x, y, z, c) = static_cast<float>(value);
      }
    }
  }
  return volume;
}

TEST(SolidCarvingTest, TrilinearSamplingIsExactOnARampAndWrapsWhenTileable) {
  const ImageExtent size{8, 10, 12};
  const Image ramp = CoordinateVolume(size);
  std::vector<float> value(3);
  for (const Eigen::Vector3d& at : {Eigen::Vector3d(0.5, 0.5, 0.5), Eigen::Vector3d(3.25, 7.9, 2.0),
                                    Eigen::Vector3d(7.5, 9.5, 11.5)}) {
    for (bool tileable : {false, true}) {
      SampleTrilinear(ramp, at, tileable, value);
      for (int c = 0; c < 3; ++c) EXPECT_NEAR(value[static_cast<std::size_t>(c)], at[c], 1e-5);
    }
  }
  // Beyond the outer centres: clamped to the face values, or interpolated across the wrap.
  SampleTrilinear(ramp, Eigen::Vector3d(0.25, 5.0, 5.0), false, value);
  EXPECT_NEAR(value[0], 0.5, 1e-6);
  SampleTrilinear(ramp, Eigen::Vector3d(0.25, 5.0, 5.0), true, value);
  EXPECT_NEAR(value[0], 0.25 * 7.5 + 0.75 * 0.5, 1e-5);
  SampleTrilinear(ramp, Eigen::Vector3d(8.0 + 3.25, 5.0, 5.0), true, value);  // one period on
  EXPECT_NEAR(value[0], 3.25, 1e-5);
}

TEST(SolidCarvingTest, MidpointSubdivisionKeepsTheSurface) {
  const TriangleMesh sphere = MakeIcosphere(1.0, 1);
  const int edges = static_cast<int>(UniqueEdges(sphere).size());
  const TriangleMesh once = SubdivideMidpoints(sphere, 1);
  EXPECT_EQ(once.vertex_count(), sphere.vertex_count() + edges);
  EXPECT_EQ(once.triangle_count(), 4 * sphere.triangle_count());
  const TriangleMesh twice = SubdivideMidpoints(sphere, 2);
  EXPECT_NO_THROW(ValidateMesh(twice, "subdivided"));
  EXPECT_EQ(CountBoundaryEdges(twice), 0);
  for (int v = 0; v < sphere.vertex_count(); ++v) {
    ASSERT_EQ(twice.positions[static_cast<std::size_t>(v)],
              sphere.positions[static_cast<std::size_t>(v)]);
  }
  // Flat splits: same area and enclosed volume (Loop subdivision would shrink both).
  EXPECT_NEAR(SurfaceArea(twice), SurfaceArea(sphere), 1e-9 * SurfaceArea(sphere));
  EXPECT_NEAR(EnclosedVolume(twice), EnclosedVolume(sphere), 1e-9);
  EXPECT_NEAR(MeanEdgeLength(twice), MeanEdgeLength(sphere) / 4, 1e-9);
}

TEST(SolidCarvingTest, PlacementCentresTheMeshAndScalesItsLongestSide) {
  const TriangleMesh torus = MakeTorus(2.0, 0.5, 32, 12);  // 5 x 5 x 1 around the origin
  const CarveMapping mapping = PlaceMesh(torus, ImageExtent{40, 50, 60}, {});
  EXPECT_NEAR(mapping.scale, 40.0 / 5.0, 1e-9);
  EXPECT_TRUE(mapping.ToVolume(Eigen::Vector3d::Zero()).isApprox(Eigen::Vector3d(20, 25, 30)));
  EXPECT_NEAR(mapping.ToVolume(Eigen::Vector3d(2.5, 0, 0)).x(), 40.0, 1e-9);
  EXPECT_NEAR(PlaceMesh(torus, ImageExtent::Cube(40), {.periods = 3.0}).scale, 24.0, 1e-9);
  EXPECT_THROW(PlaceMesh(torus, ImageExtent::Cube(40), {.periods = 0.0}), Error);
  EXPECT_THROW(PlaceMesh(torus, ImageExtent::Cube(40), {.periods = 2.0, .tileable = false}), Error);
}

TEST(SolidCarvingTest, CarvedSphereAndTorusCarryTheVolumeAtTheirSurface) {
  constexpr int n = 32;
  const Image volume = WaveVolume(n);
  for (const TriangleMesh& mesh : {MakeIcosphere(1.0, 2), MakeTorus(2.0, 0.7, 24, 10)}) {
    for (double periods : {1.0, 2.5}) {
      CarveOptions options;
      options.placement.periods = periods;
      const CarvedMesh carved = CarveMesh(mesh, volume, options);
      // Dense enough: mean edge at most a voxel, and the level before was not.
      const double edge = MeanEdgeLength(carved.mesh) * carved.mapping.scale;
      EXPECT_LE(edge, 1.0);
      EXPECT_GT(2 * edge, 1.0);
      EXPECT_NEAR(SurfaceArea(carved.mesh), SurfaceArea(mesh), 1e-9 * SurfaceArea(mesh));
      ASSERT_EQ(carved.values.size(), static_cast<std::size_t>(carved.mesh.vertex_count()) * 3);
      // Every vertex holds the (periodic) function at its place in the volume, up to the error of
      // linear interpolation between voxel centres.
      double worst = 0;
      for (int v = 0; v < carved.mesh.vertex_count(); ++v) {
        const Eigen::Vector3d at =
            carved.mapping.ToVolume(carved.mesh.positions[static_cast<std::size_t>(v)]);
        worst = std::max(worst, std::abs(carved.at(v)[0] - Wave(at, n)));
      }
      EXPECT_LT(worst, 0.01) << "periods " << periods;
    }
  }
}

TEST(SolidCarvingTest, WritesColouredMeshesAndPreviewsOfAProceduralSolid) {
  const Image marble = MakeProceduralExemplar(ProceduralPattern::kMarble, 32, 4);
  const CarvedMesh carved = CarveMesh(MakeTorus(2.0, 0.8, 32, 12), marble, {});
  const std::vector<Eigen::Vector3f> colours = CarvedColours(carved, marble, false);
  ASSERT_EQ(colours.size(), static_cast<std::size_t>(carved.mesh.vertex_count()));
  // Colours are the marble's: red bands and cream ones on the same object.
  int red = 0, cream = 0;
  for (const Eigen::Vector3f& c : colours) {
    red += c.x() > 0.4f && c.y() < 0.15f;
    cream += c.x() > 0.75f && c.y() > 0.7f;
  }
  EXPECT_GT(red, carved.mesh.vertex_count() / 10);
  EXPECT_GT(cream, carved.mesh.vertex_count() / 10);
  testing::TempDir dir;
  WriteMesh(dir / "torus.ply", carved.mesh, colours);
  WriteMesh(dir / "torus.glb", carved.mesh, colours);
  EXPECT_EQ(ReadMesh(dir / "torus.ply").vertex_count(), carved.mesh.vertex_count());
  EXPECT_EQ(ReadMesh(dir / "torus.glb").vertex_count(), carved.mesh.vertex_count());
  const auto previews =
      WritePreviews(dir.path(), "preview", carved.mesh, colours, DefaultPreviewViews());
  ASSERT_EQ(previews.size(), 5u);
  const Image front = ReadImage(previews[0]).image;
  int reddish = 0;
  for (std::size_t i = 0; i < front.pixel_count(); ++i) {
    reddish += front.pixel(i)[0] > 2.0f * front.pixel(i)[1] + 0.05f;
  }
  EXPECT_GT(reddish, 1000);  // the marble's red shows in the picture
}

TEST(SolidCarvingTest, NormalisedColoursOfNonColourChannels) {
  Image normals(ImageExtent::Cube(8), std::vector<std::string>{"normal.X", "normal.Y"});
  for (std::size_t i = 0; i < normals.pixel_count(); ++i) {
    normals.pixel(i)[0] = -1.0f + 2.0f * static_cast<float>(i % 8) / 7.0f;
    normals.pixel(i)[1] = 0.0f;
  }
  const CarvedMesh carved = CarveMesh(MakeIcosphere(1.0, 2), normals, {});
  const auto colours = CarvedColours(carved, normals, true);
  float low = 1, high = 0;
  for (const Eigen::Vector3f& c : colours) {
    EXPECT_EQ(c.x(), c.y());  // one channel shown as grey
    low = std::min(low, c.x());
    high = std::max(high, c.x());
  }
  EXPECT_EQ(low, 0.0f);
  EXPECT_EQ(high, 1.0f);
  EXPECT_THROW(CarveMesh(MakeIcosphere(1.0, 1), Image(), {}), Error);
}

TEST(SolidCarvingTest, CarvesSpot) {
  PHOTOMAT_TEST_DATA_OR_SKIP(file, "meshes/spot.obj");
  const TriangleMesh spot = ReadMesh(file);
  ASSERT_EQ(spot.vertex_count(), 2930);
  const Image wood = MakeProceduralExemplar(ProceduralPattern::kWood, 64, 2);
  const CarvedMesh carved = CarveMesh(spot, wood, {});
  // spot's mean edge spans 1.78 voxels of a 64^3 block (3.6 of a 128^3 one): one level of
  // subdivision brings it under a voxel, 11,714 vertices instead of 2,930.
  EXPECT_NEAR(MeanEdgeLength(spot) * carved.mapping.scale, 1.78, 0.01);
  EXPECT_EQ(carved.subdivision_levels, 1);
  EXPECT_EQ(carved.mesh.triangle_count(), 4 * spot.triangle_count());
  EXPECT_LE(MeanEdgeLength(carved.mesh) * carved.mapping.scale, 1.0);
  EXPECT_EQ(CountBoundaryEdges(carved.mesh), 0);
  const auto colours = CarvedColours(carved, wood, false);
  // Early and late wood both show on the cow.
  float darkest = 1, lightest = 0;
  for (const Eigen::Vector3f& c : colours) {
    darkest = std::min(darkest, c.x());
    lightest = std::max(lightest, c.x());
  }
  EXPECT_LT(darkest, 0.35f);
  EXPECT_GT(lightest, 0.6f);
  testing::TempDir dir;
  WriteMesh(dir / "spot.glb", carved.mesh, colours);
  EXPECT_EQ(ReadMesh(dir / "spot.glb").vertex_count(), carved.mesh.vertex_count());
}

}  // namespace
}  // namespace photomat
