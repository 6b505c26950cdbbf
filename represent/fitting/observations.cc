#include "represent/fitting/observations.h"

#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>

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
  std::call_once(gram_once_, [this] {
    RowGram sum(matrix_.cols());
    sum.Add(matrix_, pixel_indices_, width_, channels_);
    gram_ = sum.gram();
    column_sums_ = sum.column_sums();
  });
  return gram_;
}

const Eigen::VectorXd& Observations::ColumnSums() const {
  Gram();
  return column_sums_;
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

RowGram::RowGram(Eigen::Index columns)
    : gram_(Eigen::MatrixXd::Zero(columns, columns)),
      column_sums_(Eigen::VectorXd::Zero(columns)) {}

void RowGram::Add(const Eigen::MatrixXf& matrix, std::span<const std::size_t> pixel_indices,
                  int width, int channels) {
  const auto m = static_cast<Eigen::Index>(pixel_indices.size());
  const Eigen::Index n = gram_.cols();
  if (m == 0) return;
  // Image rows present, each with its range of selected pixels [begin, end).
  struct RowRange {
    Eigen::Index begin, end;
  };
  std::vector<RowRange> rows;
  for (Eigen::Index k = 0; k < m;) {
    const std::size_t y = pixel_indices[k] / static_cast<std::size_t>(width);
    Eigen::Index end = k;
    while (end < m && pixel_indices[end] / static_cast<std::size_t>(width) == y) ++end;
    rows.push_back({k, end});
    k = end;
  }
  // Rows in groups whose totals are computed in parallel, then added in row order.
  constexpr std::size_t kRowsPerGroup = 64;
  std::vector<Eigen::MatrixXd> totals(std::min(kRowsPerGroup, rows.size()));
  std::vector<Eigen::VectorXd> sums(totals.size());
  for (std::size_t group = 0; group < rows.size(); group += kRowsPerGroup) {
    const std::size_t count = std::min(kRowsPerGroup, rows.size() - group);
    tbb::parallel_for(std::size_t{0}, count, [&](std::size_t r) {
      const RowRange range = rows[group + r];
      Eigen::MatrixXd& total = totals[r];
      Eigen::VectorXd& sum = sums[r];
      total.setZero(n, n);
      sum.setZero(n);
      Eigen::MatrixXf partial(n, n);
      for (int c = 0; c < channels; ++c) {
        for (Eigen::Index start = range.begin; start < range.end; start += kRowBlock) {
          const Eigen::Index length = std::min(kRowBlock, range.end - start);
          const auto block = matrix.middleRows(c * m + start, length);
          partial.setZero();
          partial.selfadjointView<Eigen::Lower>().rankUpdate(block.transpose());
          total += partial.selfadjointView<Eigen::Lower>().toDenseMatrix().cast<double>();
          sum += block.cast<double>().colwise().sum().transpose();
        }
      }
    });
    for (std::size_t r = 0; r < count; ++r) {
      gram_ += totals[r];
      column_sums_ += sums[r];
    }
  }
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
