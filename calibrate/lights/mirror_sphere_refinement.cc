#include "calibrate/lights/mirror_sphere_refinement.h"

#include <ceres/ceres.h>
#include <ceres/sphere_manifold.h>

namespace photomat {
namespace {

// Distance of an edge point from the circle (orthographic outline), in pixels.
struct OrthographicEdgeResidual {
  explicit OrthographicEdgeResidual(const Eigen::Vector2d& p) : x(p.x()), y(p.y()) {}
  template <typename T>
  bool operator()(const T* circle, T* residual) const {
    const T dx = T(x) - circle[0], dy = T(y) - circle[1];
    residual[0] = ceres::sqrt(dx * dx + dy * dy + T(1e-12)) - circle[2];
    return true;
  }
  double x, y;
};

// Where the highlight of light l (photomat frame) lands on the circle, minus where it was seen.
struct OrthographicHighlightResidual {
  explicit OrthographicHighlightResidual(const Eigen::Vector2d& p) : x(p.x()), y(p.y()) {}
  template <typename T>
  bool operator()(const T* circle, const T* light, T* residual) const {
    // The normal at the mirror point bisects the light and the view vector (0, 0, 1).
    const T hx = light[0], hy = light[1], hz = light[2] + T(1.0);
    const T norm = ceres::sqrt(hx * hx + hy * hy + hz * hz);
    residual[0] = circle[0] + circle[2] * hx / norm - T(x);
    residual[1] = circle[1] - circle[2] * hy / norm - T(y);
    return true;
  }
  double x, y;
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

// The joint solves of step 3: one consistent solve, to tight tolerances (the highlight residuals
// vanish at the optimum).
ceres::Solver::Options JointSolverOptions() {
  ceres::Solver::Options solver;
  solver.linear_solver_type = ceres::DENSE_SCHUR;
  solver.max_num_iterations = 100;
  solver.num_threads = 1;
  solver.function_tolerance = 1e-12;
  solver.parameter_tolerance = 1e-12;
  return solver;
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
  return {Eigen::Vector2d(circle[0], circle[1]), circle[2]};
}

void RefineOrthographicSphere(const std::vector<Eigen::Vector2d>& edge_points,
                              const std::vector<Eigen::Vector2d>& highlights, SphereCircle* circle,
                              std::vector<Eigen::Vector3d>* lights) {
  double parameters[3] = {circle->centre.x(), circle->centre.y(), circle->radius};
  ceres::Problem problem;
  for (const auto& p : edge_points) {
    problem.AddResidualBlock(new ceres::AutoDiffCostFunction<OrthographicEdgeResidual, 1, 3>(
                                 new OrthographicEdgeResidual(p)),
                             new ceres::HuberLoss(0.5), parameters);
  }
  for (std::size_t i = 0; i < highlights.size(); ++i) {
    problem.AddResidualBlock(
        new ceres::AutoDiffCostFunction<OrthographicHighlightResidual, 2, 3, 3>(
            new OrthographicHighlightResidual(highlights[i])),
        nullptr, parameters, (*lights)[i].data());
    problem.SetManifold((*lights)[i].data(), new ceres::SphereManifold<3>());
  }
  ceres::Solver::Summary summary;
  ceres::Solve(JointSolverOptions(), &problem, &summary);
  *circle = {Eigen::Vector2d(parameters[0], parameters[1]), parameters[2]};
}

void RefinePerspectiveSphere(const std::vector<Eigen::Vector3d>& edge_rays, double focal_length,
                             const std::vector<Eigen::Vector2d>& highlights,
                             const CameraIntrinsics& camera, Eigen::Vector3d* centre,
                             std::vector<Eigen::Vector3d>* lights) {
  ceres::Problem problem;
  for (const auto& ray : edge_rays) {
    problem.AddResidualBlock(new ceres::AutoDiffCostFunction<PerspectiveEdgeResidual, 1, 3>(
                                 new PerspectiveEdgeResidual(ray, focal_length)),
                             new ceres::HuberLoss(0.5), centre->data());
  }
  for (std::size_t i = 0; i < highlights.size(); ++i) {
    problem.AddResidualBlock(new ceres::AutoDiffCostFunction<PerspectiveHighlightResidual, 2, 3, 3>(
                                 new PerspectiveHighlightResidual(highlights[i], camera)),
                             nullptr, centre->data(), (*lights)[i].data());
    problem.SetManifold((*lights)[i].data(), new ceres::SphereManifold<3>());
  }
  ceres::Solver::Summary summary;
  ceres::Solve(JointSolverOptions(), &problem, &summary);
}

}  // namespace photomat
