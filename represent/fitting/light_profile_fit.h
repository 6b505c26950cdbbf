#pragma once

#include <Eigen/Core>
#include <filesystem>
#include <memory>
#include <nlohmann/json.hpp>
#include <span>
#include <string>
#include <vector>

#include "core/light_direction.h"
#include "represent/fitting/observations.h"
#include "represent/model/light_basis.h"
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

// A light-profile fit's model: everything of it but the maps. It follows from the fitted profiles'
// Gram matrix and column sums alone (the kernel width and regularisation by leave-one-out, the
// PCA axes, each plane's sign), so a streamed fit finds it in one pass over the bands and then
// projects every band with it; the in-memory fit is the one-band case.
struct LightProfileModel {
  std::string method;                       // "rbf" or "bilinear"
  Eigen::MatrixXd projection;               // n x k: a profile's k plane coefficients
  std::shared_ptr<const LightBasis> basis;  // from the k planes to a light's value
  nlohmann::json details;
};

// The model of `method` (rbf or bilinear) for profiles over `lights` whose Gram matrix is `gram`
// (n x n) and column sums `column_sums` (n). `details` are kept and the fit's own added. Throws
// Error naming `source` for degenerate lights or options.
LightProfileModel FitLightProfileModel(const Eigen::MatrixXd& gram,
                                       const Eigen::VectorXd& column_sums,
                                       const std::vector<LightDirection>& lights,
                                       const Method& method,
                                       const std::filesystem::path& source = {},
                                       nlohmann::json details = nlohmann::json::object());

// The maps of `model` for the columns `columns` of `matrix` (rows in `observations`' order; the
// observations' own matrix or an imputed copy; entry i of the model's profile is column
// columns[i]).
Representation ProjectLightProfiles(const LightProfileModel& model,
                                    const Observations& observations, const Eigen::MatrixXf& matrix,
                                    std::span<const int> columns);

}  // namespace photomat
