#include "represent/fitting/observations.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <numeric>
#include <random>
#include <span>
#include <vector>

#include "core/error.h"
#include "core/image.h"
#include "core/light_direction.h"
#include "core/photometric_set.h"

namespace photomat {
namespace {

// A seeded image matrix (rows: pixels, columns: images) and a fit's term matrix.
Eigen::MatrixXf SeededMatrix(Eigen::Index rows, Eigen::Index cols, unsigned seed) {
  std::mt19937 random(seed);
  std::uniform_real_distribution<float> value(0.0f, 1.0f);
  Eigen::MatrixXf matrix(rows, cols);
  for (Eigen::Index j = 0; j < cols; ++j) {
    for (Eigen::Index i = 0; i < rows; ++i) matrix(i, j) = value(random);
  }
  return matrix;
}

// Both of ParallelProduct's ways: outer products for at most 16 columns, Eigen's GEMM beyond.
class ParallelProductTest : public testing::TestWithParam<int> {};

TEST_P(ParallelProductTest, EqualsTheProductToFloatRounding) {
  // Rows not a multiple of any block, images not a multiple of the kernel's four per pass.
  const Eigen::MatrixXf left = SeededMatrix(9001, 97, 1);
  const Eigen::MatrixXf right = SeededMatrix(97, GetParam(), 2);
  const Eigen::MatrixXd exact = left.cast<double>() * right.cast<double>();
  const Eigen::MatrixXf product = ParallelProduct(left, right);
  // 97 float products summed in float: a relative error of a few 1e-7 on sums of about 24.
  EXPECT_LT((product.cast<double>() - exact).cwiseAbs().maxCoeff() / exact.cwiseAbs().maxCoeff(),
            2e-6);
}

TEST_P(ParallelProductTest, RowsDoNotDependOnTheBandTheyCameFrom) {
  // A streamed fit multiplies bands of rows; up to 16 columns (terms: Gradient, PTM, HSH,
  // Eigen-k and rbf/bilinear planes up to 16) a row gives the same bits in any band. Eigen's GEMM
  // beyond that vectorises a band's rows by their position in it, so its rows agree to float
  // rounding only (measured: a few 1e-7 relative).
  const Eigen::MatrixXf left = SeededMatrix(5000, 42, 3);
  const Eigen::MatrixXf right = SeededMatrix(42, GetParam(), 4);
  const Eigen::MatrixXf whole = ParallelProduct(left, right).middleRows(1234, 777);
  const Eigen::MatrixXf band = ParallelProduct(left.middleRows(1234, 777), right);
  if (GetParam() <= 16) {
    EXPECT_EQ(band, whole);
  } else {
    EXPECT_LT((band - whole).cwiseAbs().maxCoeff() / whole.cwiseAbs().maxCoeff(), 1e-6);
  }
}

INSTANTIATE_TEST_SUITE_P(Columns, ParallelProductTest, testing::Values(1, 3, 6, 9, 16, 17, 27));

// A band decoded straight into its image data matrix (the streamed least-squares fit) is the
// same observations as the band set's: column i holds image i's planes.
TEST(ObservationsTest, FullBandMatrixEqualsTheBandSetsObservations) {
  const int width = 5, height = 3, channels = 3, images = 6;
  std::vector<Image> band;
  std::vector<LightDirection> lights;
  Eigen::MatrixXf matrix(width * height * channels, images);
  for (int i = 0; i < images; ++i) {
    const Eigen::MatrixXf values = SeededMatrix(width * height * channels, 1, 10 + i);
    Image image(width, height, channels);
    std::copy(values.data(), values.data() + values.size(), image.values().begin());
    band.push_back(std::move(image));
    matrix.col(i) = values;
    lights.push_back(LightDirection::FromSlantTilt(10.0 * i, 50.0 * i));
  }
  const Observations from_set(PhotometricSet(std::move(band), lights));
  const Observations from_matrix(matrix, width, height, channels);
  EXPECT_EQ(from_matrix.matrix(), from_set.matrix());
  EXPECT_EQ(from_matrix.pixel_indices(), from_set.pixel_indices());
  EXPECT_EQ(from_matrix.pixels(), width * height);
  EXPECT_EQ(from_matrix.Gram(), from_set.Gram());
  // A matrix of another height is not a band's.
  EXPECT_THROW(Observations(matrix, width, height + 1, channels), Error);
  EXPECT_THROW(Observations(matrix, width, height, 1), Error);
}

TEST(ObservationsTest, GatheredBandMatrixEqualsTheMaskedBandSetsObservations) {
  const int width = 5, height = 3, channels = 3, images = 6;
  Mask mask(width, height, false);
  for (std::size_t p : {1, 2, 6, 7, 8, 13}) mask.Set(p, true);
  const std::vector<std::size_t> selected = mask.SetIndices();
  const auto m = static_cast<Eigen::Index>(selected.size());
  std::vector<Image> band;
  std::vector<LightDirection> lights;
  Eigen::MatrixXf gathered(m * channels, images);
  for (int i = 0; i < images; ++i) {
    const Eigen::MatrixXf values = SeededMatrix(width * height * channels, 1, 20 + i);
    Image image(width, height, channels);
    std::copy(values.data(), values.data() + values.size(), image.values().begin());
    for (int c = 0; c < channels; ++c) {
      for (Eigen::Index k = 0; k < m; ++k) {
        gathered(c * m + k, i) = image.plane(c)[selected[static_cast<std::size_t>(k)]];
      }
    }
    band.push_back(std::move(image));
    lights.push_back(LightDirection::FromSlantTilt(10.0 * i, 50.0 * i));
  }
  PhotometricSet set(std::move(band), lights);
  set.set_mask(mask);
  const Observations from_set(set);
  const Observations from_matrix(gathered, selected, width, height, channels);
  EXPECT_EQ(from_matrix.matrix(), from_set.matrix());
  EXPECT_EQ(from_matrix.pixel_indices(), from_set.pixel_indices());
  EXPECT_EQ(from_matrix.Gram(), from_set.Gram());
  // Indices out of order, repeated or outside the band, or a matrix of another height.
  EXPECT_THROW(Observations(gathered, {1, 6, 2, 7, 8, 13}, width, height, channels), Error);
  EXPECT_THROW(Observations(gathered, {1, 2, 2, 7, 8, 13}, width, height, channels), Error);
  EXPECT_THROW(Observations(gathered, {1, 2, 6, 7, 8, 15}, width, height, channels), Error);
  EXPECT_THROW(Observations(gathered, {1, 2, 6, 7, 8}, width, height, channels), Error);
}

// The Gram pass of Eigen-k, rbf and bilinear: I^T I and the column sums, the same bits whatever
// the bands. Rows of 9001 pixels: two full blocks of 4096 and a part block whose length is not a
// multiple of the column sums' 16 lanes.
TEST(RowGramTest, EqualsTheDoubleSumsAndDoesNotDependOnTheBands) {
  const int width = 9001, height = 4, channels = 3, images = 7;
  const Eigen::Index m = Eigen::Index{width} * height;
  const Eigen::MatrixXf matrix = SeededMatrix(m * channels, images, 30);
  std::vector<std::size_t> indices(static_cast<std::size_t>(m));
  std::iota(indices.begin(), indices.end(), std::size_t{0});
  RowGram whole(images);
  whole.Add(matrix, indices, width, channels);

  const Eigen::MatrixXd exact = matrix.cast<double>().transpose() * matrix.cast<double>();
  const Eigen::VectorXd exact_sums = matrix.cast<double>().colwise().sum().transpose();
  // Float products of at most 4096 terms, summed in double: measured 4.3e-8 relative, bound 5x.
  EXPECT_LT((whole.gram() - exact).cwiseAbs().maxCoeff() / exact.cwiseAbs().maxCoeff(), 2e-7);
  // Floats added in double: measured 0 (exact here), bound at double rounding.
  EXPECT_LT((whole.column_sums() - exact_sums).cwiseAbs().maxCoeff() / exact_sums.maxCoeff(),
            1e-13);

  // Two bands of two rows each, in Observations' layout (channel-major rows of the band).
  RowGram bands(images);
  const Eigen::Index band_pixels = Eigen::Index{width} * 2;
  for (Eigen::Index first = 0; first < m; first += band_pixels) {
    Eigen::MatrixXf band(band_pixels * channels, images);
    for (int c = 0; c < channels; ++c) {
      band.middleRows(c * band_pixels, band_pixels) = matrix.middleRows(c * m + first, band_pixels);
    }
    bands.Add(band, std::span(indices).first(static_cast<std::size_t>(band_pixels)), width,
              channels);
  }
  EXPECT_EQ(bands.gram(), whole.gram());
  EXPECT_EQ(bands.column_sums(), whole.column_sums());
}

}  // namespace
}  // namespace photomat
