#include "represent/surface/surface_integration.h"

#include <fmt/format.h>
#include <tbb/parallel_for.h>

#include <Eigen/Sparse>
#include <algorithm>
#include <cmath>
#include <complex>
#include <numbers>
#include <vector>

#include "core/error.h"
#include "core/fft.h"

namespace photomat {
namespace {

void CheckGradients(const Image& gradients) {
  if (gradients.channels() < 2 || gradients.empty()) {
    throw Error("gradient images need 2 channels (p, q)");
  }
}

// Angular frequency of FFT bin k of n samples, in [-pi, pi).
double Frequency(int k, int n) {
  const int signed_k = k <= n / 2 ? k : k - n;
  return 2.0 * std::numbers::pi * signed_k / n;
}

// Half spectra (real transforms: height rows of width / 2 + 1 frequencies) of p and of the row
// derivative -q (rows run down, y up).
struct Spectra {
  std::vector<std::complex<double>> p, q_rows;
};

Spectra Transform(const RealFft2d<double>& fft, const Image& gradients) {
  std::vector<double> p(gradients.plane(0).begin(), gradients.plane(0).end());
  std::vector<double> q_rows(fft.size());
  std::transform(gradients.plane(1).begin(), gradients.plane(1).end(), q_rows.begin(),
                 [](float q) { return -static_cast<double>(q); });
  Spectra spectra{std::vector<std::complex<double>>(fft.spectrum_size()),
                  std::vector<std::complex<double>>(fft.spectrum_size())};
  fft.Forward(p, spectra.p);
  fft.Forward(q_rows, spectra.q_rows);
  return spectra;
}

// Calls visit(u, v, k) with the row and column angular frequencies of every half-spectrum bin k.
template <typename Visit>
void ForEachFrequency(const RealFft2d<double>& fft, Visit visit) {
  const int half = fft.spectrum_width();
  for (int y = 0; y < fft.height(); ++y) {
    const double v = Frequency(y, fft.height());
    for (int x = 0; x < half; ++x) {
      visit(Frequency(x, fft.width()), v, static_cast<std::size_t>(y) * half + x);
    }
  }
}

// S(u, v) of Frankot-Chellappa, in row/column frequencies.
std::vector<std::complex<double>> HeightSpectrum(const RealFft2d<double>& fft,
                                                 const Spectra& spectra) {
  std::vector<std::complex<double>> s(fft.spectrum_size());
  const std::complex<double> j(0.0, 1.0);
  ForEachFrequency(fft, [&](double u, double v, std::size_t k) {
    const double d = u * u + v * v;
    s[k] = d == 0.0 ? 0.0 : (-j * u * spectra.p[k] - j * v * spectra.q_rows[k]) / d;
  });
  return s;
}

// The inverse transform of `spectrum`, scaled by 1 / (width * height) and by `sign`, into
// channel `channel` of `out`.
void InverseInto(const RealFft2d<double>& fft, std::vector<std::complex<double>> spectrum,
                 double sign, Image& out, int channel) {
  std::vector<double> values(fft.size());
  fft.Inverse(spectrum, values);
  const double scale = sign / static_cast<double>(fft.size());
  std::transform(values.begin(), values.end(), out.plane(channel).begin(),
                 [scale](double value) { return static_cast<float>(value * scale); });
}

}  // namespace

Image GradientsFromNormals(const Image& normals, double min_nz) {
  if (normals.channels() < 3) throw Error("normal images need 3 channels (x, y, z)");
  Image gradients(normals.width(), normals.height(), std::vector<std::string>{"p", "q"});
  for (std::size_t i = 0; i < normals.pixel_count(); ++i) {
    const auto n = normals.pixel(i);
    const double nz = std::max<double>(n[2], min_nz);
    gradients.pixel(i)[0] = static_cast<float>(-n[0] / nz);
    gradients.pixel(i)[1] = static_cast<float>(-n[1] / nz);
  }
  return gradients;
}

Image NormalsFromGradients(const Image& gradients) {
  CheckGradients(gradients);
  Image normals(gradients.width(), gradients.height(),
                std::vector<std::string>{"normal.X", "normal.Y", "normal.Z"});
  for (std::size_t i = 0; i < gradients.pixel_count(); ++i) {
    const double p = gradients.pixel(i)[0], q = gradients.pixel(i)[1];
    const double norm = std::sqrt(p * p + q * q + 1.0);
    normals.pixel(i)[0] = static_cast<float>(-p / norm);
    normals.pixel(i)[1] = static_cast<float>(-q / norm);
    normals.pixel(i)[2] = static_cast<float>(1.0 / norm);
  }
  return normals;
}

Image IntegrateFrankotChellappa(const Image& gradients) {
  CheckGradients(gradients);
  const RealFft2d<double> fft(gradients.width(), gradients.height());
  Image out(gradients.width(), gradients.height(), std::vector<std::string>{"height"});
  InverseInto(fft, HeightSpectrum(fft, Transform(fft, gradients)), 1.0, out, 0);
  return out;
}

Image ProjectToIntegrable(const Image& gradients) {
  CheckGradients(gradients);
  const RealFft2d<double> fft(gradients.width(), gradients.height());
  const std::vector<std::complex<double>> s = HeightSpectrum(fft, Transform(fft, gradients));
  std::vector<std::complex<double>> p_spectrum(s.size()), q_spectrum(s.size());
  const std::complex<double> j(0.0, 1.0);
  ForEachFrequency(fft, [&](double u, double v, std::size_t k) {
    p_spectrum[k] = j * u * s[k];
    q_spectrum[k] = j * v * s[k];
  });
  Image out(gradients.width(), gradients.height(), std::vector<std::string>{"p", "q"});
  InverseInto(fft, std::move(p_spectrum), 1.0, out, 0);
  InverseInto(fft, std::move(q_spectrum), -1.0, out, 1);
  return out;
}

struct PoissonIntegrator::System {
  Eigen::SparseMatrix<double> normal;
  Eigen::SimplicialLDLT<Eigen::SparseMatrix<double>> factor;  // when direct()
};

namespace {

// Calls pair(a, b, x, y, horizontal) for each neighbouring pair of unknowns (a, b): (x, y) -> (x +
// 1, y) when horizontal, else (x, y) -> (x, y + 1), in raster order.
template <typename Pair>
void ForEachPair(const std::vector<int>& index, int w, int h, Pair pair) {
  for (int y = 0; y < h; ++y) {
    for (int x = 0; x < w; ++x) {
      const int a = index[static_cast<std::size_t>(y) * w + x];
      if (a < 0) continue;
      if (x + 1 < w) {
        const int b = index[static_cast<std::size_t>(y) * w + x + 1];
        if (b >= 0) pair(a, b, x, y, true);
      }
      if (y + 1 < h) {
        const int b = index[static_cast<std::size_t>(y + 1) * w + x];
        if (b >= 0) pair(a, b, x, y, false);
      }
    }
  }
}

}  // namespace

PoissonIntegrator::PoissonIntegrator(const Mask& mask, PoissonSolver solver)
    : width_(mask.width()), height_(mask.height()) {
  index_.assign(mask.pixel_count(), -1);
  for (std::size_t i = 0; i < index_.size(); ++i) {
    if (mask[i]) index_[i] = unknowns_++;
  }
  if (unknowns_ == 0) throw Error("the mask selects no pixel to integrate");
  direct_ = solver == PoissonSolver::kDirect ||
            (solver == PoissonSolver::kAuto && unknowns_ <= kDirectPoissonUnknowns);
  // Each pair (a, b) is a row -e_a + e_b of the least-squares matrix A: A^T A gains 1 on both
  // diagonals and -1 off them.
  std::vector<Eigen::Triplet<double>> triplets;
  for (int i = 0; i < unknowns_; ++i) triplets.emplace_back(i, i, 1e-9);
  ForEachPair(index_, width_, height_, [&](int a, int b, int, int, bool) {
    triplets.emplace_back(a, a, 1.0);
    triplets.emplace_back(b, b, 1.0);
    triplets.emplace_back(a, b, -1.0);
    triplets.emplace_back(b, a, -1.0);
  });
  auto system = std::make_unique<System>();
  system->normal.resize(unknowns_, unknowns_);
  system->normal.setFromTriplets(triplets.begin(), triplets.end());
  if (direct()) {
    system->factor.compute(system->normal);
    if (system->factor.info() != Eigen::Success) {
      throw Error(
          fmt::format("Poisson integration: the {} x {} system of {} unknowns could not be "
                      "factorised",
                      width_, height_, unknowns_));
    }
  }
  system_ = std::move(system);
}

PoissonIntegrator::~PoissonIntegrator() = default;
PoissonIntegrator::PoissonIntegrator(PoissonIntegrator&&) noexcept = default;
PoissonIntegrator& PoissonIntegrator::operator=(PoissonIntegrator&&) noexcept = default;

Image PoissonIntegrator::Integrate(const Image& gradients) const {
  CheckGradients(gradients);
  if (gradients.width() != width_ || gradients.height() != height_) {
    throw Error(fmt::format("Poisson integration: gradients of {} x {} for a mask of {} x {}",
                            gradients.width(), gradients.height(), width_, height_));
  }
  // A^T b: each pair's target, the mean slope along a -> b (one row down is one unit of -y).
  Eigen::VectorXd rhs = Eigen::VectorXd::Zero(unknowns_);
  std::size_t non_finite = 0;
  ForEachPair(index_, width_, height_, [&](int a, int b, int x, int y, bool horizontal) {
    const double slope = horizontal ? 0.5 * (gradients.at(x, y, 0) + gradients.at(x + 1, y, 0))
                                    : -0.5 * (gradients.at(x, y, 1) + gradients.at(x, y + 1, 1));
    if (!std::isfinite(slope)) ++non_finite;
    rhs[a] -= slope;
    rhs[b] += slope;
  });
  // One NaN would spread through the solve to its whole piece of the mask: refuse instead.
  if (non_finite > 0) {
    throw Error(fmt::format(
        "Poisson integration: {} slope(s) inside the mask are not finite (NaN or infinite normals "
        "or gradients)",
        non_finite));
  }
  Eigen::VectorXd s;
  if (direct()) {
    s = system_->factor.solve(rhs);
  } else {
    Eigen::ConjugateGradient<Eigen::SparseMatrix<double>, Eigen::Lower | Eigen::Upper> solver;
    solver.setTolerance(1e-10);
    solver.setMaxIterations(20 * unknowns_ + 1000);
    solver.compute(system_->normal);
    s = solver.solve(rhs);
    if (solver.info() != Eigen::Success) throw Error("Poisson integration did not converge");
  }
  if (!s.allFinite()) throw Error("Poisson integration gave non-finite heights");
  s.array() -= s.mean();
  Image out(width_, height_, std::vector<std::string>{"height"});
  for (std::size_t i = 0; i < index_.size(); ++i) {
    if (index_[i] >= 0) out.pixel(i)[0] = static_cast<float>(s[index_[i]]);
  }
  return out;
}

Image IntegratePoisson(const Image& gradients, const Mask& mask) {
  CheckGradients(gradients);
  if (mask.pixel_count() == 0) {
    return PoissonIntegrator(Mask(gradients.width(), gradients.height(), true))
        .Integrate(gradients);
  }
  if (!mask.SameSize(gradients)) throw Error("mask and gradients differ in size");
  return PoissonIntegrator(mask).Integrate(gradients);
}

}  // namespace photomat
