#include "represent/model/light_profile_basis.h"

#include <fmt/format.h>

#include <Eigen/LU>
#include <Eigen/SVD>
#include <algorithm>
#include <cmath>

#include "core/error.h"
#include "core/json_file.h"

namespace photomat {
namespace {

// Below this reciprocal condition number the RBF system's solution is rounding noise (a width
// far above the lights' spacing makes the Gaussian kernel matrix numerically singular).
constexpr double kMinimumReciprocalCondition = 1e-13;
// Tail directions whose singular value is below this fraction of the largest are not determined
// by the nodes (e.g. lz on one ring of equal slant).
constexpr double kTailRankLimit = 1e-6;

Eigen::VectorXd TailTerms(RbfTail tail, const LightDirection& l) {
  if (tail == RbfTail::kAffine) return Eigen::Vector4d(1.0, l.x(), l.y(), l.z());
  Eigen::VectorXd terms(7);
  terms << 1.0, l.x(), l.y(), l.z(), l.x() * l.x(), l.y() * l.y(), l.x() * l.y();
  return terms;
}

}  // namespace

RbfInterpolation::RbfInterpolation(std::vector<LightDirection> nodes, double width_degrees,
                                   double regularisation, RbfTail tail)
    : nodes_(std::move(nodes)),
      width_degrees_(width_degrees),
      regularisation_(regularisation),
      tail_kind_(tail) {
  const auto n = static_cast<Eigen::Index>(nodes_.size());
  if (n < 2) throw Error(fmt::format("rbf: {} lights; the interpolation needs at least 2", n));
  if (!(width_degrees_ > 0.0 && width_degrees_ <= 180.0)) {
    throw Error(fmt::format("rbf: kernel width {} degrees is outside (0, 180]", width_degrees_));
  }
  if (!(regularisation_ >= 0.0) || !std::isfinite(regularisation_)) {
    throw Error(
        fmt::format("rbf: regularisation {} must be a finite number >= 0", regularisation_));
  }
  chord_width_ = 2.0 * std::sin(width_degrees_ * M_PI / 360.0);
  const auto term_count = TailTerms(tail_kind_, nodes_[0]).size();
  Eigen::MatrixXd terms(n, term_count);
  for (Eigen::Index i = 0; i < n; ++i) terms.row(i) = TailTerms(tail_kind_, nodes_[i]).transpose();
  const Eigen::JacobiSVD<Eigen::MatrixXd> svd(terms, Eigen::ComputeFullV);
  Eigen::Index rank = 0;
  while (rank < svd.singularValues().size() &&
         svd.singularValues()[rank] > kTailRankLimit * svd.singularValues()[0]) {
    ++rank;
  }
  rank = std::min(rank, n - 1);  // keep at least one kernel degree of freedom
  tail_ = svd.matrixV().leftCols(rank);

  const Eigen::Index size = n + rank;
  Eigen::MatrixXd system = Eigen::MatrixXd::Zero(size, size);
  for (Eigen::Index i = 0; i < n; ++i) {
    system.row(i) = Features(nodes_[i]).transpose();
    system(i, i) += regularisation_;
  }
  system.bottomLeftCorner(rank, n) = (terms * tail_).transpose();
  const Eigen::PartialPivLU<Eigen::MatrixXd> lu(system);
  const double rcond = lu.rcond();
  if (!(rcond > kMinimumReciprocalCondition)) {
    throw Error(fmt::format(
        "rbf: the system of {} lights at kernel width {:.3g} degrees and regularisation {:.3g} "
        "is singular (reciprocal condition {:.2g}); use a smaller width or some regularisation",
        n, width_degrees_, regularisation_, rcond));
  }
  const Eigen::MatrixXd inverse = lu.inverse();
  // The system is symmetric, so is its inverse: the rows of the first n give w(l).
  solve_ = inverse.topRows(n);
  inverse_block_ = inverse.topLeftCorner(n, n);
}

Eigen::VectorXd RbfInterpolation::Features(const LightDirection& light) const {
  const auto n = static_cast<Eigen::Index>(nodes_.size());
  Eigen::VectorXd features(n + tail_.cols());
  const double scale = 1.0 / (chord_width_ * chord_width_);
  for (Eigen::Index i = 0; i < n; ++i) {
    features[i] = std::exp(-(light.vector() - nodes_[i].vector()).squaredNorm() * scale);
  }
  features.tail(tail_.cols()) = tail_.transpose() * TailTerms(tail_kind_, light);
  return features;
}

RbfLightBasis::RbfLightBasis(RbfInterpolation interpolation, Eigen::MatrixXd pca)
    : interpolation_(std::move(interpolation)), pca_(std::move(pca)) {
  if (pca_.rows() != static_cast<Eigen::Index>(interpolation_.nodes().size()) || pca_.cols() == 0 ||
      !pca_.allFinite()) {
    throw Error(fmt::format("rbf light basis: a {}x{} PCA basis for {} lights", pca_.rows(),
                            pca_.cols(), interpolation_.nodes().size()));
  }
  coefficients_ = pca_.transpose() * interpolation_.Solve();
}

nlohmann::json RbfLightBasis::ToJson() const {
  nlohmann::json lights = nlohmann::json::array();
  for (const LightDirection& l : interpolation_.nodes()) lights.push_back({l.x(), l.y(), l.z()});
  return {{"kind", "rbf"},
          {"lights", std::move(lights)},
          {"width_deg", interpolation_.width_degrees()},
          {"regularisation", interpolation_.regularisation()},
          {"tail", ToString(interpolation_.tail())},
          {"pca", MatrixToJson(pca_)}};
}

std::string_view ToString(RbfTail tail) {
  return tail == RbfTail::kQuadratic ? "quadratic" : "affine";
}

RbfTail RbfTailFromString(std::string_view name) {
  if (name == "affine") return RbfTail::kAffine;
  if (name == "quadratic") return RbfTail::kQuadratic;
  throw Error(fmt::format("rbf: tail \"{}\"; expected \"affine\" or \"quadratic\"", name));
}

BilinearLightBasis::BilinearLightBasis(int grid_size, Eigen::MatrixXd pca)
    : grid_size_(grid_size), pca_(std::move(pca)) {
  if (grid_size_ < 2 || grid_size_ > 256) {
    throw Error(fmt::format("bilinear light basis: grid size {} is outside 2..256", grid_size_));
  }
  if (pca_.rows() != static_cast<Eigen::Index>(grid_size_) * grid_size_ || pca_.cols() == 0 ||
      !pca_.allFinite()) {
    throw Error(fmt::format("bilinear light basis: a {}x{} PCA basis for a {}x{} grid", pca_.rows(),
                            pca_.cols(), grid_size_, grid_size_));
  }
}

std::array<std::pair<int, double>, 4> BilinearLightBasis::GridWeights(int grid_size, double lx,
                                                                      double ly) {
  const double last = grid_size - 1;
  const double u = std::clamp((lx + 1.0) * 0.5 * last, 0.0, last);
  const double v = std::clamp((ly + 1.0) * 0.5 * last, 0.0, last);
  const int i = std::min(static_cast<int>(u), grid_size - 2);
  const int j = std::min(static_cast<int>(v), grid_size - 2);
  const double fu = u - i, fv = v - j;
  const int node = j * grid_size + i;
  return {{{node, (1 - fu) * (1 - fv)},
           {node + 1, fu * (1 - fv)},
           {node + grid_size, (1 - fu) * fv},
           {node + grid_size + 1, fu * fv}}};
}

Eigen::VectorXd BilinearLightBasis::Coefficients(const LightDirection& light) const {
  Eigen::VectorXd c = Eigen::VectorXd::Zero(pca_.cols());
  for (const auto& [node, weight] : GridWeights(grid_size_, light.x(), light.y())) {
    c += weight * pca_.row(node).transpose();
  }
  return c;
}

nlohmann::json BilinearLightBasis::ToJson() const {
  return {{"kind", "bilinear"}, {"grid_size", grid_size_}, {"pca", MatrixToJson(pca_)}};
}

}  // namespace photomat
