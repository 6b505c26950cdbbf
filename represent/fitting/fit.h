#pragma once

#include <Eigen/Core>
#include <filesystem>
#include <nlohmann/json.hpp>
#include <span>
#include <vector>

#include "core/light_direction.h"
#include "core/photometric_set.h"
#include "represent/fitting/observations.h"
#include "represent/model/method.h"
#include "represent/model/representation.h"

namespace photomat {

// Fits `method` to every image of `set` over its mask (maps are 0 outside). Least squares through
// the SVD pseudo-inverse of the lighting matrix (Gradient, PTM), the three chosen images (3I), or
// the thin SVD of the image matrix through its Gram matrix (Eigen-k). Throws Error naming the
// set's source for degenerate input: fewer images than the method needs, coplanar lights
// (Gradient, 3I), lights that do not determine a biquadratic (PTM).
Representation Fit(const PhotometricSet& set, const Method& method);

// The same on prepared observations, from the images in `selected` only (leave-one-out folds).
// `lights` holds every image's light; `source` names the data in error messages.
Representation FitObservations(const Observations& observations,
                               const std::vector<LightDirection>& lights, const Method& method,
                               std::span<const int> selected,
                               const std::filesystem::path& source = {});

// Eigen-k's light basis (thesis 4.4.5): I = U W V^T without mean subtraction; M1 = U_k W_k = I V_k
// are the basis images, M2 = V_k^T the coefficients of the fitted lights. V comes from the
// eigenvectors of the Gram matrix I^T I (IMPLEMENTER CHOICE: n x n instead of an m x n SVD; same
// M1, M2 up to sign), so a streamed fit accumulates I^T I band by band (RowGram) and then writes
// M1 band by band.
struct EigenBasis {
  Eigen::MatrixXd v;         // |S| x k, each column's sign making its basis image sum positive
  Eigen::VectorXd singular;  // all |S| singular values, descending
};
// From the Gram matrix and the column sums of the whole image matrix (all images; `selected`
// picks the rows and columns used). Throws Error naming `source` if k is not in 1..|S| or the
// eigen-decomposition fails.
EigenBasis EigenBasisFromGram(const Eigen::MatrixXd& gram, const Eigen::VectorXd& column_sums,
                              std::span<const int> selected, int k,
                              const std::filesystem::path& source = {});
// The Eigen-k representation of `observations` (a set, or a band of it) in `basis`.
Representation FitEigenWithBasis(const Observations& observations,
                                 const std::vector<LightDirection>& lights,
                                 std::span<const int> selected, const EigenBasis& basis);
// The same from basis images already computed (C*m x k, Observations' rows: the robust fit's
// imputed matrix times V); `details` are added to the representation's.
Representation EigenRepresentation(const Observations& observations, const Eigen::MatrixXf& bases,
                                   const std::vector<LightDirection>& lights,
                                   std::span<const int> selected, const EigenBasis& basis,
                                   nlohmann::json details = nlohmann::json::object());

// The three lights 3I uses among `selected` (thesis 4.4.2, IMPLEMENTER CHOICE for other sets):
// slant 45 with tilts t, t + 90, t + 180 for the smallest tilt t where all three exist (the
// thesis's 0/90/180 first; with one of them left out, the triple rotated to the next tilt);
// otherwise the best-conditioned triple (largest |det [l1 l2 l3]|). Throws Error if every triple
// is (nearly) coplanar.
std::array<int, 3> SelectThreeImageLights(const std::vector<LightDirection>& lights,
                                          std::span<const int> selected,
                                          const std::filesystem::path& source = {});

}  // namespace photomat
