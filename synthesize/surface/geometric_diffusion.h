#pragma once

#include <Eigen/Core>
#include <cstdint>
#include <vector>

#include "core/progress.h"
#include "synthesize/mesh/mesh.h"
#include "synthesize/surface/reaction_diffusion.h"
#include "synthesize/surface/semi_implicit.h"

namespace photomat {

// Anisotropic geometric diffusion (Bajaj, Zhang and Xu, section 4.2; Bajaj and Xu 2003):
//
//   dx/dt - a(x)^mu div(a(x)^(1 - mu) D(x) grad x) = 0
//
// on the vertex positions, one semi-implicit step at a time with the coefficients frozen at step n
// (eq. 21). D damps diffusion across directions of high
// principal curvature (sharp edges) and keeps it along them:
//
//   D = alpha g(k1) e1 e1^T + beta g(k2) e2 e2^T + N N^T,
//   g(k) = 1 for |k| <= lambda, 1 / (1 + (|k| - lambda)^2 / lambda^2) above
//
// The paper's own recipe (Bajaj and Xu 2003's D from principal curvatures of the noisy mesh, one
// scalar system shared by x, y, z; lambda = lambda_factor x the median |k|, a = 1, alpha = beta =
// 1) is kept as FeatureDetection::kRawCurvature. It denoises, but
// on a noisy fandisk (noise 0.2 x mean edge) it leaves only 40 % of the sharp edges within
// 5 degrees of their dihedral angle (per-edge median change 6.3 degrees, edges rounded by 3 on
// average): curvature estimated from noisy vertices cannot tell noise from creases, and a scalar
// D that lets any diffusion across a crease moves the crease's vertices along both faces' normals.
//
// IMPLEMENTER CHOICE, the default (FeatureDetection::kFilteredNormals), the same equation with
// a tensor that acts on the coordinates as well as on the gradient directions:
//
//   - features are found on bilaterally filtered face normals (Zheng et al. 2011: 10 passes,
//     face neighbours sharing a vertex, spatial sigma 1.5 x mean centroid spacing, range sigma
//     following the noise, below), re-filtered at every step on the current mesh;
//   - per triangle, the shape operator fitted to the filtered vertex normals (dn = S de on its
//     three edges) gives the across-crease direction d1 (larger |k|) and the along direction d2,
//     with g(k) of eq. 20 and lambda = 0.05 / mean edge length (normals turning by 3 degrees per
//     edge: a scale-free threshold, unlike a multiple of the noisy median);
//   - the element tensor is  sum_k d_k d_k^T (x) [n n^T + w g(k_k) (I - n n^T)],  n the filtered
//     face normal: the component of position along n diffuses in every direction, which pulls
//     each triangle flat onto the plane its filtered normal asks for (the vertex update of Sun et
//     al. 2007, here as an implicit step), while the in-plane (membrane) diffusion, weight
//     w = 0.1, stops across creases and only evens out triangle shapes;
//   - lumped mass, a = 1 (mu has no effect), alpha = beta = 1 on g(k1), g(k2), tau = 0.2 x
//     (mean edge length)^2, 20 steps by default (tau = 0.1 left more creases rounded: fandisk
//     88.8..92.4 % within 5 degrees over four noise seeds, icosahedron 73.5..83.5 %; but smooth
//     surfaces flatten a little more: a noisy sphere's distance x 0.33 instead of x 0.23).
//
// Measured with noise 0.2 x mean edge, over four noise seeds each: fandisk's 722 sharp edges
// 90.2..93.8 % within 5 degrees of their dihedral angle (median change 1.3..1.6 degrees, mean
// distance to the clean surface x 0.21..0.23; at seed 5 the 45 misses are 18 of the 55 creases
// under 80 degrees and 27 of the 667 near 90); faceted cubes 96.4..100 %, icosahedron (41.8 degree
// creases) 80.4..89.4 %; with noise 0.1 x mean edge every edge of both polyhedra (max change 3.4
// degrees).

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

// Bilateral filtering of face normals (Zheng et al. 2011): each pass replaces a face's normal by
// the normalised sum over the faces sharing a vertex with it of area x exp(-|c_i - c_j|^2 / 2
// sigma_s^2) x exp(-|n_i - n_j|^2 / 2 sigma_r^2) x n_j (c the centroids).
//
// IMPLEMENTER CHOICE: sigma_r follows the noise, sigma_r = min(range_sigma, noise_factor x the
// median |n_i - n_j| over the mesh's edges) (creases are a minority of edges, so the median
// measures noise plus smooth curvature), at least 0.02. A fixed 0.25 lets each pass leak a little
// across a 40 degree crease (weight exp(-4)); re-filtered at every smoothing step, the leaks
// compound and round the crease off, even on an almost clean mesh (a faceted icosahedron with
// noise 0.05 x edge kept 15 % of its edges within 5 degrees; with the adaptive sigma_r, 100 %).
struct NormalFilterOptions {
  int iterations = 10;
  // sigma_s in units of the mean distance between the centroids of adjacent faces.
  double spatial_factor = 1.5;
  // Upper bound of sigma_r on |n_i - n_j| (0.25: normals 14 degrees apart weigh exp(-0.5)).
  double range_sigma = 0.25;
  // sigma_r = min(range_sigma, noise_factor x median |n_i - n_j|); 0: sigma_r = range_sigma.
  double noise_factor = 3.0;
};
std::vector<Eigen::Vector3d> FilterFaceNormals(const TriangleMesh& mesh,
                                               const NormalFilterOptions& options);

enum class FeatureDetection {
  kFilteredNormals,  // the default (above)
  kRawCurvature,     // the paper's: vertex curvature tensors of the current mesh, scalar D
};

struct GeometricDiffusionOptions {
  FeatureDetection detection = FeatureDetection::kFilteredNormals;
  int steps = 20;
  // Time step in units of (mean edge length)^2 of the input mesh.
  double time_step_factor = 0.2;
  double alpha = 1.0;  // weight of g(k1), across the feature
  double beta = 1.0;   // weight of g(k2), along it
  // kFilteredNormals: lambda = crease_curvature / (mean edge length of the current mesh).
  double crease_curvature = 0.05;
  NormalFilterOptions normal_filter;
  // kFilteredNormals: weight w of the in-plane (membrane) diffusion against the normal one.
  double tangential_weight = 0.1;
  // kRawCurvature: lambda = lambda_factor x median |principal curvature|.
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
