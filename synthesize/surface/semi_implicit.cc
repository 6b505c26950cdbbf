#include "synthesize/surface/semi_implicit.h"

#include <fmt/format.h>

#include <Eigen/IterativeLinearSolvers>

#include "core/error.h"

namespace photomat {
namespace {

template <typename Solver>
StepReport Solve(Solver& solver, const SparseMatrixD& system, const Eigen::VectorXd& rhs,
                 const SolverOptions& options, Eigen::VectorXd& u) {
  // A species that has died out (Gray-Scott's b outside the pattern) decays toward zero through
  // denormal numbers, where a relative residual means nothing: its solution is zero.
  if (rhs.lpNorm<Eigen::Infinity>() < 1e-100) {
    u.setZero();
    return {};
  }
  solver.setTolerance(options.tolerance);
  solver.setMaxIterations(options.max_iterations);
  solver.compute(system);
  if (solver.info() != Eigen::Success) {
    throw Error(
        "semi-implicit step: the preconditioner failed (the system matrix is not positive "
        "definite; shorten the time step)");
  }
  const Eigen::VectorXd next = solver.solveWithGuess(rhs, u);
  StepReport report{static_cast<int>(solver.iterations()), solver.error()};
  if (solver.info() != Eigen::Success || !next.allFinite()) {
    throw Error(fmt::format(
        "semi-implicit step: conjugate gradients did not converge ({} iterations, residual "
        "{:.3g}); "
        "the system is not positive definite when tau * C2 is too large: shorten the time step",
        report.iterations, report.residual));
  }
  u = next;
  return report;
}

}  // namespace

StepReport SemiImplicitStep(const FemOperators& operators, const GeneralEquation& equation,
                            double tau, const SolverOptions& options, Eigen::VectorXd& u) {
  const int n = operators.domain().node_count();
  if (u.size() != n || equation.c2.size() != n || equation.c3.size() != n ||
      (equation.c0.size() != 1 && equation.c0.size() != n)) {
    throw Error("semi-implicit step: a field does not have one value per node");
  }
  if (!(tau > 0.0)) throw Error(fmt::format("time step must be positive, not {}", tau));
  const bool lumped = options.lumped_mass;
  const SparseMatrixD& stiffness =
      equation.c1_stiffness ? *equation.c1_stiffness : operators.stiffness();
  SparseMatrixD system = operators.ZeroPattern();
  Eigen::VectorXd rhs;
  if (equation.c0.size() == 1) {
    const double c0 = equation.c0[0];
    if (!(c0 >= 0.0)) throw Error("C0 must not be negative");
    const SparseMatrixD& mass = operators.Mass(lumped);
    Eigen::Map<Eigen::VectorXd> values(system.valuePtr(), system.nonZeros());
    values =
        Eigen::Map<const Eigen::VectorXd>(mass.valuePtr(), mass.nonZeros()) +
        tau * c0 * Eigen::Map<const Eigen::VectorXd>(stiffness.valuePtr(), stiffness.nonZeros());
    operators.AddWeightedMass(system, equation.c2, -tau, lumped);
    rhs = mass * u + tau * operators.Load(equation.c3, lumped);
  } else {
    if (!(equation.c0.minCoeff() > 0.0)) throw Error("a per-node C0 must be positive everywhere");
    const Eigen::VectorXd inverse = equation.c0.cwiseInverse();
    Eigen::Map<Eigen::VectorXd>(system.valuePtr(), system.nonZeros()) =
        tau * Eigen::Map<const Eigen::VectorXd>(stiffness.valuePtr(), stiffness.nonZeros());
    SparseMatrixD weighted = operators.ZeroPattern();
    operators.AddWeightedMass(weighted, inverse, 1.0, lumped);
    Eigen::Map<Eigen::VectorXd>(system.valuePtr(), system.nonZeros()) +=
        Eigen::Map<const Eigen::VectorXd>(weighted.valuePtr(), weighted.nonZeros());
    operators.AddWeightedMass(system, equation.c2.cwiseProduct(inverse), -tau, lumped);
    rhs = weighted * u + tau * operators.Load(equation.c3.cwiseProduct(inverse), lumped);
  }
  if (options.preconditioner == Preconditioner::kJacobi) {
    Eigen::ConjugateGradient<SparseMatrixD, Eigen::Lower | Eigen::Upper,
                             Eigen::DiagonalPreconditioner<double>>
        solver;
    return Solve(solver, system, rhs, options, u);
  }
  Eigen::ConjugateGradient<SparseMatrixD, Eigen::Lower | Eigen::Upper,
                           Eigen::IncompleteCholesky<double>>
      solver;
  return Solve(solver, system, rhs, options, u);
}

}  // namespace photomat
