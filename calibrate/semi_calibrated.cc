#include "calibrate/semi_calibrated.h"

#include <fmt/format.h>
#include <tbb/enumerable_thread_specific.h>
#include <tbb/parallel_for.h>

#include <Eigen/Cholesky>
#include <Eigen/Core>
#include <Eigen/Eigenvalues>
#include <Eigen/SVD>
#include <algorithm>
#include <cmath>
#include <limits>

#include "core/error.h"

namespace photomat {
namespace {

// The Cauchy scale of the per-pixel weights, in units of the median pixel's residual share.
constexpr double kShareScale = 2.0;

// The eigenvector of the smallest eigenvalue, signed to a positive sum (NaN if the solver fails).
Eigen::VectorXd SmallestPositiveEigenvector(const Eigen::MatrixXd& matrix) {
  const Eigen::SelfAdjointEigenSolver<Eigen::MatrixXd> solver(matrix);
  if (solver.info() != Eigen::Success) {
    return Eigen::VectorXd::Constant(matrix.rows(), std::numeric_limits<double>::quiet_NaN());
  }
  Eigen::VectorXd v = solver.eigenvectors().col(0);
  return v.sum() < 0.0 ? (-v).eval() : v;
}

}  // namespace

SemiCalibratedResult EstimateLightIntensities(const PhotometricSet& set,
                                              const SemiCalibratedOptions& options) {
  const int n = set.size();
  const int channels = set.channels();
  if (n < 4) {
    set.Fail(
        fmt::format("semi-calibrated photometric stereo needs at least 4 images; {} given", n));
  }
  Eigen::Matrix3Xd l(3, n);
  for (int i = 0; i < n; ++i) l.col(i) = set.light(i).vector();
  const Eigen::JacobiSVD<Eigen::Matrix3Xd> svd(l);
  if (svd.singularValues()[2] < 0.02 * svd.singularValues()[0]) {
    set.Fail("semi-calibrated photometric stereo: the lights are coplanar");
  }
  const std::vector<std::size_t> all = set.MaskOrAll().SetIndices();
  const std::size_t stride = std::max<std::size_t>(
      1, (all.size() + options.max_pixels - 1) / std::max(1, options.max_pixels));
  std::vector<std::size_t> pixels;
  for (std::size_t k = 0; k < all.size(); k += stride) pixels.push_back(all[k]);
  const auto m = static_cast<Eigen::Index>(pixels.size());
  if (m < 10) set.Fail(fmt::format("semi-calibrated: only {} pixels to estimate from", m));

  Eigen::MatrixXd e = Eigen::MatrixXd::Ones(n, channels);
  SemiCalibratedResult result;
  NullProgress no_progress;
  Progress& progress = OrNull(options.progress, no_progress);
  progress.Start("semi-calibrated", static_cast<std::size_t>(options.max_iterations));
  using Matrices = std::vector<Eigen::MatrixXd>;
  struct Accumulator {
    Matrices sums;
    std::vector<std::vector<double>> shares;  // per channel, per pixel
  };
  std::vector<double> median_share(channels, 0.0);
  for (int iteration = 0; iteration < options.max_iterations; ++iteration) {
    tbb::enumerable_thread_specific<Accumulator> accumulators([&] {
      return Accumulator{Matrices(channels, Eigen::MatrixXd::Zero(n, n)),
                         std::vector<std::vector<double>>(channels)};
    });
    tbb::parallel_for(Eigen::Index{0}, m, [&](Eigen::Index p) {
      // The pixel's window: its observations ranked by channel sum over the current intensities.
      std::vector<double> y(n, 0.0);
      for (int i = 0; i < n; ++i) {
        const auto pixel = set.image(i).pixel(pixels[p]);
        for (int c = 0; c < channels; ++c) y[i] += pixel[c] / e(i, c);
      }
      std::vector<int> order(n);
      for (int i = 0; i < n; ++i) order[i] = i;
      std::sort(order.begin(), order.end(), [&](int a, int b) { return y[a] < y[b]; });
      const int first = static_cast<int>(std::floor(options.dark_fraction * n));
      const int last = n - static_cast<int>(std::floor(options.bright_fraction * n));
      std::vector<int> window(order.begin() + first, order.begin() + last);
      const auto k = static_cast<Eigen::Index>(window.size());
      if (k < 4) return;
      Eigen::Matrix3Xd lw(3, k);
      for (Eigen::Index j = 0; j < k; ++j) lw.col(j) = l.col(window[j]);
      const Eigen::Matrix3d gram = lw * lw.transpose();
      const Eigen::LDLT<Eigen::Matrix3d> ldlt(gram);
      if (ldlt.info() != Eigen::Success || ldlt.vectorD().minCoeff() < 1e-3) return;
      // The projector onto what the window's lights cannot explain.
      const Eigen::MatrixXd projector =
          Eigen::MatrixXd::Identity(k, k) - lw.transpose() * ldlt.solve(lw);
      Accumulator& accumulator = accumulators.local();
      for (int c = 0; c < channels; ++c) {
        Eigen::VectorXd values(k);
        for (Eigen::Index j = 0; j < k; ++j) {
          values[j] = set.image(window[j]).pixel(pixels[p])[c];
        }
        // How far the pixel's window is from Lambertian under the current intensities: the share
        // of its (intensity-corrected) values the lights cannot explain. Pixels with highlights
        // or shadows left in their window weigh less (Cauchy weight on that share).
        Eigen::VectorXd corrected(k);
        for (Eigen::Index j = 0; j < k; ++j) corrected[j] = values[j] / e(window[j], c);
        const double total_energy = corrected.squaredNorm();
        if (!(total_energy > 0.0)) continue;
        const double share = (projector * corrected).squaredNorm() / total_energy;
        const double scale = kShareScale * kShareScale * median_share[c];
        const double weight = scale > 0.0 ? 1.0 / (1.0 + share / scale) : 1.0;
        accumulator.shares[c].push_back(share);
        // w diag(v) P diag(v), scattered into the images' rows and columns (lower triangle;
        // the matrix is symmetric).
        Eigen::MatrixXd& sum = accumulator.sums[c];
        for (Eigen::Index b = 0; b < k; ++b) {
          const double vb = weight * values[b];
          for (Eigen::Index a = 0; a < k; ++a) {
            const int row = window[a], column = window[b];
            if (row >= column) sum(row, column) += values[a] * projector(a, b) * vb;
          }
        }
      }
    });
    Matrices total(channels, Eigen::MatrixXd::Zero(n, n));
    std::vector<std::vector<double>> shares(channels);
    for (const Accumulator& accumulator : accumulators) {
      for (int c = 0; c < channels; ++c) {
        total[c] += accumulator.sums[c].selfadjointView<Eigen::Lower>().toDenseMatrix();
        shares[c].insert(shares[c].end(), accumulator.shares[c].begin(),
                         accumulator.shares[c].end());
      }
    }
    for (int c = 0; c < channels; ++c) {
      if (shares[c].empty()) continue;
      std::nth_element(shares[c].begin(), shares[c].begin() + shares[c].size() / 2,
                       shares[c].end());
      median_share[c] = shares[c][shares[c].size() / 2];
    }
    Eigen::MatrixXd next(n, channels);
    for (int c = 0; c < channels; ++c) {
      // u = 1 / e spans the (near) null space of the sum: its smallest eigenvector. If that is
      // not positive (an image rarely in any window attracts it), the same after scaling each
      // image's row and column to a unit diagonal.
      Eigen::VectorXd u = SmallestPositiveEigenvector(total[c]);
      if (!(u.minCoeff() > 0.0)) {
        const Eigen::VectorXd diagonal = total[c].diagonal();
        for (int i = 0; i < n; ++i) {
          if (!(diagonal[i] > 0.0)) {
            set.Fail(
                fmt::format("{}: semi-calibrated: no pixel's rank window holds this image "
                            "(it is the darkest or brightest everywhere); lower "
                            "dark_fraction or bright_fraction",
                            set.image_name(i)));
          }
        }
        const Eigen::VectorXd scale = diagonal.cwiseSqrt().cwiseInverse();
        u = scale.asDiagonal() *
            SmallestPositiveEigenvector(scale.asDiagonal() * total[c] * scale.asDiagonal());
      }
      if (!(u.minCoeff() > 0.0)) {
        set.Fail(
            fmt::format("semi-calibrated: no consistent intensities in channel {} (do the "
                        "images share one exposure and a linear response?)",
                        c));
      }
      next.col(c) = u.cwiseInverse();
      next.col(c) /= next.col(c).mean();
    }
    result.last_change = ((next - e).array() / e.array()).abs().maxCoeff();
    e = next;
    result.iterations = iteration + 1;
    progress.Advance();
    if (result.last_change < options.tolerance) break;
  }
  progress.Finish();
  result.intensities.assign(n, std::vector<float>(channels));
  for (int i = 0; i < n; ++i) {
    for (int c = 0; c < channels; ++c) result.intensities[i][c] = static_cast<float>(e(i, c));
  }
  return result;
}

}  // namespace photomat
