#include "calibrate/lights/mirror_sphere_refinement.h"

#include <ceres/ceres.h>
#include <ceres/covariance.h>
#include <ceres/sphere_manifold.h>
#include <fmt/format.h>

#include <Eigen/Dense>
#include <algorithm>
#include <array>
#include <cmath>
#include <limits>
#include <numbers>
#include <optional>

namespace photomat {
namespace {

// Distance of an edge point from the circle (orthographic outline), in pixels.
// Divided by `sigma` (the outline's noise) in the joint problem.
struct OrthographicEdgeResidual {
  explicit OrthographicEdgeResidual(const Eigen::Vector2d& p, double sigma = 1.0)
      : x(p.x()), y(p.y()), inverse_sigma(1.0 / sigma) {}
  template <typename T>
  bool operator()(const T* circle, T* residual) const {
    const T dx = T(x) - circle[0], dy = T(y) - circle[1];
    residual[0] = (ceres::sqrt(dx * dx + dy * dy + T(1e-12)) - circle[2]) * T(inverse_sigma);
    return true;
  }
  double x, y, inverse_sigma;
};

// Where the sphere would show the highlight of the light, minus where it was seen, in pixels
// divided by the highlight noise `sigma`. The normal at the mirror point bisects the view vector
// (0, 0, 1) and the direction to the light: the distant light itself, or for a near lamp the
// direction from the mirror point, which lies above the measured highlight on the sphere (its
// height follows from the circle: the sphere rests on the sample plane).
struct SphereHighlightResidual {
  SphereHighlightResidual(const Eigen::Vector2d& p, LightModel light_model, int width, int height,
                          double sigma)
      : x(p.x()),
        y(p.y()),
        near(light_model == LightModel::kNear),
        sample_x(p.x() - width / 2.0),
        sample_y(height / 2.0 - p.y()),
        inverse_sigma(1.0 / sigma) {}
  template <typename T>
  bool operator()(const T* circle, const T* light, T* residual) const {
    const T dx = T(x) - circle[0], dy = T(y) - circle[1];
    const T height_squared = circle[2] * circle[2] - dx * dx - dy * dy;
    // A highlight outside the circle has no mirror point: this circle cannot be evaluated.
    if (!(height_squared > T(0.0))) return false;
    T to_light[3] = {light[0], light[1], light[2]};
    if (near) {
      to_light[0] -= T(sample_x);
      to_light[1] -= T(sample_y);
      to_light[2] -= circle[2] + ceres::sqrt(height_squared);
    }
    const T length = ceres::sqrt(to_light[0] * to_light[0] + to_light[1] * to_light[1] +
                                 to_light[2] * to_light[2]);
    const T hx = to_light[0] / length, hy = to_light[1] / length, hz = to_light[2] / length + T(1);
    const T norm = ceres::sqrt(hx * hx + hy * hy + hz * hz);
    residual[0] = (circle[0] + circle[2] * hx / norm - T(x)) * T(inverse_sigma);
    residual[1] = (circle[1] - circle[2] * hy / norm - T(y)) * T(inverse_sigma);
    return true;
  }
  double x, y;
  bool near;
  double sample_x, sample_y, inverse_sigma;
};

// Perspective camera, OpenCV frame (X right, Y down, Z forward), sphere of radius 1 centred at C.
// An outline point's viewing ray is tangent to the sphere: its angle to C is asin(1 / |C|).
struct PerspectiveEdgeResidual {
  PerspectiveEdgeResidual(const Eigen::Vector3d& viewing_ray, double focal_length)
      : ray(viewing_ray), focal(focal_length) {}
  template <typename T>
  bool operator()(const T* centre, T* residual) const {
    const T cx = centre[0], cy = centre[1], cz = centre[2];
    const T dot = T(ray.x()) * cx + T(ray.y()) * cy + T(ray.z()) * cz;
    const T crx = T(ray.y()) * cz - T(ray.z()) * cy;
    const T cry = T(ray.z()) * cx - T(ray.x()) * cz;
    const T crz = T(ray.x()) * cy - T(ray.y()) * cx;
    const T angle = ceres::atan2(ceres::sqrt(crx * crx + cry * cry + crz * crz + T(1e-18)), dot);
    const T distance = ceres::sqrt(cx * cx + cy * cy + cz * cz);
    residual[0] = T(focal) * (angle - ceres::asin(T(1.0) / distance));
    return true;
  }
  Eigen::Vector3d ray;
  double focal;
};

// The perspective mirror point of light l (camera frame) on the sphere: the normal bisects l and
// the direction to the camera, which itself depends on the point; a few fixed-point steps
// converge because the sphere is small next to its distance.
template <typename T>
void PerspectiveMirrorPoint(const T* centre, const T* light, T* point) {
  T view[3] = {-centre[0], -centre[1], -centre[2]};
  for (int step = 0; step < 6; ++step) {
    const T vn = ceres::sqrt(view[0] * view[0] + view[1] * view[1] + view[2] * view[2]);
    T h[3] = {light[0] + view[0] / vn, light[1] + view[1] / vn, light[2] + view[2] / vn};
    const T hn = ceres::sqrt(h[0] * h[0] + h[1] * h[1] + h[2] * h[2]);
    for (int i = 0; i < 3; ++i) point[i] = centre[i] + h[i] / hn;
    for (int i = 0; i < 3; ++i) view[i] = -point[i];
  }
}

struct PerspectiveHighlightResidual {
  PerspectiveHighlightResidual(const Eigen::Vector2d& uv, const CameraIntrinsics& k)
      : u(uv.x()), v(uv.y()), camera(k) {}
  template <typename T>
  bool operator()(const T* centre, const T* light, T* residual) const {
    T point[3];
    PerspectiveMirrorPoint(centre, light, point);
    residual[0] = T(camera.fx) * point[0] / point[2] + T(camera.cx) - T(u);
    residual[1] = T(camera.fy) * point[1] / point[2] + T(camera.cy) - T(v);
    return true;
  }
  double u, v;
  CameraIntrinsics camera;
};

// The joint solves of step 4, to tight tolerances.
ceres::Solver::Options JointSolverOptions(int max_iterations) {
  ceres::Solver::Options solver;
  solver.linear_solver_type = ceres::DENSE_SCHUR;
  solver.max_num_iterations = max_iterations;
  solver.num_threads = 1;
  // The outcome is reported through SolveStatus (the calibration's report), not Ceres's log.
  solver.logging_type = ceres::SILENT;
  solver.function_tolerance = 1e-12;
  solver.parameter_tolerance = 1e-12;
  return solver;
}

// "converged", or why the solve is not usable: only a converged solve is (a solve stopped by its
// iteration budget is usable to Ceres but not trusted here).
std::string SolveStatus(const ceres::Solver::Summary& summary) {
  if (summary.termination_type == ceres::CONVERGENCE && summary.IsSolutionUsable()) {
    return "converged";
  }
  return fmt::format("the solver did not converge ({} after {} iterations: {})",
                     ceres::TerminationTypeToString(summary.termination_type),
                     summary.iterations.size(), summary.message);
}

// IMPLEMENTER CHOICE: robust losses in units of each residual's noise. The outline's Huber loss
// keeps stray edge points (dust, a reflection at the rim) from pulling the circle; the
// highlights' Cauchy loss lets a highlight that is wrong by many sigma (a second reflection
// taken for the lamp) count for little once the other spheres disagree with it.
constexpr double kEdgeLossScale = 2.0;
constexpr double kHighlightLossScale = 3.0;
// Noise estimates are floored so that a noiseless synthetic image does not give infinite weights.
constexpr double kMinimumSigmaPixels = 0.01;
constexpr double kRadiansToDegrees = 180.0 / std::numbers::pi;

using CircleParameters = std::array<double, 3>;

double EdgeRmsOf(const CircleParameters& circle, const std::vector<Eigen::Vector2d>& points) {
  double sum = 0.0;
  for (const auto& p : points) {
    const double d = std::hypot(p.x() - circle[0], p.y() - circle[1]) - circle[2];
    sum += d * d;
  }
  return points.empty() ? 0.0 : std::sqrt(sum / static_cast<double>(points.size()));
}

// The joint problem over `circles` and `lights` (their storage must outlive it).
void BuildJointProblem(const std::vector<MirrorSphereObservations>& spheres, LightModel model,
                       int width, int height, const std::vector<double>& edge_sigmas,
                       double highlight_sigma, std::vector<CircleParameters>& circles,
                       std::vector<Eigen::Vector3d>& lights, ceres::Problem& problem) {
  for (std::size_t s = 0; s < spheres.size(); ++s) {
    for (const auto& p : spheres[s].edge_points) {
      problem.AddResidualBlock(new ceres::AutoDiffCostFunction<OrthographicEdgeResidual, 1, 3>(
                                   new OrthographicEdgeResidual(p, edge_sigmas[s])),
                               new ceres::HuberLoss(kEdgeLossScale), circles[s].data());
    }
    for (std::size_t i = 0; i < lights.size(); ++i) {
      problem.AddResidualBlock(new ceres::AutoDiffCostFunction<SphereHighlightResidual, 2, 3, 3>(
                                   new SphereHighlightResidual(spheres[s].highlights[i], model,
                                                               width, height, highlight_sigma)),
                               new ceres::CauchyLoss(kHighlightLossScale), circles[s].data(),
                               lights[i].data());
    }
  }
  if (model == LightModel::kDistant) {
    for (auto& light : lights) problem.SetManifold(light.data(), new ceres::SphereManifold<3>());
  }
}

// The highlight noise from the residuals of a solve, when the highlights are redundant (more
// residuals than light parameters); nullopt otherwise. IMPLEMENTER CHOICE: the RMS of the
// residual components within 5 robust sigmas (1.4826 x their median magnitude), so that one
// wrong highlight does not inflate the noise and hide itself from the Cauchy loss, while the
// noise of the rest is measured in full (the median alone underestimates it: highlight errors
// have heavier tails than Gaussian noise). Divided by the degrees of freedom the kept residuals
// leave after the lights' parameters.
std::optional<double> MeasuredHighlightSigma(const std::vector<MirrorSphereObservations>& spheres,
                                             LightModel model, int width, int height,
                                             const std::vector<CircleParameters>& circles,
                                             const std::vector<Eigen::Vector3d>& lights) {
  const int light_parameters = model == LightModel::kNear ? 3 : 2;
  const long degrees_of_freedom =
      static_cast<long>(lights.size()) * (2 * static_cast<long>(spheres.size()) - light_parameters);
  if (degrees_of_freedom <= 0) return std::nullopt;
  std::vector<double> components;
  for (std::size_t s = 0; s < spheres.size(); ++s) {
    for (std::size_t i = 0; i < lights.size(); ++i) {
      const SphereHighlightResidual residual(spheres[s].highlights[i], model, width, height, 1.0);
      double r[2];
      if (!residual(circles[s].data(), lights[i].data(), r)) return std::nullopt;
      components.push_back(r[0]);
      components.push_back(r[1]);
    }
  }
  std::vector<double> magnitudes;
  for (double r : components) magnitudes.push_back(std::abs(r));
  const auto middle = magnitudes.begin() + static_cast<std::ptrdiff_t>(magnitudes.size() / 2);
  std::nth_element(magnitudes.begin(), middle, magnitudes.end());
  const double limit = 5.0 * 1.4826 * *middle;
  double sum = 0.0;
  int kept = 0;
  for (double r : components) {
    if (std::abs(r) > limit) continue;
    sum += r * r;
    ++kept;
  }
  const double kept_dof =
      static_cast<double>(degrees_of_freedom) * kept / static_cast<double>(components.size());
  return std::sqrt(sum / kept_dof);
}

// Each light's expected RMS angular error (degrees) from the covariance of `problem`'s solution;
// NaN where the covariance cannot be computed (a rank-deficient problem).
std::vector<double> LightSigmasDegrees(LightModel model, std::vector<Eigen::Vector3d>& lights,
                                       ceres::Problem& problem) {
  std::vector<double> sigmas(lights.size(), std::numeric_limits<double>::quiet_NaN());
  ceres::Covariance::Options options;
  options.algorithm_type = ceres::DENSE_SVD;
  options.num_threads = 1;
  ceres::Covariance covariance(options);
  std::vector<std::pair<const double*, const double*>> blocks;
  for (const auto& light : lights) blocks.emplace_back(light.data(), light.data());
  if (!covariance.Compute(blocks, &problem)) return sigmas;
  for (std::size_t i = 0; i < lights.size(); ++i) {
    Eigen::Matrix<double, 3, 3, Eigen::RowMajor> block;
    if (!covariance.GetCovarianceBlock(lights[i].data(), lights[i].data(), block.data())) continue;
    Eigen::Matrix3d direction_covariance = block;
    if (model == LightModel::kNear) {
      // The direction from the sample's centre (the origin) to the lamp.
      const double distance = lights[i].norm();
      const Eigen::Vector3d t = lights[i] / distance;
      const Eigen::Matrix3d jacobian = (Eigen::Matrix3d::Identity() - t * t.transpose()) / distance;
      direction_covariance = jacobian * block * jacobian.transpose();
    }
    sigmas[i] = std::sqrt(std::max(0.0, direction_covariance.trace())) * kRadiansToDegrees;
  }
  return sigmas;
}

bool Finite(const std::vector<CircleParameters>& circles,
            const std::vector<Eigen::Vector3d>& lights) {
  for (const auto& c : circles) {
    if (!std::isfinite(c[0]) || !std::isfinite(c[1]) || !(c[2] > 0.0)) return false;
  }
  for (const auto& l : lights) {
    if (!l.allFinite()) return false;
  }
  return true;
}

}  // namespace

bool MirrorSphereRefinementAvailable() { return true; }

std::string MirrorSphereRefinementAbsence() { return {}; }

SphereCircle RefineCircle(const SphereCircle& start, const std::vector<Eigen::Vector2d>& points) {
  double circle[3] = {start.centre.x(), start.centre.y(), start.radius};
  ceres::Problem problem;
  for (const auto& p : points) {
    problem.AddResidualBlock(new ceres::AutoDiffCostFunction<OrthographicEdgeResidual, 1, 3>(
                                 new OrthographicEdgeResidual(p)),
                             new ceres::HuberLoss(0.5), circle);
  }
  ceres::Solver::Options options;
  options.linear_solver_type = ceres::DENSE_QR;
  options.max_num_iterations = 50;
  options.num_threads = 1;
  ceres::Solver::Summary summary;
  ceres::Solve(options, &problem, &summary);
  // A fit that did not converge keeps its start (algebraic or Hough) rather than a half-way circle.
  if (SolveStatus(summary) != "converged") return start;
  return {Eigen::Vector2d(circle[0], circle[1]), circle[2]};
}

MirrorSphereRefinement RefineMirrorSpheres(const std::vector<MirrorSphereObservations>& spheres,
                                           LightModel model, const MirrorSphereEstimate& start,
                                           int width, int height, int max_iterations) {
  MirrorSphereRefinement result;
  result.estimate = start;
  std::vector<CircleParameters> circles;
  std::vector<double> edge_sigmas;
  for (std::size_t s = 0; s < spheres.size(); ++s) {
    const SphereCircle& c = start.spheres[s];
    circles.push_back({c.centre.x(), c.centre.y(), c.radius});
    edge_sigmas.push_back(
        std::max(kMinimumSigmaPixels, EdgeRmsOf(circles.back(), spheres[s].edge_points)));
  }
  std::vector<Eigen::Vector3d> lights = start.lights;
  // Pass 1: the highlights weighed like the outline (the noise of neither is known better yet).
  double highlight_sigma = *std::max_element(edge_sigmas.begin(), edge_sigmas.end());
  for (int pass = 0; pass < 2; ++pass) {
    ceres::Problem problem;
    BuildJointProblem(spheres, model, width, height, edge_sigmas, highlight_sigma, circles, lights,
                      problem);
    ceres::Solver::Summary summary;
    ceres::Solve(JointSolverOptions(max_iterations), &problem, &summary);
    result.iterations += static_cast<int>(summary.iterations.size());
    result.status = SolveStatus(summary);
    if (result.status == "converged" && !Finite(circles, lights)) {
      result.status = "the solver returned a degenerate sphere or light";
    }
    if (result.status == "converged" && model == LightModel::kNear) {
      for (const auto& lamp : lights) {
        if (!(lamp.z() > 0.0)) result.status = "a lamp was triangulated below the sample plane";
      }
    }
    if (result.status != "converged") return result;
    const auto measured = MeasuredHighlightSigma(spheres, model, width, height, circles, lights);
    result.highlight_sigma_measured = measured.has_value();
    if (pass == 1 || !measured) {
      result.highlight_sigma_pixels = highlight_sigma;
      result.light_sigma_degrees = LightSigmasDegrees(model, lights, problem);
      break;
    }
    highlight_sigma = std::max(kMinimumSigmaPixels, *measured);
  }
  result.usable = true;
  for (std::size_t s = 0; s < circles.size(); ++s) {
    result.estimate.spheres[s] = {Eigen::Vector2d(circles[s][0], circles[s][1]), circles[s][2]};
  }
  if (model == LightModel::kDistant) {
    for (auto& light : lights) light.normalize();
  }
  result.estimate.lights = lights;
  return result;
}

std::string RefinePerspectiveSphere(const std::vector<Eigen::Vector3d>& edge_rays,
                                    double focal_length,
                                    const std::vector<Eigen::Vector2d>& highlights,
                                    const CameraIntrinsics& camera, int max_iterations,
                                    Eigen::Vector3d* centre, std::vector<Eigen::Vector3d>* lights) {
  Eigen::Vector3d refined_centre = *centre;
  std::vector<Eigen::Vector3d> refined_lights = *lights;
  ceres::Problem problem;
  for (const auto& ray : edge_rays) {
    problem.AddResidualBlock(new ceres::AutoDiffCostFunction<PerspectiveEdgeResidual, 1, 3>(
                                 new PerspectiveEdgeResidual(ray, focal_length)),
                             new ceres::HuberLoss(0.5), refined_centre.data());
  }
  for (std::size_t i = 0; i < highlights.size(); ++i) {
    problem.AddResidualBlock(new ceres::AutoDiffCostFunction<PerspectiveHighlightResidual, 2, 3, 3>(
                                 new PerspectiveHighlightResidual(highlights[i], camera)),
                             nullptr, refined_centre.data(), refined_lights[i].data());
    problem.SetManifold(refined_lights[i].data(), new ceres::SphereManifold<3>());
  }
  ceres::Solver::Summary summary;
  ceres::Solve(JointSolverOptions(max_iterations), &problem, &summary);
  const std::string status = SolveStatus(summary);
  if (status != "converged" || !refined_centre.allFinite()) return status;
  *centre = refined_centre;
  *lights = refined_lights;
  return status;
}

}  // namespace photomat
