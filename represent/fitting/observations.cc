#include "represent/fitting/observations.h"

#include <fmt/format.h>
#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>

#include <algorithm>
#include <cmath>
#include <numeric>
#include <type_traits>
#include <utility>

#include "core/cpu_dispatch.h"
#include "core/error.h"

namespace photomat {
namespace {

// Rows per block of the parallel loops: large enough for efficient products, small enough that
// float sums of one block stay accurate (2^12 terms).
constexpr Eigen::Index kRowBlock = 4096;

// The sum of `count` floats in double, in kSumLanes interleaved partial sums added at the end.
// Why lanes: one running sum waits on the adder's latency at every term (a 4096 x 50 block of
// the Gram pass: 200 us, a third of its rank update's time); independent lanes vectorise without
// reordering any lane's terms, so both clones of the loop give the same bits (16 lanes: 24 us
// with AVX2, 54 us with SSE2).
constexpr int kSumLanes = 16;
PHOTOMAT_HOT_LOOP double SumInDouble(const float* values, Eigen::Index count) {
  double lanes[kSumLanes] = {};
  Eigen::Index i = 0;
  for (; i + kSumLanes <= count; i += kSumLanes) {
    for (int lane = 0; lane < kSumLanes; ++lane) lanes[lane] += values[i + lane];
  }
  for (; i < count; ++i) lanes[0] += values[i];
  double total = 0.0;
  for (const double lane : lanes) total += lane;
  return total;
}

// Columns up to which ParallelProduct uses its own kernel instead of Eigen's GEMM, the rows of
// the result it keeps in the L1 cache (256 x 16 floats: 16 KiB at most) and the images it adds
// per pass over them.
constexpr int kKernelMaxColumns = 16;
constexpr Eigen::Index kKernelRows = 256;
constexpr Eigen::Index kKernelImages = 4;

// result = left * right, for a right-hand side of kColumns columns. Why not Eigen's product: a
// GEMM first packs its left operand (here the band's whole image matrix) into panels; with the
// few columns of a least-squares fit (3 to 16) packing cost more than multiplying (perf, a PTM
// fit of DiLiGenT cat: 7.5 % packing against 4 % multiplying). Here a block of the result stays
// in the L1 cache while the images' columns stream by, each read once and in order (which the
// prefetcher follows; 8 rows of the result in registers against every column at once was slower:
// ~100 streams), four images per pass. Within a pass each row's four image values are loaded
// once and serve all kColumns sums of that row (a product per column of the result, as before,
// reloaded them kColumns times: the kernel was bound by its loads). The block lives in a local
// array, which the compiler knows no input aliases, so it vectorises the rows without run-time
// overlap checks, and is copied to the result at the end. Each value is summed over the images
// in order, so a row gives the same bits in any block or band.
template <int kColumns>
PHOTOMAT_HOT_LOOP void MultiplyFewColumns(const Eigen::Ref<const Eigen::MatrixXf>& left,
                                          const Eigen::MatrixXf& right,
                                          Eigen::Ref<Eigen::MatrixXf> result) {
  const Eigen::Index rows = left.rows(), images = left.cols();
  alignas(64) float block[kColumns][kKernelRows];
  for (Eigen::Index first = 0; first < rows; first += kKernelRows) {
    const Eigen::Index count = std::min(kKernelRows, rows - first);
    for (int k = 0; k < kColumns; ++k) std::fill_n(block[k], count, 0.0f);
    Eigen::Index image = 0;
    for (; image + kKernelImages <= images; image += kKernelImages) {
      const float* x0 = &left.coeffRef(first, image);
      const float* x1 = &left.coeffRef(first, image + 1);
      const float* x2 = &left.coeffRef(first, image + 2);
      const float* x3 = &left.coeffRef(first, image + 3);
      float w0[kColumns], w1[kColumns], w2[kColumns], w3[kColumns];
      for (int k = 0; k < kColumns; ++k) {
        w0[k] = right(image, k), w1[k] = right(image + 1, k);
        w2[k] = right(image + 2, k), w3[k] = right(image + 3, k);
      }
      for (Eigen::Index r = 0; r < count; ++r) {
        const float a0 = x0[r], a1 = x1[r], a2 = x2[r], a3 = x3[r];
        for (int k = 0; k < kColumns; ++k) {
          block[k][r] = (((block[k][r] + w0[k] * a0) + w1[k] * a1) + w2[k] * a2) + w3[k] * a3;
        }
      }
    }
    for (; image < images; ++image) {
      const float* x = &left.coeffRef(first, image);
      for (int k = 0; k < kColumns; ++k) {
        const float w = right(image, k);
        for (Eigen::Index r = 0; r < count; ++r) block[k][r] += w * x[r];
      }
    }
    for (int k = 0; k < kColumns; ++k) std::copy_n(block[k], count, &result.coeffRef(first, k));
  }
}

// MultiplyFewColumns<right.cols()>, or false when right has more than kKernelMaxColumns.
template <int... kMinusOne>
bool MultiplyFewColumns(const Eigen::Ref<const Eigen::MatrixXf>& left, const Eigen::MatrixXf& right,
                        Eigen::Ref<Eigen::MatrixXf> result,
                        std::integer_sequence<int, kMinusOne...>) {
  return ((right.cols() == kMinusOne + 1 &&
           (MultiplyFewColumns<kMinusOne + 1>(left, right, result), true)) ||
          ...);
}

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

namespace {

std::vector<std::size_t> EveryPixel(int width, int height) {
  std::vector<std::size_t> indices(static_cast<std::size_t>(std::max(width, 0)) *
                                   static_cast<std::size_t>(std::max(height, 0)));
  std::iota(indices.begin(), indices.end(), std::size_t{0});
  return indices;
}

}  // namespace

Observations::Observations(Eigen::MatrixXf matrix, int width, int height, int channels)
    : Observations(std::move(matrix), EveryPixel(width, height), width, height, channels) {}

Observations::Observations(Eigen::MatrixXf matrix, std::vector<std::size_t> pixel_indices,
                           int width, int height, int channels)
    : matrix_(std::move(matrix)),
      pixel_indices_(std::move(pixel_indices)),
      channels_(channels),
      width_(width),
      height_(height) {
  const std::size_t pixels =
      static_cast<std::size_t>(std::max(width, 0)) * static_cast<std::size_t>(std::max(height, 0));
  if (width <= 0 || height <= 0 || channels <= 0 ||
      static_cast<std::size_t>(matrix_.rows()) !=
          pixel_indices_.size() * static_cast<std::size_t>(channels)) {
    throw Error(fmt::format(
        "a {} x {} matrix is not the observations of {} pixels of a {}x{} band of {} channels",
        matrix_.rows(), matrix_.cols(), pixel_indices_.size(), width, height, channels));
  }
  for (std::size_t k = 0; k < pixel_indices_.size(); ++k) {
    if (pixel_indices_[k] >= pixels || (k > 0 && pixel_indices_[k] <= pixel_indices_[k - 1])) {
      throw Error(
          fmt::format("observations: pixel index {} ({}) is out of order or outside a "
                      "{}x{} band",
                      k, pixel_indices_[k], width, height));
    }
  }
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
          for (Eigen::Index j = 0; j < n; ++j) sum(j) += SumInDouble(block.col(j).data(), length);
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
  tbb::parallel_for(
      tbb::blocked_range<Eigen::Index>(0, left.rows(), kRowBlock),
      [&](const tbb::blocked_range<Eigen::Index>& range) {
        const Eigen::Index count = range.end() - range.begin();
        const auto rows = left.middleRows(range.begin(), count);
        auto out = result.middleRows(range.begin(), count);
        if (!MultiplyFewColumns(rows, right, out,
                                std::make_integer_sequence<int, kKernelMaxColumns>{})) {
          out.noalias() = rows * right;
        }
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
