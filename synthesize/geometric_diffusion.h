#pragma once

#include <Eigen/Core>
#include <cstdint>
#include <vector>

#include "core/progress.h"
#include "synthesize/mesh.h"
#include "synthesize/reaction_diffusion.h"
#include "synthesize/semi_implicit.h"

namespace photomat {

// Anisotropic geometric diffusion (Bajaj, Zhang and Xu, section 4.2; Bajaj and Xu 2003):
//
//   dx/dt - a(x)^mu div(a(x)^(1 - mu) D(x) grad x) = 0
//
// on the vertex positions, one semi-implicit step at a time with the coefficients frozen at step n
// (eq. 21), the three coordinates sharing one matrix. D damps diffusion across directions of high
// principal curvature (sharp edges) and keeps it along them:
//
//   D = alpha g(k1) e1 e1^T + beta g(k2) e2 e2^T + N N^T,
//   g(k) = 1 for |k| <= lambda, 1 / (1 + (|k| - lambda)^2 / lambda^2) above
//
// IMPLEMENTER CHOICES (the paper gives no values; spec 4): a(x) = 1 (so mu has no effect),
// alpha = beta = 1, lambda = 1 x the median absolute principal curvature of the current mesh
// (1.5 x left noisy fandisk's creases 6.9 degrees rounder after 10 steps, 1 x 3.1), tau = 0.1 x
// (mean edge length)^2 per step, 10 steps; curvature tensors per vertex (below), averaged over
// each triangle and decomposed in its plane.

// Principal curvatures and directions at a vertex (|k1| >= |k2|), with the unit normal.
struct CurvatureFrame {
  double k1 = 0.0;
  double k2 = 0.0;
  Eigen::Vector3d e1 = Eigen::Vector3d::UnitX();
  Eigen::Vector3d e2 = Eigen::Vector3d::UnitY();
  Eigen::Vector3d normal = Eigen::Vector3d::UnitZ();
};
// From the normal-curvature samples 2 n.(v_j - v_i) / |v_j - v_i|^2 along each edge (Taubin 1995),
// weighted by the adjacent triangles' areas, fitted by least squares with the second fundamental
// form in the tangent plane (Taubin's own 3 m1 - m2 formula assumes evenly spread edge directions
// and splits k1, k2 wrongly on regular grids). Signs follow the outward normal (negative on a
// convex surface); only magnitudes matter here.
std::vector<CurvatureFrame> EstimateCurvatures(const TriangleMesh& mesh);

// The edge-stopping function g of eq. 20 (|k|, so concave edges stop diffusion too).
double EdgeStopping(double curvature, double lambda);

struct GeometricDiffusionOptions {
  int steps = 10;
  // Time step in units of (mean edge length)^2 of the input mesh.
  double time_step_factor = 0.1;
  double alpha = 1.0;
  double beta = 1.0;
  // lambda = lambda_factor x median |principal curvature|.
  double lambda_factor = 1.0;
  // g = 1 everywhere: plain (isotropic) Laplace-Beltrami smoothing, for comparison.
  bool isotropic = false;
  SolverOptions solver = {1e-6, 4000, Preconditioner::kIncompleteCholesky, false};
};

// One step on `mesh` (positions change, triangles do not) with time step `tau`. Returns the
// conjugate-gradient iterations of the three coordinates.
int GeometricDiffusionStep(TriangleMesh& mesh, double tau,
                           const GeometricDiffusionOptions& options);

// Runs options.steps steps; returns the smoothed mesh.
TriangleMesh SmoothMeshAnisotropic(const TriangleMesh& mesh,
                                   const GeometricDiffusionOptions& options,
                                   Progress* progress = nullptr);

// The coupled system (paper section 4.3, schedule of spec 5): every step first smooths the mesh
// (during the first geometry.steps steps), rebuilds the elements on the new geometry, then takes
// one reaction-diffusion step there. One-way coupling: the pattern does not move the surface.
struct CoupledResult {
  TriangleMesh mesh;
  SimulationResult pattern;
};
CoupledResult SimulateCoupled(const TriangleMesh& mesh, ReactionDiffusionModel& model,
                              const SimulationOptions& options,
                              const GeometricDiffusionOptions& geometry,
                              Progress* progress = nullptr);

}  // namespace photomat
