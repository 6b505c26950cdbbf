#pragma once

#include <Eigen/Core>
#include <cstddef>
#include <mutex>
#include <span>
#include <utility>
#include <vector>

#include "core/image.h"
#include "core/photometric_set.h"

namespace photomat {

// The image data matrix I of the thesis (section 4.4): one column per image, one row per
// (channel, pixel) of the pixels that take part (the set's mask, or all). Rows are channel-major:
// row c * m + k is channel c of the k-th selected pixel, so each channel is a contiguous block
// and a per-pixel fit is a product of I with a small matrix. Float storage: a DiLiGenT object
// is 96 x 3 x 313k values.
class Observations {
 public:
  explicit Observations(const PhotometricSet& set);
  // The observations of a width x height band whose every pixel takes part, from `matrix`
  // already in the layout above (column i: image i's planes, channel-major; (width * height *
  // channels) x images): the streamed fit decodes its bands straight into such a matrix
  // (StreamedSet::ReadBandInto), with no band images and no copy. Throws Error for a matrix of
  // another height.
  Observations(Eigen::MatrixXf matrix, int width, int height, int channels);
  // The same for a band whose mask selects `pixel_indices` (y * width + x within the band,
  // ascending): the streamed fit gathers them into the matrix as each image's band is decoded.
  // Throws Error for indices out of order or range, or a matrix of another height.
  Observations(Eigen::MatrixXf matrix, std::vector<std::size_t> pixel_indices, int width,
               int height, int channels);

  const Eigen::MatrixXf& matrix() const { return matrix_; }
  // The matrix, moved out for its storage to be reused (a streamed fit's next band); these
  // observations are left with none.
  Eigen::MatrixXf ReleaseMatrix() && { return std::move(matrix_); }
  int images() const { return static_cast<int>(matrix_.cols()); }
  int channels() const { return channels_; }
  // Number of selected pixels (m).
  int pixels() const { return static_cast<int>(pixel_indices_.size()); }
  // Image index (y * width + x) of selected pixel k.
  const std::vector<std::size_t>& pixel_indices() const { return pixel_indices_; }
  int width() const { return width_; }
  int height() const { return height_; }
  auto Channel(int c) const {
    return matrix_.middleRows(static_cast<Eigen::Index>(c) * pixels(), pixels());
  }

  // I^T I in double precision (RowGram: the same sum whatever the band), computed once.
  // Thread-safe.
  const Eigen::MatrixXd& Gram() const;
  // Per image, the sum of its column (double, in RowGram's order).
  const Eigen::VectorXd& ColumnSums() const;

  // Per image, the standard deviation of its values over all rows (the normaliser of Dong's
  // error).
  Eigen::VectorXd ColumnStandardDeviations() const;

 private:
  Eigen::MatrixXf matrix_;
  std::vector<std::size_t> pixel_indices_;
  int channels_ = 0;
  int width_ = 0;
  int height_ = 0;
  mutable std::once_flag gram_once_;
  mutable Eigen::MatrixXd gram_;
  mutable Eigen::VectorXd column_sums_;
};

// A^T A and the column sums of an image data matrix (Observations' row layout), accumulated band
// by band in a fixed order: per image row and channel a float product of at most 4096 pixels
// (accurate at that length), summed in double into the row's total, and the rows' totals added
// in row order. The result depends neither on the band heights nor on the thread count, so a
// streamed fit (any band) and an in-memory one (one band) get the same bits, run after run.
class RowGram {
 public:
  explicit RowGram(Eigen::Index columns);
  // Adds the rows of one band: `matrix` has Observations' layout for the band's selected
  // `pixel_indices` (y * width + x within the band, ascending) and `channels` channels.
  void Add(const Eigen::MatrixXf& matrix, std::span<const std::size_t> pixel_indices, int width,
           int channels);
  const Eigen::MatrixXd& gram() const { return gram_; }
  const Eigen::VectorXd& column_sums() const { return column_sums_; }

 private:
  Eigen::MatrixXd gram_;
  Eigen::VectorXd column_sums_;
};

// Copies a (C*m) x k matrix in the observations' row order into the maps j * C + c of `maps`
// (term-major, as CoefficientMapNames names them): each map plane takes the m values of one
// column and channel at the observed pixels; other pixels keep their value.
void StorePerChannelTerms(const Observations& observations, const Eigen::MatrixXf& terms,
                          Image& maps);

// rows x cols product computed in parallel row blocks (Eigen's own products are single-threaded
// without OpenMP). `left` is the large tall matrix.
Eigen::MatrixXf ParallelProduct(const Eigen::MatrixXf& left, const Eigen::MatrixXf& right);

}  // namespace photomat
