#include "represent/fitting/observations.h"

#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>
#include <tbb/parallel_reduce.h>

#include <algorithm>
#include <cmath>

namespace photomat {
namespace {

// Rows per block of the parallel loops: large enough for efficient products, small enough that
// float sums of one block stay accurate (2^12 terms).
constexpr Eigen::Index kRowBlock = 4096;

}  // namespace

Observations::Observations(const PhotometricSet& set)
    : pixel_indices_(set.MaskOrAll().SetIndices()),
      channels_(set.channels()),
      width_(set.width()),
      height_(set.height()) {
  const auto m = static_cast<Eigen::Index>(pixel_indices_.size());
  matrix_.resize(m * channels_, set.size());
  // A column is the image's planes restricted to the selected pixels: the planes themselves when
  // every pixel is selected.
  const bool all = static_cast<std::size_t>(m) == static_cast<std::size_t>(width_) * height_;
  tbb::parallel_for(0, set.size(), [&](int image) {
    const Image& source = set.image(image);
    float* column = matrix_.col(image).data();
    if (all) {
      std::copy(source.values().begin(), source.values().end(), column);
      return;
    }
    for (int c = 0; c < channels_; ++c) {
      const float* plane = source.plane(c).data();
      float* out = column + c * m;
      for (Eigen::Index k = 0; k < m; ++k) out[k] = plane[pixel_indices_[k]];
    }
  });
}

const Eigen::MatrixXd& Observations::Gram() const {
  std::call_once(gram_once_, [this] { gram_ = ParallelGram(matrix_); });
  return gram_;
}

Eigen::VectorXd Observations::ColumnStandardDeviations() const {
  Eigen::VectorXd deviations(matrix_.cols());
  for (Eigen::Index j = 0; j < matrix_.cols(); ++j) {
    const auto column = matrix_.col(j).cast<double>();
    const double mean = column.mean();
    deviations[j] = std::sqrt((column.array() - mean).square().mean());
  }
  return deviations;
}

Eigen::MatrixXd ParallelGram(const Eigen::MatrixXf& matrix) {
  const Eigen::Index rows = matrix.rows(), n = matrix.cols();
  return tbb::parallel_reduce(
      tbb::blocked_range<Eigen::Index>(0, rows, kRowBlock), Eigen::MatrixXd::Zero(n, n).eval(),
      [&](const tbb::blocked_range<Eigen::Index>& range, Eigen::MatrixXd sum) {
        for (Eigen::Index start = range.begin(); start < range.end(); start += kRowBlock) {
          const Eigen::Index count = std::min(kRowBlock, range.end() - start);
          Eigen::MatrixXf partial = Eigen::MatrixXf::Zero(n, n);
          partial.selfadjointView<Eigen::Lower>().rankUpdate(
              matrix.middleRows(start, count).transpose());
          sum += partial.selfadjointView<Eigen::Lower>().toDenseMatrix().cast<double>();
        }
        return sum;
      },
      [](const Eigen::MatrixXd& a, const Eigen::MatrixXd& b) -> Eigen::MatrixXd { return a + b; });
}

Eigen::MatrixXf ParallelProduct(const Eigen::MatrixXf& left, const Eigen::MatrixXf& right) {
  Eigen::MatrixXf result(left.rows(), right.cols());
  tbb::parallel_for(tbb::blocked_range<Eigen::Index>(0, left.rows(), kRowBlock),
                    [&](const tbb::blocked_range<Eigen::Index>& range) {
                      const Eigen::Index count = range.end() - range.begin();
                      result.middleRows(range.begin(), count).noalias() =
                          left.middleRows(range.begin(), count) * right;
                    });
  return result;
}

void StorePerChannelTerms(const Observations& observations, const Eigen::MatrixXf& terms,
                          Image& maps) {
  const int channels = observations.channels();
  const Eigen::Index m = observations.pixels();
  const auto planes = static_cast<int>(terms.cols()) * channels;
  tbb::parallel_for(0, planes, [&](int map) {
    const Eigen::Index j = map / channels, c = map % channels;
    const float* values = terms.col(j).data() + c * m;
    float* plane = maps.plane(map).data();
    for (Eigen::Index k = 0; k < m; ++k) plane[observations.pixel_indices()[k]] = values[k];
  });
}

}  // namespace photomat
