#include "represent/fitting/light_profile_fit.h"

#include <fmt/format.h>

#include <Eigen/Cholesky>
#include <Eigen/Eigenvalues>
#include <algorithm>
#include <cmath>
#include <limits>

#include "core/error.h"
#include "represent/model/light_profile_basis.h"

namespace photomat {
namespace {

namespace fs = std::filesystem;

// The position in LeaveOutFolds::Scores of `planes` (0: every axis).
Eigen::Index ScoreIndex(int planes, Eigen::Index fold_size) {
  return (planes == 0 ? fold_size : std::min<Eigen::Index>(planes, fold_size)) - 1;
}

// Rippa's leave-one-out weights of an RBF interpolation, e_i - B_i / B_ii; empty when a diagonal
// entry vanishes or the system cannot be solved.
Eigen::MatrixXd RbfLeaveOneOutWeights(const std::vector<LightDirection>& lights, double width,
                                      double regularisation, RbfTail tail) {
  try {
    const RbfInterpolation interpolation(lights, width, regularisation, tail);
    const Eigen::MatrixXd& block = interpolation.InverseBlock();
    Eigen::MatrixXd weights = -block;
    for (Eigen::Index i = 0; i < block.rows(); ++i) {
      const double diagonal = block(i, i);
      if (!(std::abs(diagonal) > 0.0)) return {};
      weights.row(i) /= diagonal;
      weights(i, i) = 0.0;
    }
    return weights;
  } catch (const Error&) {
    return {};
  }
}

// The leave-one-out weights of a penalised least-squares resampling, (H_i - H_ii e_i) /
// (1 - H_ii) with H = b(L) R; empty when a light is fitted alone (H_ii = 1).
Eigen::MatrixXd BilinearLeaveOneOutWeights(const std::vector<LightDirection>& lights, int grid_size,
                                           double smoothness) {
  const Eigen::MatrixXd resampling = BilinearResampling(lights, grid_size, smoothness);
  const auto n = static_cast<Eigen::Index>(lights.size());
  Eigen::MatrixXd hat(n, n);
  for (Eigen::Index i = 0; i < n; ++i) {
    Eigen::VectorXd row = Eigen::VectorXd::Zero(n);
    for (const auto& [node, w] :
         BilinearLightBasis::GridWeights(grid_size, lights[i].x(), lights[i].y())) {
      row += w * resampling.row(node).transpose();
    }
    hat.row(i) = row.transpose();
  }
  for (Eigen::Index i = 0; i < n; ++i) {
    const double rest = 1.0 - hat(i, i);
    if (!(std::abs(rest) > 1e-12)) return {};
    hat(i, i) = 0.0;
    hat.row(i) /= rest;
  }
  return hat;
}

}  // namespace

double MedianNearestNeighbourDegrees(const std::vector<LightDirection>& lights) {
  std::vector<double> nearest;
  for (std::size_t i = 0; i < lights.size(); ++i) {
    double best = 180.0;
    for (std::size_t j = 0; j < lights.size(); ++j) {
      if (j != i) best = std::min(best, lights[i].AngleToDegrees(lights[j]));
    }
    nearest.push_back(best);
  }
  std::nth_element(nearest.begin(), nearest.begin() + nearest.size() / 2, nearest.end());
  return nearest[nearest.size() / 2];
}

std::vector<Eigen::MatrixXd> RbfFoldWeights(const LeaveOutFolds& folds,
                                            const std::vector<LightDirection>& lights, double width,
                                            double regularisation, RbfTail tail) {
  std::vector<Eigen::MatrixXd> weights;
  if (OneLightFolds(folds.scheme())) {
    const Eigen::MatrixXd one = RbfLeaveOneOutWeights(lights, width, regularisation, tail);
    if (one.size() == 0) return {};
    for (const LeaveOutFolds::Fold& fold : folds.folds()) {
      weights.push_back(one(fold.held_out, fold.others));
    }
    return weights;
  }
  for (const LeaveOutFolds::Fold& fold : folds.folds()) {
    try {
      const RbfInterpolation interpolation(SelectLights(lights, fold.others), width, regularisation,
                                           tail);
      Eigen::MatrixXd fold_weights(fold.held_out.size(), fold.others.size());
      for (std::size_t h = 0; h < fold.held_out.size(); ++h) {
        fold_weights.row(static_cast<Eigen::Index>(h)) =
            interpolation.Weights(lights[fold.held_out[h]]).transpose();
      }
      weights.push_back(std::move(fold_weights));
    } catch (const Error&) {
      return {};
    }
  }
  return weights;
}

std::vector<Eigen::MatrixXd> BilinearFoldWeights(const LeaveOutFolds& folds,
                                                 const std::vector<LightDirection>& lights,
                                                 int grid_size, double smoothness) {
  std::vector<Eigen::MatrixXd> weights;
  if (OneLightFolds(folds.scheme())) {
    const Eigen::MatrixXd one = BilinearLeaveOneOutWeights(lights, grid_size, smoothness);
    if (one.size() == 0) return {};
    for (const LeaveOutFolds::Fold& fold : folds.folds()) {
      weights.push_back(one(fold.held_out, fold.others));
    }
    return weights;
  }
  for (const LeaveOutFolds::Fold& fold : folds.folds()) {
    const Eigen::MatrixXd resampling =
        BilinearResampling(SelectLights(lights, fold.others), grid_size, smoothness);
    Eigen::MatrixXd fold_weights = Eigen::MatrixXd::Zero(fold.held_out.size(), fold.others.size());
    for (std::size_t h = 0; h < fold.held_out.size(); ++h) {
      const LightDirection& l = lights[fold.held_out[h]];
      for (const auto& [node, w] : BilinearLightBasis::GridWeights(grid_size, l.x(), l.y())) {
        fold_weights.row(static_cast<Eigen::Index>(h)) += w * resampling.row(node);
      }
    }
    weights.push_back(std::move(fold_weights));
  }
  return weights;
}

namespace {

// The scores of an RBF candidate: Rippa's closed form for leave-one-out, else each fold's
// interpolation over its other lights evaluated at its left-out ones.
LeaveOutFolds::Scores RbfScores(const LeaveOutFolds& folds,
                                const std::vector<LightDirection>& lights, double width,
                                double regularisation, RbfTail tail) {
  return folds.Score(RbfFoldWeights(folds, lights, width, regularisation, tail));
}

// The scores of a bilinear smoothness, as RbfScores.
LeaveOutFolds::Scores BilinearScores(const LeaveOutFolds& folds,
                                     const std::vector<LightDirection>& lights, int grid_size,
                                     double smoothness) {
  return folds.Score(BilinearFoldWeights(folds, lights, grid_size, smoothness));
}

std::string_view ToString(LeaveOut scheme) {
  switch (scheme) {
    case LeaveOut::kBlock:
      return "leave-block-out";
    case LeaveOut::kEdge:
      return "leave-edge-out";
    case LeaveOut::kSide:
      return "leave-side-out";
    case LeaveOut::kOne:
      break;
  }
  return "leave-one-out";
}

nlohmann::json Number(double value) {
  return std::isfinite(value) ? nlohmann::json(value) : nlohmann::json();
}

// One candidate's best plane count: the largest mean_snr_db among `planes` (NaN scores never win).
struct PlaneChoice {
  int planes = 0;
  double relative_error = std::numeric_limits<double>::quiet_NaN();
  double mean_snr_db = -std::numeric_limits<double>::infinity();
};
PlaneChoice BestPlanes(const LeaveOutFolds::Scores& scores, const std::vector<int>& planes) {
  PlaneChoice best;
  best.planes = planes.front();
  for (int k : planes) {
    const Eigen::Index index = ScoreIndex(k, scores.mean_snr_db.size());
    if (scores.mean_snr_db[index] > best.mean_snr_db) {
      best = {k, scores.relative_error[index], scores.mean_snr_db[index]};
    }
  }
  return best;
}

nlohmann::json ScoresByPlanes(const LeaveOutFolds::Scores& scores, const std::vector<int>& planes) {
  nlohmann::json table = nlohmann::json::array();
  for (int k : planes) {
    const Eigen::Index index = ScoreIndex(k, scores.mean_snr_db.size());
    table.push_back({{"planes", k},
                     {"relative_error", Number(scores.relative_error[index])},
                     {"mean_snr_db", Number(scores.mean_snr_db[index])}});
  }
  return table;
}

struct PrincipalAxes {
  Eigen::MatrixXd basis;  // d x k, orthonormal columns
  Eigen::VectorXd singular_values;
};

// The k principal axes (uncentred, as Eigen-k's SVD) of profiles whose Gram matrix is `gram`;
// planes == 0: the identity (no compression).
PrincipalAxes FindPrincipalAxes(const Eigen::MatrixXd& gram, int planes, int rank_limit,
                                const std::string& method, const fs::path& source) {
  const Eigen::Index d = gram.rows();
  const Eigen::SelfAdjointEigenSolver<Eigen::MatrixXd> solver(gram);
  if (solver.info() != Eigen::Success) {
    throw Error(source, fmt::format("{}: the PCA did not converge", method));
  }
  PrincipalAxes axes;
  axes.singular_values.resize(d);
  for (Eigen::Index j = 0; j < d; ++j) {
    axes.singular_values[j] = std::sqrt(std::max(0.0, solver.eigenvalues()[d - 1 - j]));
  }
  if (planes == 0) {
    axes.basis = Eigen::MatrixXd::Identity(d, d);
    return axes;
  }
  const int k = std::min(planes, rank_limit);
  axes.basis.resize(d, k);
  for (int j = 0; j < k; ++j) axes.basis.col(j) = solver.eigenvectors().col(d - 1 - j);
  return axes;
}

nlohmann::json CumulativeInformation(const Eigen::VectorXd& singular) {
  const double total = singular.squaredNorm();
  nlohmann::json cumulative = nlohmann::json::array();
  double sum = 0.0;
  for (Eigen::Index j = 0; j < singular.size(); ++j) {
    sum += singular[j] * singular[j];
    cumulative.push_back(total > 0 ? std::sqrt(sum / total) : 0.0);
  }
  return cumulative;
}

// The projection E V (E: profile -> coordinates, n x d; V: d x k) with each plane's sign made to
// sum positive over the fitted rows, whose column sums are `column_sums` (the sum of plane j is
// column_sums . (E V)_j). V's column signs are arbitrary and flipping both keeps E V V^T; taking
// the sign from the sums, not from one band's maps, makes every band of a streamed fit agree.
Eigen::MatrixXd SignedProjection(const Eigen::VectorXd& column_sums,
                                 const Eigen::MatrixXd& to_coordinates, Eigen::MatrixXd& axes) {
  Eigen::MatrixXd projection = to_coordinates * axes;  // n x k
  for (Eigen::Index j = 0; j < projection.cols(); ++j) {
    if (column_sums.dot(projection.col(j)) < 0.0) {
      projection.col(j) *= -1.0;
      axes.col(j) *= -1.0;
    }
  }
  return projection;
}

nlohmann::json PlanesJson(int planes, const PrincipalAxes& axes) {
  const std::vector<double> singular(axes.singular_values.data(),
                                     axes.singular_values.data() + axes.singular_values.size());
  return {{"planes", planes == 0 ? "uncompressed" : nlohmann::json(axes.basis.cols())},
          {"singular_values", singular},
          {"cumulative_information", CumulativeInformation(axes.singular_values)}};
}

std::string PlanesFrom(const LightProfileOptions& options) {
  return options.planes == LightProfileOptions::kChoosePlanes
             ? std::string(ToString(options.leave_out))
             : "fixed";
}

void CheckPlanes(const LightProfileOptions& options, const std::string& method,
                 const fs::path& source) {
  if ((options.planes < 0 && options.planes != LightProfileOptions::kChoosePlanes) ||
      options.planes > 1024) {
    throw Error(source,
                fmt::format("{}: {} planes; expected 0 (no PCA) to 1024", method, options.planes));
  }
}

LightProfileModel RbfModel(const Eigen::MatrixXd& gram, const Eigen::VectorXd& column_sums,
                           const std::vector<LightDirection>& lights,
                           const LightProfileOptions& options, const fs::path& source,
                           nlohmann::json details) {
  const RbfParameters chosen = ChooseRbfParameters(lights, gram, options, source);
  PrincipalAxes axes =
      FindPrincipalAxes(gram, chosen.planes, static_cast<int>(lights.size()), "rbf", source);
  const auto n = static_cast<Eigen::Index>(lights.size());
  LightProfileModel model;
  model.method = "rbf";
  model.projection = SignedProjection(column_sums, Eigen::MatrixXd::Identity(n, n), axes.basis);
  details["rbf"] = {
      {"width_deg", chosen.width_degrees},
      {"regularisation", chosen.regularisation},
      {"tail", ToString(chosen.tail)},
      {"width_from", options.rbf_width_degrees ? "option" : ToString(options.leave_out)},
      {"regularisation_from", options.rbf_regularisation ? "option" : ToString(options.leave_out)},
      {"relative_error", Number(chosen.relative_error)},
      {"mean_snr_db", Number(chosen.mean_snr_db)},
      {"leave_one_out", chosen.leave_one_out}};
  details["pca"] = PlanesJson(chosen.planes, axes);
  details["pca"]["planes_from"] = PlanesFrom(options);
  details["pca"]["leave_one_out"] = chosen.by_planes;
  model.basis = std::make_shared<RbfLightBasis>(
      RbfInterpolation(lights, chosen.width_degrees, chosen.regularisation, chosen.tail),
      axes.basis);
  model.details = std::move(details);
  return model;
}

LightProfileModel BilinearModel(const Eigen::MatrixXd& gram, const Eigen::VectorXd& column_sums,
                                const std::vector<LightDirection>& lights,
                                const LightProfileOptions& options, const fs::path& source,
                                nlohmann::json details) {
  const int g = options.grid_size;
  if (g < 2 || g > 32) {
    throw Error(source, fmt::format("bilinear: grid size {} is outside 2..32", g));
  }
  const BilinearParameters chosen = ChooseBilinearParameters(lights, gram, options, source);
  const Eigen::MatrixXd resampling = BilinearResampling(lights, g, chosen.smoothness);  // G^2 x n
  const auto n = static_cast<Eigen::Index>(lights.size());
  LightProfileModel model;
  model.method = "bilinear";
  Eigen::MatrixXd grid_basis;  // G^2 x k: the grid values of each plane's profile
  PrincipalAxes axes =
      FindPrincipalAxes(gram, chosen.planes, static_cast<int>(n), "bilinear", source);
  if (chosen.planes == 0) {
    // Uncompressed: every grid node is a plane, the maps are the grid profiles R p.
    grid_basis = Eigen::MatrixXd::Identity(g * g, g * g);
    model.projection = SignedProjection(column_sums, resampling.transpose(), grid_basis);
  } else {
    // IMPLEMENTER CHOICE: the PCA runs over the captured profiles (p ~ V V^T p, as rbf), and the
    // grid holds the resampled axes R V, so value(l) = b(l) . R V (V^T p). A PCA over the grid
    // profiles R p instead weighs every node alike, and spends its planes on the extrapolated
    // corners no light reaches (DiLiGenT cat, 10 held-out lights: 27.1 dB against 33+).
    model.projection = SignedProjection(column_sums, Eigen::MatrixXd::Identity(n, n), axes.basis);
    grid_basis = resampling * axes.basis;
  }
  details["pca"] = PlanesJson(chosen.planes, axes);
  details["pca"]["planes_from"] = PlanesFrom(options);
  details["pca"]["leave_one_out"] = chosen.by_planes;
  details["bilinear"] = {
      {"grid_size", g},
      {"smoothness", chosen.smoothness},
      {"smoothness_from", options.bilinear_smoothness ? "option" : ToString(options.leave_out)},
      {"relative_error", Number(chosen.relative_error)},
      {"mean_snr_db", Number(chosen.mean_snr_db)},
      {"leave_one_out", chosen.leave_one_out}};
  model.basis = std::make_shared<BilinearLightBasis>(g, grid_basis);
  model.details = std::move(details);
  return model;
}

}  // namespace

namespace {

constexpr double kHullTolerance = 0.02;

std::vector<Eigen::Vector2d> Projected(const std::vector<LightDirection>& lights) {
  std::vector<Eigen::Vector2d> points;
  for (const LightDirection& l : lights) points.emplace_back(l.x(), l.y());
  return points;
}

// The convex hull's vertices, counter-clockwise (Andrew's monotone chain: the lower hull, then
// the upper).
std::vector<int> HullVertices(const std::vector<Eigen::Vector2d>& points) {
  std::vector<int> order(points.size());
  for (std::size_t i = 0; i < order.size(); ++i) order[i] = static_cast<int>(i);
  std::sort(order.begin(), order.end(), [&](int a, int b) {
    return points[a].x() < points[b].x() ||
           (points[a].x() == points[b].x() && points[a].y() < points[b].y());
  });
  const auto turn = [&](int o, int a, int b) {
    const Eigen::Vector2d u = points[a] - points[o], v = points[b] - points[o];
    return u.x() * v.y() - u.y() * v.x();
  };
  std::vector<int> hull;
  for (int pass = 0; pass < 2; ++pass) {
    const std::size_t start = hull.size();
    for (int i : order) {
      while (hull.size() >= start + 2 && turn(hull[hull.size() - 2], hull.back(), i) <= 0) {
        hull.pop_back();
      }
      hull.push_back(i);
    }
    hull.pop_back();
    std::reverse(order.begin(), order.end());
  }
  return hull;
}

// Whether `point` lies within kHullTolerance of the hull edge from vertex e to e + 1.
bool NearHullEdge(const std::vector<Eigen::Vector2d>& points, const std::vector<int>& hull,
                  std::size_t e, const Eigen::Vector2d& point) {
  const Eigen::Vector2d a = points[hull[e]], d = points[hull[(e + 1) % hull.size()]] - a;
  const double along =
      d.squaredNorm() > 0.0 ? std::clamp((point - a).dot(d) / d.squaredNorm(), 0.0, 1.0) : 0.0;
  return (a + along * d - point).norm() < kHullTolerance;
}

// The angle from direction a to direction b in (-pi, pi].
double TurnAngle(const Eigen::Vector2d& a, const Eigen::Vector2d& b) {
  return std::atan2(a.x() * b.y() - a.y() * b.x(), a.dot(b));
}

}  // namespace

std::vector<int> HullBoundaryLights(const std::vector<LightDirection>& lights) {
  const std::vector<Eigen::Vector2d> points = Projected(lights);
  const std::vector<int> hull = HullVertices(points);
  std::vector<int> boundary;
  for (std::size_t t = 0; t < points.size(); ++t) {
    for (std::size_t e = 0; e < hull.size(); ++e) {
      if (NearHullEdge(points, hull, e, points[t])) {
        boundary.push_back(static_cast<int>(t));
        break;
      }
    }
  }
  return boundary;
}

std::vector<std::vector<int>> HullSideLights(const std::vector<LightDirection>& lights) {
  const std::vector<Eigen::Vector2d> points = Projected(lights);
  const std::vector<int> hull = HullVertices(points);
  const std::size_t m = hull.size();
  if (m < 3) return {HullBoundaryLights(lights)};
  std::vector<Eigen::Vector2d> direction(m);
  for (std::size_t e = 0; e < m; ++e) direction[e] = points[hull[(e + 1) % m]] - points[hull[e]];
  // Start at the sharpest corner, then group consecutive edges into one side while they turn less
  // than kSideTurn from the side's first edge.
  constexpr double kSideTurn = M_PI / 4.0;
  std::size_t start = 0;
  double sharpest = -1.0;
  for (std::size_t e = 0; e < m; ++e) {
    const double turn = std::abs(TurnAngle(direction[(e + m - 1) % m], direction[e]));
    if (turn > sharpest) sharpest = turn, start = e;
  }
  std::vector<std::vector<std::size_t>> sides;
  for (std::size_t step = 0; step < m; ++step) {
    const std::size_t e = (start + step) % m;
    if (sides.empty() ||
        std::abs(TurnAngle(direction[sides.back().front()], direction[e])) > kSideTurn) {
      sides.emplace_back();
    }
    sides.back().push_back(e);
  }
  std::vector<std::vector<int>> side_lights;
  for (const std::vector<std::size_t>& side : sides) {
    std::vector<int> members;
    for (std::size_t t = 0; t < points.size(); ++t) {
      for (std::size_t e : side) {
        if (NearHullEdge(points, hull, e, points[t])) {
          members.push_back(static_cast<int>(t));
          break;
        }
      }
    }
    side_lights.push_back(std::move(members));
  }
  return side_lights;
}

LeaveOutFolds::LeaveOutFolds(const Eigen::MatrixXd& gram, LeaveOut scheme,
                             const std::vector<LightDirection>& lights)
    : scheme_(scheme), diagonal_(gram.diagonal()) {
  const auto n = static_cast<int>(gram.rows());
  std::vector<std::vector<int>> held_out;
  if (scheme == LeaveOut::kEdge) {
    if (static_cast<int>(lights.size()) != n) {
      throw Error(
          fmt::format("leave-edge-out: {} lights for a {}x{} Gram matrix", lights.size(), n, n));
    }
    for (int i : HullBoundaryLights(lights)) held_out.push_back({i});
  } else if (scheme == LeaveOut::kSide) {
    if (static_cast<int>(lights.size()) != n) {
      throw Error(
          fmt::format("leave-side-out: {} lights for a {}x{} Gram matrix", lights.size(), n, n));
    }
    held_out = HullSideLights(lights);
  } else if (scheme == LeaveOut::kBlock) {
    for (int offset = 0; offset < std::min(kBlockStride, n); ++offset) {
      held_out.emplace_back();
      for (int i = offset; i < n; i += kBlockStride) held_out.back().push_back(i);
    }
  } else {
    const int stride = (n + kMaxFolds - 1) / kMaxFolds;
    for (int i = 0; i < n; i += stride) held_out.push_back({i});
  }
  plane_entries_ = std::numeric_limits<Eigen::Index>::max();
  for (std::vector<int>& left_out : held_out) {
    Fold fold;
    fold.held_out = std::move(left_out);
    for (int j = 0; j < n; ++j) {
      if (!std::binary_search(fold.held_out.begin(), fold.held_out.end(), j)) {
        fold.others.push_back(j);
      }
    }
    if (fold.others.empty()) continue;
    const Eigen::MatrixXd rest = gram(fold.others, fold.others);
    const Eigen::SelfAdjointEigenSolver<Eigen::MatrixXd> solver(rest);
    if (solver.info() != Eigen::Success) continue;  // leaves this fold out
    fold.axes = solver.eigenvectors().rowwise().reverse();
    fold.eigenvalues = solver.eigenvalues().reverse();
    fold.cross = fold.axes.transpose() * gram(fold.others, fold.held_out);
    plane_entries_ = std::min<Eigen::Index>(plane_entries_, fold.others.size());
    folds_.push_back(std::move(fold));
  }
  if (folds_.empty()) plane_entries_ = std::max(1, n - 1);
}

LeaveOutFolds::Scores LeaveOutFolds::Score(const Eigen::MatrixXd& weights) const {
  if (!OneLightFolds(scheme_) || weights.rows() != diagonal_.size() ||
      weights.cols() != diagonal_.size()) {
    const double nan = std::numeric_limits<double>::quiet_NaN();
    return {Eigen::VectorXd::Constant(plane_entries_, nan),
            Eigen::VectorXd::Constant(plane_entries_, nan)};
  }
  return Score(
      [&](const Fold& fold) -> Eigen::MatrixXd { return weights(fold.held_out, fold.others); });
}

LeaveOutFolds::Scores LeaveOutFolds::Score(const std::vector<Eigen::MatrixXd>& weights) const {
  if (weights.size() != folds_.size()) {
    const double nan = std::numeric_limits<double>::quiet_NaN();
    return {Eigen::VectorXd::Constant(plane_entries_, nan),
            Eigen::VectorXd::Constant(plane_entries_, nan)};
  }
  return Score([&](const Fold& fold) -> Eigen::MatrixXd {
    return weights[static_cast<std::size_t>(&fold - folds_.data())];
  });
}

LeaveOutFolds::Scores LeaveOutFolds::Score(const FoldWeights& weights) const {
  const Eigen::Index size = plane_entries_;
  const double nan = std::numeric_limits<double>::quiet_NaN();
  const Scores failed{Eigen::VectorXd::Constant(size, nan), Eigen::VectorXd::Constant(size, nan)};
  Scores scores{Eigen::VectorXd::Zero(size), Eigen::VectorXd::Zero(size)};
  if (folds_.empty()) return failed;
  double total = 0.0;
  int left_out = 0;
  for (const Fold& fold : folds_) {
    const Eigen::MatrixXd w = weights(fold);
    const auto held = static_cast<Eigen::Index>(fold.held_out.size());
    const auto others = static_cast<Eigen::Index>(fold.others.size());
    if (w.rows() != held || w.cols() != others || !w.allFinite()) return failed;
    for (Eigen::Index h = 0; h < held; ++h) {
      const Eigen::VectorXd a = fold.axes.transpose() * w.row(h).transpose();
      const double signal = diagonal_[fold.held_out[h]];
      double error = signal;
      // Entry j < size - 1: j + 1 planes; the last entry: every axis of the fold.
      for (Eigen::Index j = 0; j < others; ++j) {
        error += fold.eigenvalues[j] * a[j] * a[j] - 2.0 * a[j] * fold.cross(j, h);
        if (j < size - 1 || j == others - 1) {
          const Eigen::Index entry = std::min(j, size - 1);
          const double positive = std::max(error, 1e-300);
          scores.relative_error[entry] += positive;
          // An empty image (signal 0) predicted exactly carries no information: 0 dB.
          scores.mean_snr_db[entry] += signal > 0.0 ? 10.0 * std::log10(signal / positive) : 0.0;
        }
      }
      total += signal;
      ++left_out;
    }
  }
  if (total > 0.0) {
    scores.relative_error = (scores.relative_error / total).cwiseSqrt();
  } else {
    scores.relative_error.setZero();
  }
  scores.mean_snr_db /= static_cast<double>(left_out);
  return scores;
}

std::vector<int> CandidatePlanes(const LightProfileOptions& options, int lights) {
  if (options.planes >= 0) return {options.planes};
  std::vector<int> planes;
  for (int k = 1; k <= std::min(LightProfileOptions::kMaxChosenPlanes, lights - 1); ++k) {
    planes.push_back(k);
  }
  return planes;
}

RbfParameters ChooseRbfParameters(const std::vector<LightDirection>& lights,
                                  const Eigen::MatrixXd& gram, const LightProfileOptions& options,
                                  const fs::path& source) {
  if (lights.size() < 4) {
    throw Error(source, fmt::format("rbf: {} lights; at least 4 are needed", lights.size()));
  }
  std::vector<double> widths, regularisations;
  if (options.rbf_width_degrees) {
    widths.push_back(*options.rbf_width_degrees);
  } else {
    const double spacing = MedianNearestNeighbourDegrees(lights);
    for (double factor : kRbfWidthFactors) widths.push_back(std::min(180.0, factor * spacing));
  }
  if (options.rbf_regularisation) {
    regularisations.push_back(*options.rbf_regularisation);
  } else {
    regularisations.assign(kRbfRegularisations.begin(), kRbfRegularisations.end());
  }
  const RbfTail tail = options.rbf_tail;
  const std::vector<int> planes = CandidatePlanes(options, static_cast<int>(lights.size()));
  const LeaveOutFolds folds(gram, options.leave_out, lights);
  RbfParameters best;
  best.tail = tail;
  best.mean_snr_db = -std::numeric_limits<double>::infinity();
  best.leave_one_out = nlohmann::json::array();
  for (double width : widths) {
    for (double regularisation : regularisations) {
      const PlaneChoice choice =
          BestPlanes(RbfScores(folds, lights, width, regularisation, tail), planes);
      best.leave_one_out.push_back({{"width_deg", width},
                                    {"regularisation", regularisation},
                                    {"planes", choice.planes},
                                    {"relative_error", Number(choice.relative_error)},
                                    {"mean_snr_db", Number(choice.mean_snr_db)}});
      if (choice.mean_snr_db > best.mean_snr_db) {
        best.width_degrees = width;
        best.regularisation = regularisation;
        best.planes = choice.planes;
        best.relative_error = choice.relative_error;
        best.mean_snr_db = choice.mean_snr_db;
      }
    }
  }
  if (std::isfinite(best.mean_snr_db)) {
    best.by_planes = ScoresByPlanes(
        RbfScores(folds, lights, best.width_degrees, best.regularisation, best.tail), planes);
  }
  if (!std::isfinite(best.mean_snr_db)) {
    // Rebuild the first candidate to report why it fails (or the options' fault).
    try {
      RbfInterpolation(lights, widths.front(), regularisations.front(), tail);
    } catch (const Error& error) {
      throw Error(source, error.fault());
    }
    throw Error(source, "rbf: no kernel width and regularisation give a usable fit");
  }
  return best;
}

BilinearParameters ChooseBilinearParameters(const std::vector<LightDirection>& lights,
                                            const Eigen::MatrixXd& gram,
                                            const LightProfileOptions& options,
                                            const fs::path& source) {
  if (lights.size() < 2) {
    throw Error(source, fmt::format("bilinear: {} lights; at least 2 are needed", lights.size()));
  }
  const std::vector<int> planes = CandidatePlanes(options, static_cast<int>(lights.size()));
  const LeaveOutFolds folds(gram, options.leave_out, lights);
  BilinearParameters best;
  best.mean_snr_db = -std::numeric_limits<double>::infinity();
  best.planes = planes.front();
  best.leave_one_out = nlohmann::json::array();
  std::vector<double> smoothnesses(kBilinearSmoothnesses.begin(), kBilinearSmoothnesses.end());
  if (options.bilinear_smoothness) smoothnesses = {*options.bilinear_smoothness};
  for (double smoothness : smoothnesses) {
    const LeaveOutFolds::Scores scores =
        BilinearScores(folds, lights, options.grid_size, smoothness);
    const PlaneChoice choice = BestPlanes(scores, planes);
    best.leave_one_out.push_back({{"smoothness", smoothness},
                                  {"planes", choice.planes},
                                  {"relative_error", Number(choice.relative_error)},
                                  {"mean_snr_db", Number(choice.mean_snr_db)}});
    if (choice.mean_snr_db > best.mean_snr_db) {
      best.smoothness = smoothness;
      best.planes = choice.planes;
      best.relative_error = choice.relative_error;
      best.mean_snr_db = choice.mean_snr_db;
      best.by_planes = ScoresByPlanes(scores, planes);
    }
  }
  if (!std::isfinite(best.mean_snr_db)) {
    // No candidate scores (e.g. a light alone in its grid cells at smoothness 0): the first
    // candidate still fits; the choice is recorded without scores.
    best.smoothness = smoothnesses.front();
    best.relative_error = std::numeric_limits<double>::quiet_NaN();
    best.by_planes = nlohmann::json::array();
  }
  return best;
}

Eigen::MatrixXd BilinearResampling(const std::vector<LightDirection>& lights, int grid_size,
                                   double smoothness) {
  const int g = grid_size;
  const Eigen::Index nodes = static_cast<Eigen::Index>(g) * g;
  const auto n = static_cast<Eigen::Index>(lights.size());
  Eigen::MatrixXd weights = Eigen::MatrixXd::Zero(n, nodes);  // b(l_i) as rows
  for (Eigen::Index i = 0; i < n; ++i) {
    for (const auto& [node, w] : BilinearLightBasis::GridWeights(g, lights[i].x(), lights[i].y())) {
      weights(i, node) += w;
    }
  }
  Eigen::MatrixXd normal = weights.transpose() * weights;
  // D^T D of the second differences along both grid axes.
  const auto add_difference = [&](int a, int b, int c) {
    const std::array<int, 3> index = {a, b, c};
    const std::array<double, 3> coefficient = {1.0, -2.0, 1.0};
    for (int r = 0; r < 3; ++r) {
      for (int s = 0; s < 3; ++s) {
        normal(index[r], index[s]) += smoothness * coefficient[r] * coefficient[s];
      }
    }
  };
  for (int j = 0; j < g; ++j) {
    for (int i = 1; i + 1 < g; ++i) {
      add_difference(j * g + i - 1, j * g + i, j * g + i + 1);      // along lx
      add_difference((i - 1) * g + j, i * g + j, (i + 1) * g + j);  // along ly
    }
  }
  const Eigen::LDLT<Eigen::MatrixXd> ldlt(normal);
  return ldlt.solve(weights.transpose());
}

LightProfileModel FitLightProfileModel(const Eigen::MatrixXd& gram,
                                       const Eigen::VectorXd& column_sums,
                                       const std::vector<LightDirection>& lights,
                                       const Method& method, const fs::path& source,
                                       nlohmann::json details) {
  CheckPlanes(method.profile, method.Name(), source);
  if (gram.rows() != gram.cols() || static_cast<std::size_t>(gram.rows()) != lights.size() ||
      column_sums.size() != gram.rows()) {
    throw Error(source,
                fmt::format("{}: {} lights, {} column sums and a {}x{} Gram matrix", method.Name(),
                            lights.size(), column_sums.size(), gram.rows(), gram.cols()));
  }
  if (method.kind == Method::Kind::kBilinear) {
    return BilinearModel(gram, column_sums, lights, method.profile, source, std::move(details));
  }
  if (method.kind != Method::Kind::kRbf) {
    throw Error(source, fmt::format("{} is not a light-profile method", method.Name()));
  }
  return RbfModel(gram, column_sums, lights, method.profile, source, std::move(details));
}

LightProfileModel FitLightProfileModel(const Eigen::MatrixXd& gram,
                                       const Eigen::VectorXd& column_sums,
                                       const std::vector<LightDirection>& lights,
                                       std::span<const int> selected, const Method& method,
                                       const fs::path& source) {
  const auto n = static_cast<Eigen::Index>(selected.size());
  Eigen::MatrixXd sub(n, n);
  Eigen::VectorXd sums(n);
  std::vector<LightDirection> selected_lights;
  for (Eigen::Index a = 0; a < n; ++a) {
    for (Eigen::Index b = 0; b < n; ++b) sub(a, b) = gram(selected[a], selected[b]);
    sums[a] = column_sums[selected[a]];
    selected_lights.push_back(lights[static_cast<std::size_t>(selected[a])]);
  }
  return FitLightProfileModel(sub, sums, selected_lights, method, source);
}

Representation ProjectLightProfiles(const LightProfileModel& model,
                                    const Observations& observations, const Eigen::MatrixXf& matrix,
                                    std::span<const int> columns) {
  if (static_cast<std::size_t>(model.projection.rows()) != columns.size()) {
    throw Error(fmt::format("{}: a model of {} profile entries projects {} columns", model.method,
                            model.projection.rows(), columns.size()));
  }
  const Eigen::Index k = model.projection.cols();
  Eigen::MatrixXf scattered = Eigen::MatrixXf::Zero(matrix.cols(), k);
  for (std::size_t i = 0; i < columns.size(); ++i) {
    scattered.row(columns[i]) = model.projection.row(static_cast<Eigen::Index>(i)).cast<float>();
  }
  const Eigen::MatrixXf planes = ParallelProduct(matrix, scattered);
  const int channels = observations.channels();
  Image maps(
      observations.width(), observations.height(),
      CoefficientMapNames(model.method + ".", static_cast<int>(k), OutputChannelNames(channels)));
  StorePerChannelTerms(observations, planes, maps);
  return Representation(model.method, std::move(maps), {static_cast<int>(k), true, false, channels},
                        model.basis, model.details);
}

}  // namespace photomat
