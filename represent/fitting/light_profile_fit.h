#pragma once

#include <Eigen/Core>
#include <filesystem>
#include <nlohmann/json.hpp>
#include <span>
#include <vector>

#include "core/light_direction.h"
#include "represent/fitting/observations.h"
#include "represent/model/method.h"
#include "represent/model/representation.h"

namespace photomat {

// The fits of the light-profile methods `rbf` and `bilinear`
// (represent/model/light_profile_basis.h, README "RBF and bilinear").

// The RBF's kernel width and regularisation: the options' values where set, otherwise those of
// least leave-one-out error over the capture itself. With c = B p (B the system inverse's n x n
// block, p a profile) the residual of leaving light i out is c_i / B_ii (Rippa), so the error
// summed over every profile row is sum_i (B G B)_ii / B_ii^2 with G = P^T P, the n x n Gram matrix
// of the fitted images: a whole search costs a few n^3 solves and no pass over the pixels.
// Candidates (IMPLEMENTER CHOICE): widths 0.5 .. 4 times the median angle from a light to its
// nearest neighbour (7 steps of sqrt 2), regularisation 0 and 1e-5 .. 1e-1 (decades; the kernel
// matrix's diagonal is 1). `leave_one_out` lists every candidate's relative error
// sqrt(sum / trace G).
struct RbfParameters {
  double width_degrees = 0.0;
  double regularisation = 0.0;
  nlohmann::json leave_one_out;  // [{"width_deg", "regularisation", "relative_error"}...]
};
RbfParameters ChooseRbfParameters(const std::vector<LightDirection>& lights,
                                  const Eigen::MatrixXd& gram, const LightProfileOptions& options,
                                  const std::filesystem::path& source = {});

// The bilinear grid's resampling: grid values g of a profile p minimise
//   sum_i (b(l_i) . g - p_i)^2 + kBilinearSmoothness * |D g|^2,
// b the bilinear weights, D the second differences of the grid along lx and along ly
// (IMPLEMENTER CHOICE: the data term makes the grid reproduce the captured lights, the small
// curvature term fills cells no light falls in smoothly and extrapolates linearly). Returns R,
// G^2 x n, with g = R p.
inline constexpr double kBilinearSmoothness = 1e-4;
Eigen::MatrixXd BilinearResampling(const std::vector<LightDirection>& lights, int grid_size);

// Fits `method` (rbf or bilinear) to the columns `columns` of `matrix` (rows in `observations`'
// order; the observations' own matrix or an imputed copy), whose lights are `lights` (one per
// entry of `columns`) and Gram matrix `gram` (|columns| x |columns|). `details` are kept and the
// fit's own added. Throws Error naming `source` for degenerate lights or options.
Representation FitLightProfiles(const Observations& observations, const Eigen::MatrixXf& matrix,
                                std::span<const int> columns, const Eigen::MatrixXd& gram,
                                const std::vector<LightDirection>& lights, const Method& method,
                                const std::filesystem::path& source = {},
                                nlohmann::json details = nlohmann::json::object());

}  // namespace photomat
