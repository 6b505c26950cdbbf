#pragma once

#include <Eigen/Core>
#include <vector>

#include "synthesize/surface/fem.h"

namespace photomat {

// Measurements of a pattern's scale: the checks of spec section 9 and what `photomat rd` reports.

// Power of the field (mean removed) per spherical-harmonic degree l = 0..max_degree, for a domain
// whose nodes lie on a sphere around the origin: P_l = sum_m c_lm^2 with c_lm = the mass-weighted
// projection onto the orthonormal real harmonic Y_lm (node directions, so any radius works).
std::vector<double> SphericalHarmonicPower(const FemOperators& operators,
                                           const Eigen::VectorXd& field, int max_degree);

// The degree of largest power (l >= 1) and its wavelength 2 pi R / sqrt(l (l + 1)) on a sphere of
// radius R.
struct SphereSpectrumPeak {
  int degree = 0;
  double wavelength = 0.0;
};
SphereSpectrumPeak DominantSphericalDegree(const std::vector<double>& power, double radius);

// Dominant wavelength of a field on a periodic grid domain (spacing units): the power-weighted
// mean of the radial wavenumber over the spectrum's peak ring (the radial bins within a factor 2 of
// the peak), from the 2-D DFT (OpenCV) of the field with its mean removed.
double DominantGridWavelength(const GridShape& grid, const Eigen::VectorXd& field);

// sqrt(u' K u / u' M u) for u the field minus its mean: the root-mean-square wavenumber, a
// wavelength 2 pi / k_rms that works on any mesh (harmonics of non-sinusoidal patterns bias it
// short).
double RmsWavenumber(const FemOperators& operators, const Eigen::VectorXd& field);

}  // namespace photomat

namespace photomat {

// The shape of a pattern on a periodic grid: the field thresholded at the middle of its range,
// split into 4-connected components (wrapping at the edges). Spots are many compact components,
// stripes and labyrinths few elongated ones.
struct GridPatternShape {
  int components = 0;
  // Share of nodes above the threshold.
  double covered_fraction = 0.0;
  // Area-weighted mean of the isoperimetric quotient 4 pi A / P^2 of the components, with P the
  // count of grid edges on their boundary: about 0.62 for a digital disc (pi^2 / 16), near 0 for
  // a long stripe.
  double compactness = 0.0;
};
GridPatternShape MeasureGridPattern(const GridShape& grid, const Eigen::VectorXd& field);

}  // namespace photomat
