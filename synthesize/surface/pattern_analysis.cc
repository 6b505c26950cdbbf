#include "synthesize/surface/pattern_analysis.h"

#include <fmt/format.h>

#include <cmath>
#include <complex>
#include <numbers>

#include "core/error.h"
#include "core/fft.h"

namespace photomat {

std::vector<double> SphericalHarmonicPower(const FemOperators& operators,
                                           const Eigen::VectorXd& field, int max_degree) {
  const FemDomain& domain = operators.domain();
  if (field.size() != domain.node_count() || max_degree < 0 || max_degree > 200) {
    throw Error("spherical harmonic power: one value per node and degrees 0..200 needed");
  }
  const Eigen::VectorXd mass = operators.lumped_mass_vector();
  const double mean = mass.dot(field) / mass.sum();
  // Quadrature weights: mass times the field (the projection (u, Y_lm) in the lumped product).
  const Eigen::VectorXd weighted = mass.cwiseProduct((field.array() - mean).matrix());
  const int lmax = max_degree;
  // c[l][m] accumulates the cosine (m >= 0) and sine (m > 0) coefficients.
  std::vector<std::vector<double>> cos_c(lmax + 1, std::vector<double>(lmax + 1, 0.0));
  std::vector<std::vector<double>> sin_c = cos_c;
  std::vector<double> p(lmax + 1);
  for (int i = 0; i < domain.node_count(); ++i) {
    const Eigen::Vector3d d = domain.node_positions()[i].normalized();
    const double x = std::clamp(d.z(), -1.0, 1.0);
    const double sine = std::sqrt(std::max(0.0, 1.0 - x * x));
    const double phi = std::atan2(d.y(), d.x());
    // Fully normalised associated Legendre functions by the standard stable recurrences.
    double pmm = 1.0 / std::sqrt(4.0 * std::numbers::pi);
    for (int m = 0; m <= lmax; ++m) {
      if (m > 0) pmm *= -std::sqrt((2.0 * m + 1.0) / (2.0 * m)) * sine;
      p[m] = pmm;
      if (m + 1 <= lmax) p[m + 1] = std::sqrt(2.0 * m + 3.0) * x * pmm;
      for (int l = m + 2; l <= lmax; ++l) {
        const double a = std::sqrt((4.0 * l * l - 1.0) / (static_cast<double>(l) * l - m * m));
        const double b =
            std::sqrt(((l - 1.0) * (l - 1.0) - m * m) / (4.0 * (l - 1.0) * (l - 1.0) - 1.0));
        p[l] = a * (x * p[l - 1] - b * p[l - 2]);
      }
      const double scale = m == 0 ? 1.0 : std::sqrt(2.0);
      const double c = std::cos(m * phi) * scale * weighted[i];
      const double s = std::sin(m * phi) * scale * weighted[i];
      for (int l = m; l <= lmax; ++l) {
        cos_c[l][m] += c * p[l];
        sin_c[l][m] += s * p[l];
      }
    }
  }
  std::vector<double> power(lmax + 1, 0.0);
  for (int l = 0; l <= lmax; ++l) {
    for (int m = 0; m <= l; ++m) power[l] += cos_c[l][m] * cos_c[l][m] + sin_c[l][m] * sin_c[l][m];
  }
  return power;
}

SphereSpectrumPeak DominantSphericalDegree(const std::vector<double>& power, double radius) {
  SphereSpectrumPeak peak;
  double best = -1.0;
  for (std::size_t l = 1; l < power.size(); ++l) {
    if (power[l] > best) {
      best = power[l];
      peak.degree = static_cast<int>(l);
    }
  }
  if (peak.degree > 0) {
    peak.wavelength = 2.0 * std::numbers::pi * radius /
                      std::sqrt(static_cast<double>(peak.degree) * (peak.degree + 1));
  }
  return peak;
}

double DominantGridWavelength(const GridShape& grid, const Eigen::VectorXd& field) {
  if (field.size() != static_cast<Eigen::Index>(grid.width) * grid.height) {
    throw Error("grid wavelength: one value per grid node needed");
  }
  const double mean = field.mean();
  std::vector<double> values(field.size());
  for (Eigen::Index i = 0; i < field.size(); ++i) values[i] = field[i] - mean;
  const RealFft2d<double> fft(grid.width, grid.height);
  std::vector<std::complex<double>> spectrum(fft.spectrum_size());
  fft.Forward(values, spectrum);
  // Radial bins of the wavenumber in cycles per domain width (square cells assumed per axis). The
  // half spectrum of a real field: every column but 0 and width / 2 stands for a conjugate pair.
  const int bins = std::max(grid.width, grid.height);
  std::vector<double> power(bins, 0.0), weighted_k(bins, 0.0);
  const int half = fft.spectrum_width();
  for (int y = 0; y < grid.height; ++y) {
    for (int x = 0; x < half; ++x) {
      const double fx = x / (grid.width * grid.spacing);
      const double fy = (y <= grid.height / 2 ? y : y - grid.height) / (grid.height * grid.spacing);
      const double f = std::hypot(fx, fy);  // cycles per length unit
      const double pairs = (x == 0 || 2 * x == grid.width) ? 1.0 : 2.0;
      const double p = pairs * std::norm(spectrum[static_cast<std::size_t>(y) * half + x]);
      const int bin = static_cast<int>(std::lround(f * bins * grid.spacing));
      if (bin <= 0 || bin >= bins) continue;
      power[bin] += p;
      weighted_k[bin] += p * f;
    }
  }
  int peak = 1;
  for (int b = 1; b < bins; ++b) {
    if (power[b] > power[peak]) peak = b;
  }
  double sum_p = 0.0, sum_pf = 0.0;
  for (int b = 1; b < bins; ++b) {
    if (power[b] >= 0.5 * power[peak] && b >= peak / 2 && b <= 2 * peak) {
      sum_p += power[b];
      sum_pf += weighted_k[b];
    }
  }
  if (!(sum_p > 0.0)) return 0.0;
  return sum_p / sum_pf;
}

double RmsWavenumber(const FemOperators& operators, const Eigen::VectorXd& field) {
  const Eigen::VectorXd& mass = operators.lumped_mass_vector();
  const Eigen::VectorXd u = (field.array() - mass.dot(field) / mass.sum()).matrix();
  const double m = u.dot(operators.mass() * u);
  if (!(m > 0.0)) return 0.0;
  return std::sqrt(u.dot(operators.stiffness() * u) / m);
}

}  // namespace photomat

