#include "represent/surface/surface_integration.h"

#include <tbb/parallel_for.h>

#include <Eigen/Sparse>
#include <algorithm>
#include <cmath>
#include <complex>
#include <numbers>
#include <opencv2/core.hpp>

#include "core/error.h"

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

// Spectra of p and of the row derivative -q (rows run down, y up), complex, one per channel.
struct Spectra {
  cv::Mat p, q_rows;
};

Spectra Transform(const Image& gradients) {
  const int w = gradients.width(), h = gradients.height();
  cv::Mat p(h, w, CV_64F), q_rows(h, w, CV_64F);
  for (int y = 0; y < h; ++y) {
    for (int x = 0; x < w; ++x) {
      p.at<double>(y, x) = gradients.at(x, y, 0);
      q_rows.at<double>(y, x) = -gradients.at(x, y, 1);
    }
  }
  Spectra spectra;
  cv::dft(p, spectra.p, cv::DFT_COMPLEX_OUTPUT);
  cv::dft(q_rows, spectra.q_rows, cv::DFT_COMPLEX_OUTPUT);
  return spectra;
}

// S(u, v) of Frankot-Chellappa, in row/column frequencies.
cv::Mat HeightSpectrum(const Spectra& spectra) {
  const int h = spectra.p.rows, w = spectra.p.cols;
  cv::Mat s(h, w, CV_64FC2);
  for (int y = 0; y < h; ++y) {
    const double v = Frequency(y, h);
    for (int x = 0; x < w; ++x) {
      const double u = Frequency(x, w);
      const double d = u * u + v * v;
      const auto& pv = spectra.p.at<cv::Vec2d>(y, x);
      const auto& qv = spectra.q_rows.at<cv::Vec2d>(y, x);
      const std::complex<double> P(pv[0], pv[1]), Q(qv[0], qv[1]), j(0.0, 1.0);
      const std::complex<double> S = d == 0.0 ? 0.0 : (-j * u * P - j * v * Q) / d;
      s.at<cv::Vec2d>(y, x) = {S.real(), S.imag()};
    }
  }
  return s;
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
  cv::Mat height;
  cv::dft(HeightSpectrum(Transform(gradients)), height,
          cv::DFT_INVERSE | cv::DFT_SCALE | cv::DFT_REAL_OUTPUT);
  Image out(gradients.width(), gradients.height(), std::vector<std::string>{"height"});
  for (int y = 0; y < out.height(); ++y) {
    for (int x = 0; x < out.width(); ++x)
      out.at(x, y, 0) = static_cast<float>(height.at<double>(y, x));
  }
  return out;
}

Image ProjectToIntegrable(const Image& gradients) {
  CheckGradients(gradients);
  const cv::Mat s = HeightSpectrum(Transform(gradients));
  const int h = s.rows, w = s.cols;
  cv::Mat p_spectrum(h, w, CV_64FC2), q_spectrum(h, w, CV_64FC2);
  for (int y = 0; y < h; ++y) {
    const double v = Frequency(y, h);
    for (int x = 0; x < w; ++x) {
      const double u = Frequency(x, w);
      const auto& sv = s.at<cv::Vec2d>(y, x);
      const std::complex<double> S(sv[0], sv[1]), j(0.0, 1.0);
      const std::complex<double> P = j * u * S, Q_rows = j * v * S;
      p_spectrum.at<cv::Vec2d>(y, x) = {P.real(), P.imag()};
      q_spectrum.at<cv::Vec2d>(y, x) = {Q_rows.real(), Q_rows.imag()};
    }
  }
  cv::Mat p, q_rows;
  cv::dft(p_spectrum, p, cv::DFT_INVERSE | cv::DFT_SCALE | cv::DFT_REAL_OUTPUT);
  cv::dft(q_spectrum, q_rows, cv::DFT_INVERSE | cv::DFT_SCALE | cv::DFT_REAL_OUTPUT);
  Image out(w, h, std::vector<std::string>{"p", "q"});
  for (int y = 0; y < h; ++y) {
    for (int x = 0; x < w; ++x) {
      out.at(x, y, 0) = static_cast<float>(p.at<double>(y, x));
      out.at(x, y, 1) = static_cast<float>(-q_rows.at<double>(y, x));
    }
  }
  return out;
}

Image IntegratePoisson(const Image& gradients, const Mask& mask_in) {
  CheckGradients(gradients);
  const int w = gradients.width(), h = gradients.height();
  const Mask mask = mask_in.pixel_count() == 0 ? Mask(w, h, true) : mask_in;
  if (mask.width() != w || mask.height() != h) throw Error("mask and gradients differ in size");
  // Unknowns: the masked pixels.
  std::vector<int> index(static_cast<std::size_t>(w) * h, -1);
  int unknowns = 0;
  for (std::size_t i = 0; i < index.size(); ++i) {
    if (mask[i]) index[i] = unknowns++;
  }
  if (unknowns == 0) throw Error("the mask selects no pixel to integrate");
  // Each neighbouring pair (a, b) inside the mask gives s_b - s_a = mean slope along a -> b.
  std::vector<Eigen::Triplet<double>> triplets;
  std::vector<double> targets;
  const auto add_pair = [&](int a, int b, double slope) {
    const int row = static_cast<int>(targets.size());
    triplets.emplace_back(row, a, -1.0);
    triplets.emplace_back(row, b, 1.0);
    targets.push_back(slope);
  };
  for (int y = 0; y < h; ++y) {
    for (int x = 0; x < w; ++x) {
      const int a = index[static_cast<std::size_t>(y) * w + x];
      if (a < 0) continue;
      if (x + 1 < w) {
        const int b = index[static_cast<std::size_t>(y) * w + x + 1];
        if (b >= 0) add_pair(a, b, 0.5 * (gradients.at(x, y, 0) + gradients.at(x + 1, y, 0)));
      }
      if (y + 1 < h) {
        // One row down is one unit of -y.
        const int b = index[static_cast<std::size_t>(y + 1) * w + x];
        if (b >= 0) add_pair(a, b, -0.5 * (gradients.at(x, y, 1) + gradients.at(x, y + 1, 1)));
      }
    }
  }
  Eigen::SparseMatrix<double> a(static_cast<Eigen::Index>(targets.size()), unknowns);
  a.setFromTriplets(triplets.begin(), triplets.end());
  const Eigen::Map<const Eigen::VectorXd> b(targets.data(),
                                            static_cast<Eigen::Index>(targets.size()));
  // The normal equations are singular by the free constant (one per connected region); a tiny
  // Tikhonov term picks the zero-mean solution without biasing the shape measurably.
  Eigen::SparseMatrix<double> normal = a.transpose() * a;
  for (int i = 0; i < unknowns; ++i) normal.coeffRef(i, i) += 1e-9;
  Eigen::ConjugateGradient<Eigen::SparseMatrix<double>, Eigen::Lower | Eigen::Upper> solver;
  solver.setTolerance(1e-10);
  solver.setMaxIterations(20 * unknowns + 1000);
  solver.compute(normal);
  Eigen::VectorXd s = solver.solve(a.transpose() * b);
  if (solver.info() != Eigen::Success) throw Error("Poisson integration did not converge");
  s.array() -= s.mean();
  Image out(w, h, std::vector<std::string>{"height"});
  for (std::size_t i = 0; i < index.size(); ++i) {
    if (index[i] >= 0) out.pixel(i)[0] = static_cast<float>(s[index[i]]);
  }
  return out;
}

}  // namespace photomat
