#include "calibrate/radiometry/semi_calibrated.h"

#include <fmt/format.h>
#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>
#include <tbb/parallel_reduce.h>

#include <Eigen/Cholesky>
#include <Eigen/Eigenvalues>
#include <Eigen/SVD>
#include <algorithm>
#include <cmath>
#include <limits>

#include "core/error.h"

namespace photomat {
namespace {

// The Cauchy scale of RankWindowWeights' pixel weights, in units of the median pixel's residual
// share.
constexpr double kShareScale = 2.0;
// Pixels per block of the null-space sums: each block is one rank update of the n x n sums, and
// the blocks are added in a fixed order (the same intensities on any number of threads).
constexpr Eigen::Index kPixelBlock = 128;
// A pixel's weighted lights must span 3 directions: the smallest pivot of their weighted Gram
// matrix at least this fraction of the largest.
constexpr double kMinimumRelativePivot = 1e-3;

// The eigenvector of the smallest eigenvalue, signed to a positive sum (NaN if the solver fails).
Eigen::VectorXd SmallestPositiveEigenvector(const Eigen::MatrixXd& matrix) {
  const Eigen::SelfAdjointEigenSolver<Eigen::MatrixXd> solver(matrix);
  if (solver.info() != Eigen::Success) {
    return Eigen::VectorXd::Constant(matrix.rows(), std::numeric_limits<double>::quiet_NaN());
  }
  Eigen::VectorXd v = solver.eigenvectors().col(0);
  return v.sum() < 0.0 ? (-v).eval() : v;
}

// The current intensities of a set as an images x channels matrix (1 where the set has none).
Eigen::MatrixXd IntensityMatrix(const PhotometricSet& set) {
  Eigen::MatrixXd e = Eigen::MatrixXd::Ones(set.size(), set.channels());
  const auto& rows = set.intensities();
  for (std::size_t i = 0; i < rows.size(); ++i) {
    for (int c = 0; c < set.channels(); ++c) {
      e(static_cast<Eigen::Index>(i), c) = rows[i].size() == 1 ? rows[i][0] : rows[i][c];
    }
  }
  return e;
}

// Throws Error naming the set's source when the intensities cannot be estimated from it with
// `pixels` sampled pixels: fewer than 4 images, coplanar lights, fewer than 10 pixels.
void CheckEstimable(const PhotometricSet& set, std::size_t pixels) {
  if (set.size() < 4) {
    set.Fail(fmt::format("semi-calibrated photometric stereo needs at least 4 images; {} given",
                         set.size()));
  }
  const Eigen::JacobiSVD<Eigen::Matrix3Xd> svd(LightMatrix(set.lights()));
  if (svd.singularValues()[2] < 0.02 * svd.singularValues()[0]) {
    set.Fail("semi-calibrated photometric stereo: the lights are coplanar");
  }
  if (pixels < 10)
    set.Fail(fmt::format("semi-calibrated: only {} pixels to estimate from", pixels));
}

// The sampled pixels of every image as one-row images (see ObservationWeigher).
PhotometricSet SampleSet(const PhotometricSet& set, const std::vector<std::size_t>& pixels) {
  std::vector<Image> images;
  images.reserve(set.size());
  const int m = static_cast<int>(pixels.size());
  for (int i = 0; i < set.size(); ++i) {
    // By count, not by names: an image may have none.
    Image strip(m, 1, set.channels());
    if (!set.image(i).channel_names().empty()) {
      strip.set_channel_names(set.image(i).channel_names());
    }
    for (int k = 0; k < m; ++k) {
      const auto from = set.image(i).pixel(pixels[k]);
      std::copy(from.begin(), from.end(), strip.pixel(k, 0).begin());
    }
    images.push_back(std::move(strip));
  }
  return PhotometricSet(std::move(images), set.lights(), set.image_names(), set.source());
}

// Per channel, M_c = sum_p diag(I_p,c) P_p diag(I_p,c) with P_p the weighted projector
// W - W L^T (L W L^T)^-1 L W of pixel p's weighted lights. With L W L^T = C C^T (Cholesky),
// entry (a, b) of pixel p's term is w_a I_a^2 [a = b] - z_a.z_b with z_a = I_a C^-1 (w_a l_a):
// a diagonal plus a rank-3 downdate, accumulated per block of pixels.
std::vector<Eigen::MatrixXd> NullSpaceSums(const PhotometricSet& samples, const Eigen::Matrix3Xd& l,
                                           const Eigen::MatrixXf& weights) {
  const Eigen::Index n = samples.size(), m = samples.width();
  const int channels = samples.channels();
  using Sums = std::vector<Eigen::MatrixXd>;
  const Sums zero(channels, Eigen::MatrixXd::Zero(n, n));
  const Eigen::Index blocks = (m + kPixelBlock - 1) / kPixelBlock;
  return tbb::parallel_deterministic_reduce(
      tbb::blocked_range<Eigen::Index>(0, blocks, 1), zero,
      [&](const tbb::blocked_range<Eigen::Index>& range, Sums sums) {
        Eigen::Matrix3Xd scaled(3, n);
        for (Eigen::Index block = range.begin(); block < range.end(); ++block) {
          const Eigen::Index first = block * kPixelBlock;
          const Eigen::Index count = std::min(kPixelBlock, m - first);
          std::vector<Eigen::MatrixXd> z(channels, Eigen::MatrixXd::Zero(n, 3 * count));
          std::vector<Eigen::VectorXd> diagonal(channels, Eigen::VectorXd::Zero(n));
          for (Eigen::Index k = 0; k < count; ++k) {
            const Eigen::Index p = first + k;
            Eigen::Matrix3d gram = Eigen::Matrix3d::Zero();
            int used = 0;
            for (Eigen::Index i = 0; i < n; ++i) {
              const double w = weights(p, i);
              scaled.col(i) = w * l.col(i);
              if (w <= 0.0) continue;
              gram.noalias() += scaled.col(i) * l.col(i).transpose();
              ++used;
            }
            if (used < 4) continue;
            const Eigen::LDLT<Eigen::Matrix3d> ldlt(gram);
            const auto d = ldlt.vectorD();
            if (ldlt.info() != Eigen::Success ||
                !(d.minCoeff() >= kMinimumRelativePivot * d.maxCoeff())) {
              continue;
            }
            const Eigen::LLT<Eigen::Matrix3d> llt(gram);
            const Eigen::Matrix3Xd whitened = llt.matrixL().solve(scaled);
            for (Eigen::Index i = 0; i < n; ++i) {
              const double w = weights(p, i);
              if (w <= 0.0) continue;
              const auto value = samples.image(static_cast<int>(i)).pixel(static_cast<int>(p), 0);
              for (int c = 0; c < channels; ++c) {
                const double v = value[c];
                diagonal[c][i] += w * v * v;
                z[c].block<1, 3>(i, 3 * k) = v * whitened.col(i).transpose();
              }
            }
          }
          for (int c = 0; c < channels; ++c) {
            sums[c].diagonal() += diagonal[c];
            sums[c].selfadjointView<Eigen::Lower>().rankUpdate(z[c], -1.0);
          }
        }
        return sums;
      },
      [](Sums a, const Sums& b) {
        for (std::size_t c = 0; c < a.size(); ++c) a[c] += b[c];
        return a;
      });
}

}  // namespace

Eigen::MatrixXf RankWindowWeights(const PhotometricSet& samples, double dark_fraction,
                                  double bright_fraction) {
  const int n = samples.size(), m = samples.width(), channels = samples.channels();
  const Eigen::Matrix3Xd l = LightMatrix(samples.lights());
  const Eigen::MatrixXd e = IntensityMatrix(samples);
  Eigen::MatrixXf weights = Eigen::MatrixXf::Zero(m, n);
  std::vector<double> shares(m, -1.0);  // -1: the pixel takes no part
  const int first = static_cast<int>(std::floor(dark_fraction * n));
  const int last = n - static_cast<int>(std::floor(bright_fraction * n));
  tbb::parallel_for(0, m, [&](int p) {
    // The pixel's window: its observations ranked by channel sum over the current intensities.
    Eigen::VectorXd y = Eigen::VectorXd::Zero(n);
    for (int i = 0; i < n; ++i) {
      const auto value = samples.image(i).pixel(p, 0);
      for (int c = 0; c < channels; ++c) y[i] += value[c] / e(i, c);
    }
    std::vector<int> order(n);
    for (int i = 0; i < n; ++i) order[i] = i;
    std::sort(order.begin(), order.end(), [&](int a, int b) { return y[a] < y[b]; });
    if (last - first < 4) return;
    Eigen::Matrix3Xd lw(3, last - first);
    Eigen::VectorXd yw(last - first);
    for (int j = first; j < last; ++j) {
      lw.col(j - first) = l.col(order[j]);
      yw[j - first] = y[order[j]];
    }
    const double energy = yw.squaredNorm();
    if (!(energy > 0.0)) return;
    // The share of the window's values its lights cannot explain.
    const Eigen::Vector3d b = (lw * lw.transpose()).ldlt().solve(lw * yw);
    shares[p] = (yw - lw.transpose() * b).squaredNorm() / energy;
    for (int j = first; j < last; ++j) weights(p, order[j]) = 1.0f;
  });
  std::vector<double> valid;
  for (double share : shares) {
    if (share >= 0.0) valid.push_back(share);
  }
  if (valid.empty()) return weights;
  std::nth_element(valid.begin(), valid.begin() + valid.size() / 2, valid.end());
  const double scale = kShareScale * kShareScale * valid[valid.size() / 2];
  for (int p = 0; p < m; ++p) {
    if (shares[p] < 0.0) continue;
    // Pixels with highlights or shadows left in their window weigh less.
    const double w = scale > 0.0 ? 1.0 / (1.0 + shares[p] / scale) : 1.0;
    weights.row(p) *= static_cast<float>(w);
  }
  return weights;
}

std::vector<std::size_t> SemiCalibratedPixels(const Mask& mask,
                                              const SemiCalibratedOptions& options) {
  const std::vector<std::size_t> all = mask.SetIndices();
  const std::size_t stride = std::max<std::size_t>(
      1, (all.size() + options.max_pixels - 1) / std::max(1, options.max_pixels));
  std::vector<std::size_t> pixels;
  for (std::size_t k = 0; k < all.size(); k += stride) pixels.push_back(all[k]);
  return pixels;
}

SemiCalibratedSamples::SemiCalibratedSamples(std::vector<std::size_t> pixels, int width)
    : pixels_(std::move(pixels)), width_(width) {}

void SemiCalibratedSamples::Add(const PhotometricSet& band, int first_row) {
  if (strips_.empty()) {
    for (int i = 0; i < band.size(); ++i) {
      // As SampleSet makes them: by count, with the images' channel names.
      Image strip(static_cast<int>(pixels_.size()), 1, band.channels());
      if (!band.image(i).channel_names().empty()) {
        strip.set_channel_names(band.image(i).channel_names());
      }
      strips_.push_back(std::move(strip));
    }
    lights_ = band.lights();
    names_ = band.image_names();
    source_ = band.source();
  }
  const std::size_t begin = static_cast<std::size_t>(first_row) * width_;
  const std::size_t end = begin + static_cast<std::size_t>(band.height()) * width_;
  const auto first = std::lower_bound(pixels_.begin(), pixels_.end(), begin);
  for (auto it = first; it != pixels_.end() && *it < end; ++it) {
    const int k = static_cast<int>(it - pixels_.begin());
    for (int i = 0; i < band.size(); ++i) {
      const auto from = band.image(i).pixel(*it - begin);
      std::copy(from.begin(), from.end(), strips_[i].pixel(k, 0).begin());
    }
  }
}

PhotometricSet SemiCalibratedSamples::samples() const {
  if (strips_.empty()) throw Error("semi-calibrated: no band of the capture was read");
  return PhotometricSet(strips_, lights_, names_, source_);
}

SemiCalibratedResult EstimateLightIntensities(const PhotometricSet& set,
                                              const SemiCalibratedOptions& options) {
  const std::vector<std::size_t> pixels = SemiCalibratedPixels(set.MaskOrAll(), options);
  CheckEstimable(set, pixels.size());
  return EstimateLightIntensitiesFromSamples(SampleSet(set, pixels), options);
}

SemiCalibratedResult EstimateLightIntensitiesFromSamples(PhotometricSet samples,
                                                         const SemiCalibratedOptions& options) {
  const PhotometricSet& set = samples;  // errors name the capture's source, as the samples do
  const int n = set.size();
  const int channels = set.channels();
  CheckEstimable(set, static_cast<std::size_t>(set.width()));
  const Eigen::Matrix3Xd l = LightMatrix(set.lights());
  const auto m = static_cast<Eigen::Index>(set.width());

  Eigen::MatrixXd e = Eigen::MatrixXd::Ones(n, channels);
  SemiCalibratedResult result;
  NullProgress no_progress;
  Progress& progress = OrNull(options.progress, no_progress);
  progress.Start("semi-calibrated", static_cast<std::size_t>(options.max_iterations));
  double smallest_change = std::numeric_limits<double>::infinity();
  int stalled = 0;
  for (int iteration = 0; iteration < options.max_iterations; ++iteration) {
    std::vector<std::vector<float>> rows(n, std::vector<float>(channels));
    for (int i = 0; i < n; ++i) {
      for (int c = 0; c < channels; ++c) rows[i][c] = static_cast<float>(e(i, c));
    }
    samples.set_intensities(std::move(rows));
    const Eigen::MatrixXf weights =
        options.weigher
            ? options.weigher(samples)
            : RankWindowWeights(samples, options.dark_fraction, options.bright_fraction);
    if (weights.rows() != m || weights.cols() != n || !weights.allFinite() ||
        weights.minCoeff() < 0.0f) {
      set.Fail(
          fmt::format("semi-calibrated: the observation weights are {}x{} (want {}x{}, "
                      "finite and not negative)",
                      weights.rows(), weights.cols(), m, n));
    }
    const std::vector<Eigen::MatrixXd> sums = NullSpaceSums(samples, l, weights);
    Eigen::MatrixXd next(n, channels);
    for (int c = 0; c < channels; ++c) {
      const Eigen::MatrixXd total = sums[c].selfadjointView<Eigen::Lower>();
      // u = 1 / e spans the (near) null space of the sum: its smallest eigenvector. If that is
      // not positive (an image with few weighted observations attracts it), the same after
      // scaling each image's row and column to a unit diagonal.
      Eigen::VectorXd u = SmallestPositiveEigenvector(total);
      if (!(u.minCoeff() > 0.0)) {
        const Eigen::VectorXd diagonal = total.diagonal();
        for (int i = 0; i < n; ++i) {
          if (!(diagonal[i] > 0.0)) {
            set.Fail(
                fmt::format("{}: semi-calibrated: no sampled observation of this image "
                            "takes part (it is dark, clipped or an outlier everywhere)",
                            set.image_name(i)));
          }
        }
        const Eigen::VectorXd scale = diagonal.cwiseSqrt().cwiseInverse();
        u = scale.asDiagonal() *
            SmallestPositiveEigenvector(scale.asDiagonal() * total * scale.asDiagonal());
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
    // Re-weighing can settle into a cycle between nearly equal weight sets, where the change
    // stops falling: stop once it has not reached a new low for `stall_iterations`.
    if (result.last_change < smallest_change) {
      smallest_change = result.last_change;
      stalled = 0;
    } else if (++stalled >= options.stall_iterations) {
      break;
    }
  }
  progress.Finish();
  result.intensities.assign(n, std::vector<float>(channels));
  for (int i = 0; i < n; ++i) {
    for (int c = 0; c < channels; ++c) result.intensities[i][c] = static_cast<float>(e(i, c));
  }
  return result;
}

}  // namespace photomat