namespace photomat {

GridPatternShape MeasureGridPattern(const GridShape& grid, const Eigen::VectorXd& field) {
  const int w = grid.width, h = grid.height;
  if (field.size() != static_cast<Eigen::Index>(w) * h) {
    throw Error("grid pattern: one value per grid node needed");
  }
  const double threshold = 0.5 * (field.minCoeff() + field.maxCoeff());
  std::vector<int> label(field.size(), -1);
  GridPatternShape shape;
  double weighted = 0.0, covered = 0.0;
  std::vector<int> stack;
  for (int start = 0; start < field.size(); ++start) {
    if (field[start] <= threshold || label[start] >= 0) continue;
    // Flood fill one component, counting its area and boundary edges.
    const int id = shape.components++;
    double area = 0.0, perimeter = 0.0;
    label[start] = id;
    stack.assign(1, start);
    while (!stack.empty()) {
      const int node = stack.back();
      stack.pop_back();
      area += 1.0;
      const int x = node % w, y = node / w;
      const int neighbours[4] = {y * w + (x + 1) % w, y * w + (x + w - 1) % w,
                                 ((y + 1) % h) * w + x, ((y + h - 1) % h) * w + x};
      for (int next : neighbours) {
        if (field[next] <= threshold) {
          perimeter += 1.0;
        } else if (label[next] < 0) {
          label[next] = id;
          stack.push_back(next);
        }
      }
    }
    covered += area;
    if (perimeter > 0.0) weighted += area * 4.0 * std::numbers::pi * area / (perimeter * perimeter);
  }
  if (covered > 0.0) shape.compactness = weighted / covered;
  shape.covered_fraction = covered / static_cast<double>(field.size());
  return shape;
}

}  // namespace photomat
