#pragma once

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
// `mask` (all if empty), by conjugate gradients on the sparse normal equations. Height zero-mean
// over the mask, 0 outside. Throws Error if the mask selects no pixel.
Image IntegratePoisson(const Image& gradients, const Mask& mask = {});

}  // namespace photomat
