#include "synthesize/geometric_diffusion.h"

#include <gtest/gtest.h>

#include "synthesize/mesh_compare.h"
#include "synthesize/mesh_io.h"
#include "tests/support/test_support.h"

namespace photomat {
namespace {

TEST(CurvatureTest, SphereAndCylinderCurvatures) {
  const TriangleMesh sphere = MakeIcosphere(2.0, 4);
  const auto sphere_frames = EstimateCurvatures(sphere);
  // Taubin's estimator is approximate near the valence-5 vertices (up to 17 % here).
  double mean = 0.0;
  for (const auto& frame : sphere_frames) {
    ASSERT_NEAR(std::abs(frame.k1), 0.5, 0.1);
    ASSERT_NEAR(std::abs(frame.k2), 0.5, 0.1);
    mean += (std::abs(frame.k1) + std::abs(frame.k2)) / (2.0 * sphere_frames.size());
  }
  EXPECT_NEAR(mean, 0.5, 0.01);
  // The outer equator of a torus: curvatures 1 / r across the tube and 1 / (R + r) around.
  const TriangleMesh torus = MakeTorus(3.0, 1.0, 240, 60);
  const auto frames = EstimateCurvatures(torus);
  const auto& outer = frames[0];  // u = 0, v = 0: the point (4, 0, 0)
  EXPECT_NEAR(std::abs(outer.k1), 1.0, 0.03);
  EXPECT_NEAR(std::abs(outer.k2), 0.25, 0.03);
  EXPECT_NEAR(std::abs(outer.e1.z()), 1.0, 0.01);  // across the tube
  EXPECT_DOUBLE_EQ(EdgeStopping(0.5, 1.0), 1.0);
  EXPECT_DOUBLE_EQ(EdgeStopping(-3.0, 1.0), 0.2);
}

// Fandisk (6,475 vertices) with Gaussian noise of 0.2 x mean edge length along the normals, then
// 10 steps of anisotropic diffusion at the defaults (about 0.5 s) against 10 isotropic ones.
TEST(GeometricDiffusionTest, NoisyFandiskIsDenoisedWhileItsSharpEdgesStay) {
  PHOTOMAT_TEST_DATA_OR_SKIP(file, "meshes/fandisk.obj");
  const TriangleMesh clean = ReadMesh(file);
  TriangleMesh noisy = clean;
  AddNormalNoise(noisy, 0.2 * MeanEdgeLength(clean), 5);
  const auto edges = FeatureEdges(clean, 30.0);
  ASSERT_GT(edges.size(), 500u);
  GeometricDiffusionOptions options;
  options.steps = 10;
  const TriangleMesh smoothed = SmoothMeshAnisotropic(noisy, options);
  options.isotropic = true;
  const TriangleMesh rounded = SmoothMeshAnisotropic(noisy, options);

  const auto noisy_distance = DeviationFromReference(noisy, clean);
  const auto smoothed_distance = DeviationFromReference(smoothed, clean);
  const auto smoothed_angles = FeatureAngleChange(smoothed, clean, edges);
  const auto rounded_angles = FeatureAngleChange(rounded, clean, edges);
  const auto noisy_angles = FeatureAngleChange(noisy, clean, edges);
  std::printf(
      "fandisk: mean distance to the clean surface %.5f -> %.5f (x %.2f); %zu sharp "
      "edges, angle change mean %+.2f deg (noisy %+.2f, isotropic %+.2f), per-edge "
      "median |change| %.2f (noisy %.2f), mean |change| %.2f; volume %.3f -> %.3f\n",
      noisy_distance.mean, smoothed_distance.mean, smoothed_distance.mean / noisy_distance.mean,
      edges.size(), smoothed_angles.mean_signed, noisy_angles.mean_signed,
      rounded_angles.mean_signed, smoothed_angles.median, noisy_angles.median, smoothed_angles.mean,
      EnclosedVolume(clean), EnclosedVolume(smoothed));
  EXPECT_LT(smoothed_distance.mean, 0.5 * noisy_distance.mean);
  // The sharp edges keep their angle on average (isotropic smoothing rounds them by tens of
  // degrees) ...
  EXPECT_LT(std::abs(smoothed_angles.mean_signed), 5.0);
  EXPECT_LT(rounded_angles.mean_signed, -20.0);
  // ... and per edge the typical change is below what the noise alone made.
  EXPECT_LT(smoothed_angles.median, noisy_angles.median);
  EXPECT_NEAR(EnclosedVolume(smoothed), EnclosedVolume(clean), 0.01 * EnclosedVolume(clean));
}

TEST(GeometricDiffusionTest, CoupledLoopSmoothsAndGrowsThePattern) {
  TriangleMesh noisy = MakeIcosphere(12.0, 4);
  AddNormalNoise(noisy, 0.2 * MeanEdgeLength(noisy), 9);
  TurkParameters parameters;
  auto model = MakeTurkModel(parameters);
  SimulationOptions options;
  options.time_step = model->suggested_time_step();
  options.max_steps = 1200;
  GeometricDiffusionOptions geometry;
  geometry.steps = 5;
  const CoupledResult coupled = SimulateCoupled(noisy, *model, options, geometry);
  // The sphere came back toward round...
  auto radius_spread = [](const TriangleMesh& mesh) {
    double sum = 0, sum2 = 0;
    for (const auto& p : mesh.positions) {
      sum += p.norm();
      sum2 += p.squaredNorm();
    }
    const double n = mesh.vertex_count();
    return std::sqrt(sum2 / n - (sum / n) * (sum / n));
  };
  std::printf("coupled: radius spread %.4f -> %.4f; pattern contrast %.2f after %d steps\n",
              radius_spread(noisy), radius_spread(coupled.mesh),
              coupled.pattern.fields[1].maxCoeff() - coupled.pattern.fields[1].minCoeff(),
              coupled.pattern.steps);
  EXPECT_LT(radius_spread(coupled.mesh), 0.5 * radius_spread(noisy));
  // ... and the pattern formed on it.
  EXPECT_GT(coupled.pattern.fields[1].maxCoeff() - coupled.pattern.fields[1].minCoeff(), 3.0);
  EXPECT_EQ(coupled.pattern.steps, 1200);
}

}  // namespace
}  // namespace photomat
