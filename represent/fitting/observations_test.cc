#include "represent/fitting/observations.h"

#include <gtest/gtest.h>

#include <random>

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
  const Eigen::MatrixXf left = SeededMatrix(9001, 96, 1);  // rows not a multiple of any block
  const Eigen::MatrixXf right = SeededMatrix(96, GetParam(), 2);
  const Eigen::MatrixXd exact = left.cast<double>() * right.cast<double>();
  const Eigen::MatrixXf product = ParallelProduct(left, right);
  // 96 float products summed in float: a relative error of a few 1e-7 on sums of about 24.
  EXPECT_LT((product.cast<double>() - exact).cwiseAbs().maxCoeff() / exact.cwiseAbs().maxCoeff(),
            2e-6);
}

TEST_P(ParallelProductTest, RowsDoNotDependOnTheBandTheyCameFrom) {
  // A streamed fit multiplies bands of rows; up to 16 columns (terms: Gradient, PTM, HSH,
  // Eigen-k and rbf/bilinear planes up to 16) a row gives the same bits in any band. Eigen's GEMM
  // beyond that vectorises a band's rows by their position in it, so its rows agree to float
  // rounding only (measured: a few 1e-7 relative).
  const Eigen::MatrixXf left = SeededMatrix(5000, 40, 3);
  const Eigen::MatrixXf right = SeededMatrix(40, GetParam(), 4);
  const Eigen::MatrixXf whole = ParallelProduct(left, right).middleRows(1234, 777);
  const Eigen::MatrixXf band = ParallelProduct(left.middleRows(1234, 777), right);
  if (GetParam() <= 16) {
    EXPECT_EQ(band, whole);
  } else {
    EXPECT_LT((band - whole).cwiseAbs().maxCoeff() / whole.cwiseAbs().maxCoeff(), 1e-6);
  }
}

INSTANTIATE_TEST_SUITE_P(Columns, ParallelProductTest, testing::Values(3, 6, 16, 17, 27));

}  // namespace
}  // namespace photomat
