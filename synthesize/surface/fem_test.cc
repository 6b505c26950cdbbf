#include "synthesize/surface/fem.h"

#include <gtest/gtest.h>

#include <Eigen/Dense>
#include <cmath>
#include <numbers>

#include "core/random.h"
#include "synthesize/mesh/mesh.h"
#include "synthesize/surface/semi_implicit.h"

namespace photomat {
namespace {

constexpr double kPi = std::numbers::pi;

Eigen::MatrixXd Dense(const SparseMatrixD& m) { return Eigen::MatrixXd(m); }

TEST(FemTest, MassSumsToTheSphereArea) {
  // Level 5: 10,242 vertices, mean edge 0.03 R.
  const double radius = 3.0;
  const FemDomain domain = FemDomain::FromMesh(MakeIcosphere(radius, 5));
  const FemOperators operators(domain);
  const Eigen::VectorXd ones = Eigen::VectorXd::Ones(domain.node_count());
  const double area = 4.0 * kPi * radius * radius;
  const double consistent = ones.dot(operators.mass() * ones);
  EXPECT_NEAR(consistent, area, 0.005 * area);
  EXPECT_NEAR(operators.lumped_mass_vector().sum(), consistent, 1e-9 * area);
  EXPECT_NEAR(ones.dot(operators.lumped_mass() * ones), consistent, 1e-9 * area);
  RecordProperty("area_ratio", std::to_string(consistent / area));
  std::printf("mass: 1'M1 / 4 pi R^2 = %.5f on %d vertices\n", consistent / area,
              domain.node_count());
}

TEST(FemTest, StiffnessIsSymmetricSemidefiniteWithConstantsInItsKernel) {
  const FemDomain domain = FemDomain::FromMesh(MakeTorus(2.0, 0.7, 24, 12));
  const FemOperators operators(domain);
  const Eigen::MatrixXd k = Dense(operators.stiffness());
  EXPECT_LT((k - k.transpose()).cwiseAbs().maxCoeff(), 1e-12);
  EXPECT_LT((k * Eigen::VectorXd::Ones(k.rows())).cwiseAbs().maxCoeff(), 1e-12);
  const Eigen::SelfAdjointEigenSolver<Eigen::MatrixXd> eigen(k);
  EXPECT_GT(eigen.eigenvalues().minCoeff(), -1e-10);
  // The cotangent formula and the gradient form with the identity tensor agree.
  const std::vector<Eigen::Matrix3d> identity(domain.element_count(), Eigen::Matrix3d::Identity());
  EXPECT_LT((Dense(operators.TensorStiffness(identity)) - k).cwiseAbs().maxCoeff(), 1e-12);
}

TEST(FemTest, WeightedMassUsesTheExactLinearIntegrals) {
  const FemDomain domain = FemDomain::FromMesh(MakeIcosphere(1.0, 2));
  const FemOperators operators(domain);
  const int n = domain.node_count();
  SparseMatrixD ones_weighted = operators.ZeroPattern();
  operators.AddWeightedMass(ones_weighted, Eigen::VectorXd::Ones(n), 1.0, false);
  EXPECT_LT((Dense(ones_weighted) - Dense(operators.mass())).cwiseAbs().maxCoeff(), 1e-14);
  // 1' M[c] 1 = integral of c = 1' M c, for a linear field c.
  Random random(3);
  Eigen::VectorXd c(n), u(n), w(n);
  for (int i = 0; i < n; ++i) {
    c[i] = random.Uniform(-1, 1);
    u[i] = random.Uniform(-1, 1);
    w[i] = random.Uniform(-1, 1);
  }
  SparseMatrixD weighted = operators.ZeroPattern();
  operators.AddWeightedMass(weighted, c, 1.0, false);
  const Eigen::VectorXd ones = Eigen::VectorXd::Ones(n);
  EXPECT_NEAR(ones.dot(weighted * ones), ones.dot(operators.mass() * c), 1e-12);
  // Symmetric in its three arguments: u' M[c] w = c' M[u] w.
  SparseMatrixD weighted_u = operators.ZeroPattern();
  operators.AddWeightedMass(weighted_u, u, 1.0, false);
  EXPECT_NEAR(u.dot(weighted * w), c.dot(weighted_u * w), 1e-12);
}

TEST(FemTest, PeriodicGridIsTheFivePointLaplacian) {
  const FemDomain domain = FemDomain::PeriodicGrid(6, 5, 0.5);
  const FemOperators operators(domain);
  EXPECT_NEAR(domain.total_area(), 6 * 5 * 0.25, 1e-12);
  const Eigen::MatrixXd k = Dense(operators.stiffness());
  for (int node = 0; node < 30; ++node) {
    const int x = node % 6, y = node / 6;
    EXPECT_NEAR(k(node, node), 4.0, 1e-12);
    EXPECT_NEAR(k(node, y * 6 + (x + 1) % 6), -1.0, 1e-12);
    EXPECT_NEAR(k(node, y * 6 + (x + 5) % 6), -1.0, 1e-12);
    EXPECT_NEAR(k(node, ((y + 1) % 5) * 6 + x), -1.0, 1e-12);
    EXPECT_NEAR(k(node, ((y + 1) % 5) * 6 + (x + 1) % 6), 0.0, 1e-12);
    EXPECT_NEAR(operators.lumped_mass_vector()[node], 0.25, 1e-12);
  }
}

// Real spherical harmonics of degree l <= 4 are not needed as such: the generalized eigenvalues of
// K x = lambda M x on a sphere must come in groups of 2l + 1 near l (l + 1) / R^2.
// Dense solves keep it fast: levels 2 and 3 (162 and 642 vertices) show the O(h^2) convergence.
TEST(FemTest, LaplacianEigenvaluesOnASphereAreLTimesLPlusOneOverRSquared) {
  const double radius = 2.0;
  std::array<std::array<double, 5>, 2> worst{};  // per level, per l
  for (int level : {2, 3}) {
    const FemDomain domain = FemDomain::FromMesh(MakeIcosphere(radius, level));
    const FemOperators operators(domain);
    const Eigen::GeneralizedSelfAdjointEigenSolver<Eigen::MatrixXd> eigen(
        Dense(operators.stiffness()), Dense(operators.mass()), Eigen::EigenvaluesOnly);
    const Eigen::VectorXd values = eigen.eigenvalues();
    EXPECT_NEAR(values[0], 0.0, 1e-9);
    int index = 1;
    for (int l = 1; l <= 4; ++l) {
      const double expected = l * (l + 1) / (radius * radius);
      double& w = worst[level - 2][l];
      for (int m = 0; m < 2 * l + 1; ++m, ++index) {
        w = std::max(w, std::abs(values[index] / expected - 1.0));
      }
      std::printf("level %d, l = %d: expected %.4f, group of %d in %.4f .. %.4f (worst %.2f %%)\n",
                  level, l, expected, 2 * l + 1, values[index - 2 * l - 1], values[index - 1],
                  100.0 * w);
    }
    // The group of 2l + 1 is complete: the next eigenvalue is near the l = 5 value.
    EXPECT_GT(values[index], 0.97 * 30.0 / (radius * radius));
  }
  for (int l = 1; l <= 4; ++l) {
    EXPECT_LT(worst[1][l], 0.01 * l) << "l = " << l;           // 0.6, 1.2, 2.1, 3.2 %
    EXPECT_LT(worst[1][l], 0.3 * worst[0][l]) << "l = " << l;  // halving h: error / 4
  }
}

// u = Y_2,0 ~ 3z^2 - r^2 decays as exp(-D l(l+1) t / R^2); the integral of u is conserved.
TEST(FemTest, HeatEquationDecayRateConvergesAndTheIntegralIsConserved) {
  const double radius = 1.0, diffusion = 0.5, end_time = 0.4;
  const FemDomain domain = FemDomain::FromMesh(MakeIcosphere(radius, 4));  // 2562 vertices
  const FemOperators operators(domain);
  const int n = domain.node_count();
  Eigen::VectorXd mode(n);
  for (int i = 0; i < n; ++i) {
    const auto& p = domain.node_positions()[i];
    mode[i] = 3.0 * p.z() * p.z() - p.squaredNorm();
  }
  const double exact_rate = diffusion * 6.0 / (radius * radius);
  SolverOptions solver;
  solver.tolerance = 1e-12;
  std::vector<double> errors;
  for (int steps : {20, 40, 80}) {
    Eigen::VectorXd u = mode;
    GeneralEquation heat;
    heat.c0 = Eigen::VectorXd::Constant(1, diffusion);
    heat.c2 = Eigen::VectorXd::Zero(n);
    heat.c3 = Eigen::VectorXd::Zero(n);
    for (int s = 0; s < steps; ++s) SemiImplicitStep(operators, heat, end_time / steps, solver, u);
    // Amplitude along the mode in the mass inner product.
    const double amplitude = mode.dot(operators.mass() * u) / mode.dot(operators.mass() * mode);
    const double rate = -std::log(amplitude) / end_time;
    errors.push_back(std::abs(rate / exact_rate - 1.0));
    std::printf("heat: %d steps, decay rate %.4f (exact %.4f)\n", steps, rate, exact_rate);
  }
  EXPECT_LT(errors.back(), 0.03);
  // First order in tau: halving the step roughly halves the error (spatial error is smaller).
  EXPECT_LT(errors[1], 0.65 * errors[0]);
  EXPECT_LT(errors[2], 0.65 * errors[1]);

  Random random(11);
  Eigen::VectorXd u(n);
  for (int i = 0; i < n; ++i) u[i] = random.Uniform(0.0, 1.0);
  const double before = operators.Load(u, false).sum();
  GeneralEquation heat;
  heat.c0 = Eigen::VectorXd::Constant(1, diffusion);
  heat.c2 = Eigen::VectorXd::Zero(n);
  heat.c3 = Eigen::VectorXd::Zero(n);
  for (int s = 0; s < 10; ++s) SemiImplicitStep(operators, heat, 0.05, solver, u);
  EXPECT_NEAR(operators.Load(u, false).sum(), before, 1e-9 * before);
  EXPECT_LT(u.maxCoeff() - u.minCoeff(), 0.5);  // and it did diffuse
}

TEST(FemTest, PerNodeC0FormMatchesTheMultipliedForm) {
  const FemDomain domain = FemDomain::FromMesh(MakeIcosphere(1.0, 2));
  const FemOperators operators(domain);
  const int n = domain.node_count();
  Random random(5);
  Eigen::VectorXd u0(n), c2(n), c3(n);
  for (int i = 0; i < n; ++i) {
    u0[i] = random.Uniform(0, 1);
    c2[i] = -0.5;
    c3[i] = 0.2;
  }
  SolverOptions solver;
  solver.tolerance = 1e-13;
  solver.lumped_mass = true;  // with lumped mass the divided form is exactly the same equation
  GeneralEquation constant{Eigen::VectorXd::Constant(1, 2.0), nullptr, c2, c3};
  GeneralEquation per_node{Eigen::VectorXd::Constant(n, 2.0), nullptr, c2, c3};
  Eigen::VectorXd a = u0, b = u0;
  SemiImplicitStep(operators, constant, 0.1, solver, a);
  SemiImplicitStep(operators, per_node, 0.1, solver, b);
  EXPECT_LT((a - b).cwiseAbs().maxCoeff(), 1e-10);
}

}  // namespace
}  // namespace photomat
