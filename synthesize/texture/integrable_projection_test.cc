#include "synthesize/texture/integrable_projection.h"

#include <gtest/gtest.h>

#include <cmath>

#include "core/error.h"
#include "represent/fitting/fit.h"
#include "represent/surface/surface_integration.h"
#include "synthesize/texture/synthesis.h"
#include "tests/support/synthetic_sets.h"

namespace photomat {
namespace {

Image Normals(const Representation& representation) { return representation.maps().Channels(0, 3); }

// RMS distance of a gradient field from its integrable projection.
double NonIntegrability(const Image& normals) {
  const Image gradients = GradientsFromNormals(normals);
  const Image projected = ProjectToIntegrable(gradients);
  double sum = 0.0;
  for (std::size_t i = 0; i < gradients.values().size(); ++i) {
    const double d = gradients.values()[i] - projected.values()[i];
    sum += d * d;
  }
  return std::sqrt(sum / gradients.values().size());
}

TEST(IntegrableProjectionTest, GrownGradientMapsBecomeIntegrable) {
  const testing::SyntheticSet synthetic = testing::LambertianSet(SurfacePattern::kBumps, 48);
  const Representation gradient = Fit(synthetic.set, Method::Parse("gradient"));
  SynthesisOptions options;
  options.target = {96, 80, true, 2};
  const Representation grown = Synthesize(gradient, options);
  const Representation projected = ProjectNormalsToIntegrable(grown);

  const double sample = NonIntegrability(Normals(gradient));
  const double before = NonIntegrability(Normals(grown));
  const double after = NonIntegrability(Normals(projected));
  // The sample's gradients come from a surface; the quilt's do not, across its seams.
  EXPECT_GT(before, 20.0 * sample) << "quilted gradients are not a surface's";
  // (Not 0: the Nyquist terms of a real FFT projection do not survive a second projection.)
  EXPECT_LT(after, 0.02 * before);
  EXPECT_EQ(projected.details()["integrable_projection"], true);
  // The albedo maps are untouched; the normals stay unit vectors.
  for (std::size_t i = 0; i < grown.maps().pixel_count(); ++i) {
    const auto a = grown.maps().pixel(i), b = projected.maps().pixel(i);
    for (int c = 3; c < 6; ++c) ASSERT_EQ(a[c], b[c]);
    EXPECT_NEAR(b[0] * b[0] + b[1] * b[1] + b[2] * b[2], 1.0, 1e-5);
  }
  // Projection keeps the height Frankot-Chellappa integrates: only the non-integrable part goes.
  const Image height_before = HeightFromRepresentation(grown);
  const Image height_after = HeightFromRepresentation(projected);
  double worst = 0.0, range = 0.0;
  for (std::size_t i = 0; i < height_before.pixel_count(); ++i) {
    worst = std::max(worst, std::abs(double{height_before.pixel(i)[0]} - height_after.pixel(i)[0]));
    range = std::max(range, std::abs(double{height_before.pixel(i)[0]}));
  }
  EXPECT_GT(range, 0.5);
  EXPECT_LT(worst, 1e-3 * range);
}

TEST(IntegrableProjectionTest, NeedsNormals) {
  const testing::SyntheticSet synthetic = testing::LambertianSet(SurfacePattern::kBumps, 24);
  const Representation ptm = Fit(synthetic.set, Method::Parse("ptm"));
  const Representation eigen = Fit(synthetic.set, Method::Parse("eigen3"));
  EXPECT_FALSE(HasNormalMaps(ptm));
  EXPECT_THROW(ProjectNormalsToIntegrable(ptm), Error);
  EXPECT_EQ(HeightFromRepresentation(ptm).width(), 24);  // from PTM's normals
  EXPECT_THROW(HeightFromRepresentation(eigen), Error);
}

}  // namespace
}  // namespace photomat
