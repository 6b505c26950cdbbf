#pragma once

#include <Eigen/Core>
#include <Eigen/SparseCore>
#include <span>
#include <vector>

#include "synthesize/surface/fem.h"

namespace photomat {

// The paper's generalised equation (Bajaj, Zhang and Xu, eq. 2)
//
//   du/dt = C0 div(C1 grad u) + C2 u + C3
//
// with its semi-implicit backward-Euler step (eqs. 5-11): diffusion and the linear reaction C2 u
// at step n+1, every coefficient (including the other species inside C2, and the source C3)
// frozen at step n. Solved by preconditioned conjugate gradients, warm-started from u^n.

// The coefficients at step n.
struct GeneralEquation {
  // C0: one value (constant, may be 0: no diffusion, the Brusselator's delta = 0) or one per node
  // (all positive; a(x)^mu of geometric diffusion).
  Eigen::VectorXd c0 = Eigen::VectorXd::Ones(1);
  // C1 K: the diffusion stiffness (grad phi_i, C1 grad phi_j) on the operators' pattern; nullptr
  // means C1 = 1 (the cotangent stiffness).
  const SparseMatrixD* c1_stiffness = nullptr;
  // C2 and C3, one value per node (piecewise linear).
  Eigen::VectorXd c2;
  Eigen::VectorXd c3;
};

enum class Preconditioner { kJacobi, kIncompleteCholesky };

struct SolverOptions {
  // Relative residual |A u - b| / |b| at which conjugate gradients stop.
  double tolerance = 1e-8;
  int max_iterations = 1000;
  Preconditioner preconditioner = Preconditioner::kJacobi;
  // Lumped (diagonal) mass instead of the consistent one, for the time derivative and C2, C3.
  bool lumped_mass = false;
};

struct StepReport {
  int iterations = 0;
  double residual = 0.0;  // relative, as reached
};

// Builds and solves the step's system. With constant C0 it is multiplied through (spec 2.4, the
// form of the paper's eqs. 14-15, valid for C0 = 0):
//   (M + tau (C0 K[C1] - M[C2])) u^{n+1} = M u^n + tau M C3
// With C0 per node it is the paper's form divided by C0 (eqs. 7-11):
//   (M[1/C0] + tau (K[C1] - M[C2/C0])) u^{n+1} = M[1/C0] u^n + tau M (C3/C0)
// Throws Error if conjugate gradients do not converge (the matrix is not positive definite: the
// time step is too long for the reaction, spec 3.1) or the result is not finite.
StepReport SemiImplicitStep(const FemOperators& operators, const GeneralEquation& equation,
                            double tau, const SolverOptions& options, Eigen::VectorXd& u);

}  // namespace photomat
