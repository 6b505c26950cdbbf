#include "synthesize/surface/reaction_diffusion.h"

#include <gtest/gtest.h>

#include <cmath>
#include <numbers>

#include "core/error.h"
#include "represent/stack/map_stack.h"
#include "synthesize/mesh/mesh.h"
#include "synthesize/surface/pattern_analysis.h"
#include "synthesize/surface/pattern_material.h"
#include "synthesize/surface/ready_pattern.h"
#include "tests/support/test_support.h"

namespace photomat {
namespace {

constexpr double kPi = std::numbers::pi;

TEST(PatternAnalysisTest, SphericalHarmonicPowerFindsTheDegree) {
  const FemDomain domain = FemDomain::FromMesh(MakeIcosphere(5.0, 4));
  const FemOperators operators(domain);
  Eigen::VectorXd field(domain.node_count());
  for (int i = 0; i < domain.node_count(); ++i) {
    const Eigen::Vector3d d = domain.node_positions()[i].normalized();
    // Degree-3 harmonics (a mix of m) plus a constant: all the power at l = 3.
    field[i] = 2.0 + d.x() * d.y() * d.z() + 0.3 * (5 * d.z() * d.z() * d.z() - 3 * d.z());
  }
  const auto power = SphericalHarmonicPower(operators, field, 8);
  double total = 0.0;
  for (double p : power) total += p;
  EXPECT_GT(power[3] / total, 0.99);
  const auto peak = DominantSphericalDegree(power, 5.0);
  EXPECT_EQ(peak.degree, 3);
  EXPECT_NEAR(peak.wavelength, 2 * kPi * 5.0 / std::sqrt(12.0), 1e-12);
}

TEST(PatternAnalysisTest, GridWavelengthAndShapes) {
  const GridShape grid{64, 64, 0.5};
  Eigen::VectorXd stripes(64 * 64), spots(64 * 64);
  for (int y = 0; y < 64; ++y) {
    for (int x = 0; x < 64; ++x) {
      stripes[y * 64 + x] = std::sin(2 * kPi * (x + 0.5) / 8.0);  // wavelength 8 nodes = 4 units
      spots[y * 64 + x] = std::sin(2 * kPi * x / 16.0) * std::sin(2 * kPi * y / 16.0);
    }
  }
  EXPECT_NEAR(DominantGridWavelength(grid, stripes), 4.0, 1e-9);
  const auto stripe_shape = MeasureGridPattern(grid, stripes);
  // One stripe per period, 4 nodes wide, wrapping around: 4 pi 256 / 128^2.
  EXPECT_EQ(stripe_shape.components, 8);
  EXPECT_NEAR(stripe_shape.compactness, 4 * kPi * 256 / (128.0 * 128.0), 1e-9);
  const auto spot_shape = MeasureGridPattern(grid, spots);
  EXPECT_EQ(spot_shape.components, 32);  // the positive lobes of 4 x 4 periods
  EXPECT_GT(spot_shape.compactness, 0.5);
}

// Turk's model on a sphere of radius 12 (icosphere level 4: 2,562 vertices, edge 0.79, 1/6.3 of
// the shortest wavelength), tau s = 0.025, 1,200 steps: about 0.6 s per value of s.
TEST(TurkTest, WavelengthOnASphereFollowsTheLinearTheoryAndScalesAsSToTheMinusHalf) {
  const double radius = 12.0;
  const FemDomain domain = FemDomain::FromMesh(MakeIcosphere(radius, 4));
  const FemOperators operators(domain);
  std::vector<double> s_values = {0.025, 0.0375, 0.05}, wavelengths;
  for (double s : s_values) {
    TurkParameters parameters;
    parameters.s = s;
    auto model = MakeTurkModel(parameters);
    SimulationOptions options;
    options.time_step = model->suggested_time_step();
    options.max_steps = 1200;
    options.seed = 7;
    const SimulationResult result = SimulateReactionDiffusion(*model, domain, options);
    const Eigen::VectorXd& b = result.fields[1];
    const auto peak = DominantSphericalDegree(SphericalHarmonicPower(operators, b, 40), radius);
    const double theory = TurkCriticalWavelength(s);
    std::printf(
        "turk s = %.4f: l = %d, wavelength %.3f (theory %.3f, %+.1f %%), contrast %.2f, "
        "%d steps, %lld CG iterations\n",
        s, peak.degree, peak.wavelength, theory, 100 * (peak.wavelength / theory - 1),
        b.maxCoeff() - b.minCoeff(), result.steps, result.total_iterations);
    EXPECT_GT(b.maxCoeff() - b.minCoeff(), 3.0) << "no pattern formed at s = " << s;
    EXPECT_NEAR(peak.wavelength, theory, 0.15 * theory) << "s = " << s;
    wavelengths.push_back(peak.wavelength);
  }
  // Least-squares slope of log wavelength against log s: -1/2.
  double mx = 0, my = 0;
  for (int i = 0; i < 3; ++i) {
    mx += std::log(s_values[i]) / 3;
    my += std::log(wavelengths[i]) / 3;
  }
  double sxy = 0, sxx = 0;
  for (int i = 0; i < 3; ++i) {
    sxy += (std::log(s_values[i]) - mx) * (std::log(wavelengths[i]) - my);
    sxx += (std::log(s_values[i]) - mx) * (std::log(s_values[i]) - mx);
  }
  std::printf("turk: wavelength ~ s^%.3f (theory s^-0.5)\n", sxy / sxx);
  EXPECT_NEAR(sxy / sxx, -0.5, 0.1);
}

// Spec 9.5: the semi-implicit scheme at a longer step lands on the same pattern scale. The
// Gauss-Seidel ordering at tau s = 0.06 (2.4x the Jacobi step, beyond Jacobi's limit 1/28).
TEST(TurkTest, GaussSeidelOrderingAtALongerStepFindsTheSameDegree) {
  const double radius = 12.0;
  const FemDomain domain = FemDomain::FromMesh(MakeIcosphere(radius, 4));
  const FemOperators operators(domain);
  std::array<int, 2> degrees{};
  for (int gauss_seidel = 0; gauss_seidel < 2; ++gauss_seidel) {
    TurkParameters parameters;
    auto model = MakeTurkModel(parameters);
    SimulationOptions options;
    options.time_step = (gauss_seidel ? 0.06 : 0.025) / parameters.s;
    options.max_steps = gauss_seidel ? 500 : 1200;
    options.ordering = gauss_seidel ? SpeciesOrdering::kGaussSeidel : SpeciesOrdering::kJacobi;
    const SimulationResult result = SimulateReactionDiffusion(*model, domain, options);
    degrees[gauss_seidel] =
        DominantSphericalDegree(SphericalHarmonicPower(operators, result.fields[1], 40), radius)
            .degree;
    EXPECT_GT(result.fields[1].maxCoeff() - result.fields[1].minCoeff(), 3.0);
  }
  EXPECT_NEAR(degrees[1], degrees[0], 1);
}

TEST(TurkTest, UniformBetaStaysHomogeneousAndTheReactionAloneIsStable) {
  const FemDomain domain = FemDomain::FromMesh(MakeIcosphere(12.0, 3));
  TurkParameters parameters;
  parameters.beta_noise = 0.0;  // beta = 12 exactly: a = b = 4 is an exact steady state
  auto model = MakeTurkModel(parameters);
  SimulationOptions options;
  options.time_step = model->suggested_time_step();
  options.max_steps = 400;
  const SimulationResult result = SimulateReactionDiffusion(*model, domain, options);
  EXPECT_LT((result.fields[0].array() - 4.0).abs().maxCoeff(), 1e-9);
  EXPECT_LT((result.fields[1].array() - 4.0).abs().maxCoeff(), 1e-9);
}

TEST(TurkTest, AnisotropicDiffusionLaysStripesAlongTheDirectionField) {
  const FemDomain domain = FemDomain::FromMesh(MakeIcosphere(12.0, 4));
  // Share of the pattern's gradient energy along the field's direction t (rings around y).
  auto along_share = [&](const Eigen::VectorXd& b) {
    const auto tensors = AnisotropicTensors(
        domain, {DirectionField::kAroundAxis, Eigen::Vector3d::UnitY(), 1.0, 0.0});
    double along = 0, total = 0;
    for (int e = 0; e < domain.element_count(); ++e) {
      Eigen::Vector3d gradient = Eigen::Vector3d::Zero();
      for (int k = 0; k < 3; ++k) gradient += b[domain.elements()[e][k]] * domain.gradient(e, k);
      along += domain.area(e) * gradient.dot(tensors[e] * gradient);
      total += domain.area(e) * gradient.squaredNorm();
    }
    return along / total;
  };
  std::array<double, 2> shares{};
  for (int anisotropic = 0; anisotropic < 2; ++anisotropic) {
    TurkParameters parameters;
    auto model = MakeTurkModel(parameters);
    SimulationOptions options;
    options.time_step = model->suggested_time_step();
    options.max_steps = 1200;
    if (anisotropic) {
      // Faster diffusion along the rings stretches the pattern into them.
      options.anisotropy =
          Anisotropy{DirectionField::kAroundAxis, Eigen::Vector3d::UnitY(), 4.0, 1.0};
    }
    const SimulationResult result = SimulateReactionDiffusion(*model, domain, options);
    shares[anisotropic] = along_share(result.fields[1]);
  }
  std::printf("gradient energy along the rings: isotropic %.2f, anisotropic %.2f\n", shares[0],
              shares[1]);
  EXPECT_NEAR(shares[0], 0.5, 0.15);
  EXPECT_LT(shares[1], 0.3);
}

// Gray-Scott on Pearson's grid spacing (2.5 / 256) and time step, with Pearson's seed square of
// 20 x 20 cells, on a 64 x 64 periodic grid (0.625 wide, a quarter of Pearson's), 2,000 and
// 4,000 steps (lumped mass, the 5-point scheme): about 1 and 1.5 s.
SimulationResult RunGrayScott(const GrayScottParameters& parameters, double dx, double time_step,
                              int steps, GridShape& grid) {
  grid = GridShape{64, 64, dx};
  const FemDomain domain = FemDomain::PeriodicGrid(grid.width, grid.height, dx);
  auto model = MakeGrayScottModel(parameters);
  SimulationOptions options;
  options.time_step = time_step;
  options.max_steps = steps;
  options.seed = 3;
  options.solver.lumped_mass = true;  // see FemDomain::PeriodicGrid
  return SimulateReactionDiffusion(*model, domain, options);
}

TEST(GrayScottTest, PearsonsParameterSetsLandInTheirRegimes) {
  PHOTOMAT_TEST_DATA_OR_SKIP(file, "reaction-diffusion/Pearson1993.vti");
  const ReadyGrayScottPattern pearson = ReadReadyGrayScott(file);
  // The file's settings: Pearson's "theta", stripes.
  EXPECT_DOUBLE_EQ(pearson.parameters.f, 0.040);
  EXPECT_DOUBLE_EQ(pearson.parameters.k, 0.060);
  EXPECT_DOUBLE_EQ(pearson.parameters.d_a, 2e-5);
  EXPECT_DOUBLE_EQ(pearson.parameters.d_b, 1e-5);
  EXPECT_DOUBLE_EQ(pearson.dx, 2.5 / 256);
  EXPECT_EQ(pearson.width, 256);
  EXPECT_TRUE(pearson.wrap);
  EXPECT_NEAR(pearson.parameters.seed_size, 0.08, 1e-12);

  GrayScottParameters stripes = pearson.parameters;
  stripes.seed_size = pearson.parameters.seed_size * pearson.width / 64.0;  // 20 cells
  GridShape grid;
  const auto theta = RunGrayScott(stripes, pearson.dx, pearson.time_step, 2000, grid);
  const auto theta_shape = MeasureGridPattern(grid, theta.fields[1]);
  // Spots: F = 0.030, K = 0.060 (self-replicating spots, below theta in F on Pearson's map).
  GrayScottParameters spots = stripes;
  spots.f = 0.030;
  const auto spot_run = RunGrayScott(spots, pearson.dx, pearson.time_step, 4000, grid);
  const auto spot_shape = MeasureGridPattern(grid, spot_run.fields[1]);
  std::printf(
      "gray-scott theta: %d components, compactness %.2f, cover %.2f; spots: %d "
      "components, compactness %.2f, cover %.2f\n",
      theta_shape.components, theta_shape.compactness, theta_shape.covered_fraction,
      spot_shape.components, spot_shape.compactness, spot_shape.covered_fraction);
  EXPECT_LE(theta_shape.components, 4);
  EXPECT_LT(theta_shape.compactness, 0.2);  // 0.06 measured
  EXPECT_GT(theta_shape.covered_fraction, 0.2);
  EXPECT_GE(spot_shape.components, 10);
  EXPECT_GT(spot_shape.compactness, 0.35);  // 0.47 measured; a digital disc 0.62
}

TEST(GrayScottTest, ReadyFileErrorsNameTheFile) {
  testing::TempDir dir;
  testing::WriteFile(dir / "bad.vti",
                     "<VTKFile><RD><rule name=\"Gray-Scott\"><param name=\"F\">"
                     "x</param></rule></RD></VTKFile>");
  try {
    ReadReadyGrayScott(dir / "bad.vti");
    FAIL() << "no error";
  } catch (const Error& error) {
    EXPECT_EQ(error.file(), dir / "bad.vti");
  }
  testing::WriteFile(dir / "other.vti",
                     "<VTKFile><RD><rule name=\"Schnakenberg\"/></RD></VTKFile>");
  EXPECT_THROW(ReadReadyGrayScott(dir / "other.vti"), Error);
  testing::WriteFile(dir / "broken.vti", "<VTKFile><RD>");
  EXPECT_THROW(ReadReadyGrayScott(dir / "broken.vti"), Error);
  EXPECT_THROW(ReadReadyGrayScott(dir / "missing.vti"), Error);
}

TEST(OtherModelsTest, BrusselatorAndFitzHughNagumoFormBoundedPatterns) {
  const GridShape grid{48, 48, 0.5};
  const FemDomain domain = FemDomain::PeriodicGrid(grid.width, grid.height, grid.spacing);
  // FitzHugh-Nagumo variant at its defaults: a Turing pattern near 2 pi / (1.5 / (0.2 * 4))^(1/4).
  auto fhn = MakeFitzHughNagumoModel({});
  SimulationOptions options;
  options.time_step = fhn->suggested_time_step();
  options.max_steps = 600;
  options.solver.lumped_mass = true;
  const SimulationResult fhn_result = SimulateReactionDiffusion(*fhn, domain, options);
  const Eigen::VectorXd& a = fhn_result.fields[0];
  const double fhn_theory = 2 * kPi / std::pow(1.5 / (0.2 * 4.0), 0.25);
  const double fhn_wavelength = DominantGridWavelength(grid, a);
  std::printf("fhn: contrast %.2f, wavelength %.2f (linear theory %.2f)\n",
              a.maxCoeff() - a.minCoeff(), fhn_wavelength, fhn_theory);
  EXPECT_GT(a.maxCoeff() - a.minCoeff(), 0.5);
  EXPECT_NEAR(fhn_wavelength, fhn_theory, 0.25 * fhn_theory);

  // Forced Brusselator, standard form with delta = 5: stays bounded; the printed form drifts up.
  for (bool printed : {false, true}) {
    BrusselatorParameters parameters;
    parameters.delta = 5.0;
    parameters.printed_form = printed;
    auto brusselator = MakeBrusselatorModel(parameters);
    SimulationOptions b_options;
    b_options.time_step = brusselator->suggested_time_step();
    b_options.max_steps = 1000;  // 50 time units
    b_options.solver.lumped_mass = true;
    const SimulationResult result = SimulateReactionDiffusion(*brusselator, domain, b_options);
    const double total = (result.fields[0] + result.fields[1]).mean();
    std::printf("brusselator (%s): mean u + v %.2f, u in [%.2f, %.2f]\n",
                printed ? "printed" : "standard", total, result.fields[0].minCoeff(),
                result.fields[0].maxCoeff());
    ASSERT_TRUE(result.fields[0].allFinite());
    if (printed) {
      EXPECT_GT(total, 3.5 + 0.3 * 50);  // c = 0.5 per unit time, less what forcing takes
    } else {
      EXPECT_LT(total, 10.0);
    }
  }
}

TEST(PatternMaterialTest, HeightGradientsNormalsAndTiling) {
  const GridShape grid{32, 16, 1.0};
  Eigen::VectorXd field(32 * 16);
  for (int y = 0; y < 16; ++y) {
    for (int x = 0; x < 32; ++x) field[y * 32 + x] = std::sin(2 * kPi * x / 32.0);
  }
  PatternMaterialOptions options;
  options.relief_pixels = 4.0;
  const Representation material = PatternMaterial(grid, field, options);
  EXPECT_EQ(material.method(), "gradient");
  EXPECT_EQ(material.maps().channel_names()[0], "normal.X");
  EXPECT_EQ(material.maps().channel_names()[5], "albedo.B");
  // Height 4 * (sin + 1) / 2: at x = 0 the slope is 2 * (2 pi / 32) * sinc-ish of the central
  // difference: 2 * sin(2 pi / 32).
  const double slope = 2.0 * std::sin(2 * kPi / 32.0);
  const double nx = -slope / std::sqrt(1 + slope * slope);
  EXPECT_NEAR(material.maps().at(0, 5, 0), nx, 1e-5);  // wraps to x = 31 for its neighbour
  EXPECT_NEAR(material.maps().at(16, 5, 0), -nx, 1e-5);
  EXPECT_NEAR(material.maps().at(8, 5, 0), 0.0, 1e-5);
  // Relit from overhead: albedo times n_z.
  const Image relit = material.Relight(LightDirection::FromVector(0, 0, 1));
  const float nz = material.maps().at(0, 5, 2);
  EXPECT_NEAR(relit.at(0, 5, 0), material.maps().at(0, 5, 3) * nz, 1e-5);
  // And it saves as a map stack.
  testing::TempDir dir;
  SaveRepresentation(dir / "rd.exr", material);
  EXPECT_EQ(LoadRepresentation(dir / "rd.exr").representation.maps().channels(), 6);
}

}  // namespace
}  // namespace photomat
