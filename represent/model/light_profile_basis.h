#pragma once

#include <Eigen/Core>
#include <array>
#include <utility>
#include <vector>

#include "core/light_direction.h"
#include "represent/model/light_basis.h"
#include "represent/model/method.h"

namespace photomat {

// The light bases of the `rbf` and `bilinear` methods (README "RBF and bilinear"): each pixel's
// light profile (its values at the n captured lights) is interpolated to a new light by a fixed
// linear map, value(l) = w(l) . profile, and the profiles are compressed by PCA to k planes:
// profile ~ V V^T profile with V orthonormal (n x k), so the maps are P V and the coefficients of
// a light are c(l) = V^T w(l). V is the "pca" matrix both bases store.

// Gaussian radial basis interpolation over light directions, with a low-order tail:
//   f(l) = sum_i a_i exp(-|l - l_i|^2 / s^2) + t(l) . b,   t(l) in span(1, lx, ly, lz) (affine)
//   or span(1, lx, ly, lz, lx^2, ly^2, lx ly) (quadratic: PTM's terms and lz),
// the coefficients solving [Phi + lambda I, T; T^T, 0] [a; b] = [profile; 0]. |l - l_i| is the
// chord between unit vectors (a Gaussian of the chord is positive definite on the sphere; of the
// angle it need not be); the width is given as an angle, s = 2 sin(width / 2). The tail
// (IMPLEMENTER CHOICE) makes the interpolant reproduce affine functions of the light, so that
// outside the captured lights it follows the profile's Lambertian-like trend instead of decaying
// to 0 as a bare Gaussian sum does. Tail terms the lights do not determine (one ring of equal
// slant fixes lz) are left out: the tail is the span of t over the nodes (SVD). lambda = 0
// interpolates the nodes exactly; lambda > 0 smooths the Gaussian part only, so the tail acts as
// a least-squares base (the quadratic one a PTM) with the Gaussians interpolating its residual.
class RbfInterpolation {
 public:
  // Throws Error for fewer than 2 nodes, a width outside (0, 180] degrees, a negative
  // regularisation or a system too ill-conditioned to solve (the message names the width).
  RbfInterpolation(std::vector<LightDirection> nodes, double width_degrees, double regularisation,
                   RbfTail tail = RbfTail::kAffine);

  const std::vector<LightDirection>& nodes() const { return nodes_; }
  RbfTail tail() const { return tail_kind_; }
  double width_degrees() const { return width_degrees_; }
  double regularisation() const { return regularisation_; }

  // The kernel values and tail terms of `light`, [phi_i(l); t(l)] (n + tail terms).
  Eigen::VectorXd Features(const LightDirection& light) const;
  // w(l) = Solve() * Features(l): the n weights of the node values at `light`.
  const Eigen::MatrixXd& Solve() const { return solve_; }
  Eigen::VectorXd Weights(const LightDirection& light) const { return solve_ * Features(light); }
  // The n x n leading block of the system's inverse: with c = block * profile, the leave-one-out
  // residual of node i is c_i / block_ii (Rippa 1999; it holds with the tail and with lambda).
  const Eigen::MatrixXd& InverseBlock() const { return inverse_block_; }

 private:
  std::vector<LightDirection> nodes_;
  double width_degrees_;
  double regularisation_;
  RbfTail tail_kind_;
  double chord_width_;
  Eigen::MatrixXd tail_;  // terms x r: t(l) = tail_^T (1, lx, ly, lz[, lx^2, ly^2, lx ly])
  Eigen::MatrixXd solve_;
  Eigen::MatrixXd inverse_block_;
};

// `rbf`: c(l) = V^T w(l) with w the RbfInterpolation's weights.
class RbfLightBasis final : public LightBasis {
 public:
  // `pca` is n x k (n nodes). Throws Error for a mismatch or non-finite values.
  RbfLightBasis(RbfInterpolation interpolation, Eigen::MatrixXd pca);
  std::string_view kind() const override { return "rbf"; }
  int size() const override { return static_cast<int>(pca_.cols()); }
  Eigen::VectorXd Coefficients(const LightDirection& light) const override {
    return coefficients_ * interpolation_.Features(light);
  }
  // {"kind": "rbf", "lights": [[x, y, z]...], "width_deg", "regularisation", "tail": "affine" |
  // "quadratic", "pca": n rows of k}. A stack without "tail" (before it existed) is affine.
  nlohmann::json ToJson() const override;

  const RbfInterpolation& interpolation() const { return interpolation_; }
  const Eigen::MatrixXd& pca() const { return pca_; }

 private:
  RbfInterpolation interpolation_;
  Eigen::MatrixXd pca_;
  Eigen::MatrixXd coefficients_;  // V^T Solve(): k x (n + tail)
};

// `bilinear`: a G x G grid over the projected light plane, (lx, ly) in [-1, 1]^2, node (i, j) at
// (-1 + 2 i / (G - 1), -1 + 2 j / (G - 1)), index j * G + i. c(l) = V^T b(l), b(l) the bilinear
// weights of the light's (lx, ly) (clamped to the square) on the four surrounding nodes; V's rows
// are the PCA basis at the grid nodes.
// "affine" / "quadratic", and back (throws Error for another name).
std::string_view ToString(RbfTail tail);
RbfTail RbfTailFromString(std::string_view name);

class BilinearLightBasis final : public LightBasis {
 public:
  // `pca` is G^2 x k. Throws Error for G < 2 or a mismatch.
  BilinearLightBasis(int grid_size, Eigen::MatrixXd pca);
  std::string_view kind() const override { return "bilinear"; }
  int size() const override { return static_cast<int>(pca_.cols()); }
  Eigen::VectorXd Coefficients(const LightDirection& light) const override;
  // {"kind": "bilinear", "grid_size": G, "pca": G^2 rows of k}.
  nlohmann::json ToJson() const override;

  int grid_size() const { return grid_size_; }
  const Eigen::MatrixXd& pca() const { return pca_; }

  // The four (node, weight) pairs of (lx, ly) on a G x G grid; weights sum to 1.
  static std::array<std::pair<int, double>, 4> GridWeights(int grid_size, double lx, double ly);

 private:
  int grid_size_;
  Eigen::MatrixXd pca_;
};

}  // namespace photomat
