#pragma once

#include <memory>
#include <vector>

#include "core/image.h"

namespace photomat {

// Between normals, gradients and heights. Gradients are p = ds/dx and q = ds/dy in the light frame
// (x right, y up), so q points toward image row 0; heights are in pixel units.

// (p, q) = (-nx / nz, -ny / nz) from unit normals (channels 0..2), as a 2-channel image "p", "q".
// Normals with nz below `min_nz` (grazing or facing away) are clamped to that nz first, so slopes
// stay finite (IMPLEMENTER CHOICE: 0.05, about 87 degrees).
Image GradientsFromNormals(const Image& normals, double min_nz = 0.05);

// Unit normals (-p, -q, 1) / |.| from a 2-channel gradient image.
Image NormalsFromGradients(const Image& gradients);

// Frankot-Chellappa (thesis eq. 4.5.5): the periodic height whose spectral gradient is closest to
// (p, q) in least squares, S = (-j u P - j v Q) / (u^2 + v^2), S(0, 0) = 0 (zero mean). Exact for
// integrable, periodic, band-limited fields; use on tileable samples.
Image IntegrateFrankotChellappa(const Image& gradients);

// The integrable field nearest to (p, q) (the same projection, transformed back: P' = juS,
// Q' = jvS), for gradients that must integrate to a height without residual (synthesis output).
Image ProjectToIntegrable(const Image& gradients);

// Least-squares (Poisson) integration for non-periodic samples: minimises the squared difference
// between height differences of neighbouring pixels and their mean gradients, over the pixels of
// `mask` (all if empty). Height zero-mean over the mask, 0 outside. Throws Error if the mask
// selects no pixel. PoissonIntegrator(mask).Integrate(gradients).
Image IntegratePoisson(const Image& gradients, const Mask& mask = {});

// That integration's system for one mask. Its matrix (the normal equations: the graph Laplacian
// of the mask's 4-neighbour pairs, plus 1e-9 on the diagonal, which fixes the free constant of
// each connected piece at a zero mean without biasing the shape measurably) depends on the mask
// alone, so it is set up once and serves any gradient field over that mask: the tiled
// integration's full tiles share one (represent/surface/tiled_poisson.h).
// Solver (IMPLEMENTER CHOICE): up to kDirectPoissonUnknowns unknowns a sparse Cholesky (LDL^T,
// Eigen's SimplicialLDLT with AMD ordering) factorised in the constructor, each Integrate then two
// triangular solves (a 320 x 320 tile: 0.4 s to factorise, 13 ms to solve, against 1.4 s of
// conjugate gradients per field, measured); above it conjugate gradients (diagonal preconditioner,
// relative residual 1e-10), whose memory stays linear in the unknowns where the factor's would
// not (524 MB for 1024 x 1024, 127 MB at the limit). Integrate is thread-safe.
inline constexpr int kDirectPoissonUnknowns = 1 << 18;
enum class PoissonSolver { kAuto, kDirect, kConjugateGradients };
class PoissonIntegrator {
 public:
  // Over the pixels `mask` sets (its size the fields'); kAuto chooses the solver as above. Throws
  // Error if it selects no pixel, or if the factorisation fails.
  explicit PoissonIntegrator(const Mask& mask, PoissonSolver solver = PoissonSolver::kAuto);
  ~PoissonIntegrator();
  PoissonIntegrator(PoissonIntegrator&&) noexcept;
  PoissonIntegrator& operator=(PoissonIntegrator&&) noexcept;

  int width() const { return width_; }
  int height() const { return height_; }
  int unknowns() const { return unknowns_; }
  bool direct() const { return direct_; }

  // The height of `gradients` (channels p, q; the mask's size). Throws Error for another size or
  // a solve that does not converge.
  Image Integrate(const Image& gradients) const;

 private:
  struct System;
  int width_ = 0;
  int height_ = 0;
  int unknowns_ = 0;
  bool direct_ = true;
  std::vector<int> index_;  // per pixel its unknown, -1 outside the mask
  std::unique_ptr<const System> system_;
};

}  // namespace photomat
