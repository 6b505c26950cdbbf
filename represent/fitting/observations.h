#pragma once

#include <Eigen/Core>
#include <cstddef>
#include <mutex>
#include <span>
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

  const Eigen::MatrixXf& matrix() const { return matrix_; }
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

  // I^T I in double precision (summed in blocks of float products), computed once. Thread-safe.
  const Eigen::MatrixXd& Gram() const;

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
};

// A^T A over the rows of a tall float matrix, in double: float products of blocks of 4096 rows
// (accurate at that length), summed in double.
Eigen::MatrixXd ParallelGram(const Eigen::MatrixXf& matrix);

// Copies a (C*m) x k matrix in the observations' row order into the maps j * C + c of `maps`
// (term-major, as CoefficientMapNames names them): each map plane takes the m values of one
// column and channel at the observed pixels; other pixels keep their value.
void StorePerChannelTerms(const Observations& observations, const Eigen::MatrixXf& terms,
                          Image& maps);

// rows x cols product computed in parallel row blocks (Eigen's own products are single-threaded
// without OpenMP). `left` is the large tall matrix.
Eigen::MatrixXf ParallelProduct(const Eigen::MatrixXf& left, const Eigen::MatrixXf& right);

}  // namespace photomat
