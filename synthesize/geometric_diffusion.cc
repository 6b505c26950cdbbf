#include "synthesize/geometric_diffusion.h"

#include <fmt/format.h>
#include <tbb/parallel_for.h>

#include <Eigen/Eigenvalues>
#include <Eigen/LU>
#include <algorithm>
#include <cmath>
#include <memory>

#include "core/error.h"
#include "synthesize/fem.h"

namespace photomat {

std::vector<CurvatureFrame> EstimateCurvatures(const TriangleMesh& mesh) {
  const int n = mesh.vertex_count();
  const auto normals = VertexNormals(mesh);
  // A tangent basis per vertex; the normal equations of the fit of the second fundamental form
  // (a, b, c) to the normal-curvature samples: kappa = a x^2 + 2 b x y + c y^2 along (x, y).
  std::vector<Eigen::Vector3d> t1(n), t2(n);
  for (int v = 0; v < n; ++v) {
    const Eigen::Vector3d& normal = normals[v];
    const Eigen::Vector3d helper =
        std::abs(normal.x()) < 0.9 ? Eigen::Vector3d::UnitX() : Eigen::Vector3d::UnitY();
    t1[v] = normal.cross(helper).normalized();
    t2[v] = normal.cross(t1[v]);
  }
  std::vector<Eigen::Matrix3d> lhs(n, Eigen::Matrix3d::Zero());
  std::vector<Eigen::Vector3d> rhs(n, Eigen::Vector3d::Zero());
  for (const auto& edge : EdgeFaceAdjacency(mesh)) {
    // Edge weights: the areas of the (one or two) triangles on the edge.
    double weight = TriangleArea(mesh, edge.faces[0]);
    if (edge.faces[1] >= 0) weight += TriangleArea(mesh, edge.faces[1]);
    const int a = edge.vertices[0], b = edge.vertices[1];
    for (const auto& [i, j] : {std::pair{a, b}, std::pair{b, a}}) {
      const Eigen::Vector3d d = mesh.positions[j] - mesh.positions[i];
      const double length2 = d.squaredNorm();
      if (!(length2 > 0.0)) continue;
      const Eigen::Vector2d tangent(d.dot(t1[i]), d.dot(t2[i]));
      if (!(tangent.norm() > 0.0)) continue;
      const Eigen::Vector2d t = tangent.normalized();
      const double kappa = 2.0 * normals[i].dot(d) / length2;
      const Eigen::Vector3d row(t.x() * t.x(), 2.0 * t.x() * t.y(), t.y() * t.y());
      lhs[i] += weight * row * row.transpose();
      rhs[i] += weight * kappa * row;
    }
  }
  std::vector<CurvatureFrame> frames(n);
  for (int i = 0; i < n; ++i) {
    CurvatureFrame& frame = frames[i];
    frame.normal = normals[i];
    frame.e1 = t1[i];
    frame.e2 = t2[i];
    const Eigen::FullPivLU<Eigen::Matrix3d> lu(lhs[i]);
    if (lu.rank() < 3) continue;  // fewer than three edge directions: no estimate
    const Eigen::Vector3d form = lu.solve(rhs[i]);
    Eigen::Matrix2d second;
    second << form[0], form[1], form[1], form[2];
    const Eigen::SelfAdjointEigenSolver<Eigen::Matrix2d> eigen(second);
    int first = std::abs(eigen.eigenvalues()[1]) >= std::abs(eigen.eigenvalues()[0]) ? 1 : 0;
    const Eigen::Vector2d v1 = eigen.eigenvectors().col(first);
    const Eigen::Vector2d v2 = eigen.eigenvectors().col(1 - first);
    frame.k1 = eigen.eigenvalues()[first];
    frame.k2 = eigen.eigenvalues()[1 - first];
    frame.e1 = (v1.x() * t1[i] + v1.y() * t2[i]).normalized();
    frame.e2 = (v2.x() * t1[i] + v2.y() * t2[i]).normalized();
  }
  return frames;
}

double EdgeStopping(double curvature, double lambda) {
  const double k = std::abs(curvature);
  if (k <= lambda) return 1.0;
  const double excess = (k - lambda) / lambda;
  return 1.0 / (1.0 + excess * excess);
}

namespace {

// Per-element diffusion tensors D from the vertex curvature frames.
std::vector<Eigen::Matrix3d> DiffusionTensors(const TriangleMesh& mesh,
                                              const GeometricDiffusionOptions& options) {
  const int elements = mesh.triangle_count();
  if (options.isotropic) return std::vector<Eigen::Matrix3d>(elements, Eigen::Matrix3d::Identity());
  const auto frames = EstimateCurvatures(mesh);
  std::vector<double> magnitudes;
  magnitudes.reserve(frames.size() * 2);
  for (const auto& f : frames) {
    magnitudes.push_back(std::abs(f.k1));
    magnitudes.push_back(std::abs(f.k2));
  }
  const auto middle = magnitudes.begin() + magnitudes.size() / 2;
  std::nth_element(magnitudes.begin(), middle, magnitudes.end());
  const double lambda = std::max(options.lambda_factor * *middle, 1e-300);
  // Shape tensors k1 e1 e1^T + k2 e2 e2^T averaged over each triangle, then decomposed in the
  // triangle's plane: a triangle with two vertices on a crease keeps a large curvature across it
  // (averaging the diffusion tensors instead would let the third, flat vertex open the crease).
  std::vector<Eigen::Matrix3d> shape(frames.size());
  for (std::size_t v = 0; v < frames.size(); ++v) {
    const auto& f = frames[v];
    shape[v] = f.k1 * f.e1 * f.e1.transpose() + f.k2 * f.e2 * f.e2.transpose();
  }
  const auto normals = FaceNormals(mesh);
  std::vector<Eigen::Matrix3d> tensors(elements);
  for (int e = 0; e < elements; ++e) {
    const auto& t = mesh.triangles[e];
    const Eigen::Matrix3d s = (shape[t[0]] + shape[t[1]] + shape[t[2]]) / 3.0;
    const Eigen::Vector3d& n = normals[e];
    const Eigen::Vector3d helper =
        std::abs(n.x()) < 0.9 ? Eigen::Vector3d::UnitX() : Eigen::Vector3d::UnitY();
    const Eigen::Vector3d t1 = n.cross(helper).normalized();
    const Eigen::Vector3d t2 = n.cross(t1);
    Eigen::Matrix2d plane;
    plane << t1.dot(s * t1), t1.dot(s * t2), t2.dot(s * t1), t2.dot(s * t2);
    const Eigen::SelfAdjointEigenSolver<Eigen::Matrix2d> eigen(plane);
    Eigen::Matrix3d d = n * n.transpose();  // the normal term with the triangle's own normal
    for (int k = 0; k < 2; ++k) {
      const Eigen::Vector2d c = eigen.eigenvectors().col(k);
      const Eigen::Vector3d direction = (c.x() * t1 + c.y() * t2).normalized();
      const double curvature = eigen.eigenvalues()[k];
      // alpha weighs the direction of larger |k| (e1), beta the other (e2).
      const int larger = std::abs(eigen.eigenvalues()[1]) >= std::abs(eigen.eigenvalues()[0]);
      const double weight = k == larger ? options.alpha : options.beta;
      d += weight * EdgeStopping(curvature, lambda) * direction * direction.transpose();
    }
    tensors[e] = d;
  }
  return tensors;
}

}  // namespace

int GeometricDiffusionStep(TriangleMesh& mesh, double tau,
                           const GeometricDiffusionOptions& options) {
  const FemDomain domain = FemDomain::FromMesh(mesh);
  const FemOperators operators(domain);
  const SparseMatrixD stiffness = operators.TensorStiffness(DiffusionTensors(mesh, options));
  const int n = mesh.vertex_count();
  std::array<Eigen::VectorXd, 3> coordinates;
  for (int c = 0; c < 3; ++c) {
    coordinates[c].resize(n);
    for (int v = 0; v < n; ++v) coordinates[c][v] = mesh.positions[v][c];
  }
  // a = 1: C0 = 1, C1 = D, C2 = C3 = 0 (eq. 21 with F = 0).
  GeneralEquation equation;
  equation.c0 = Eigen::VectorXd::Ones(1);
  equation.c1_stiffness = &stiffness;
  equation.c2 = Eigen::VectorXd::Zero(n);
  equation.c3 = Eigen::VectorXd::Zero(n);
  std::array<int, 3> iterations{};
  tbb::parallel_for(0, 3, [&](int c) {
    iterations[c] =
        SemiImplicitStep(operators, equation, tau, options.solver, coordinates[c]).iterations;
  });
  for (int v = 0; v < n; ++v) {
    mesh.positions[v] = {coordinates[0][v], coordinates[1][v], coordinates[2][v]};
  }
  return iterations[0] + iterations[1] + iterations[2];
}

TriangleMesh SmoothMeshAnisotropic(const TriangleMesh& mesh,
                                   const GeometricDiffusionOptions& options, Progress* progress) {
  if (options.steps < 0 || !(options.time_step_factor > 0.0)) {
    throw Error("geometric diffusion: steps must not be negative and the time step positive");
  }
  NullProgress null;
  Progress& report = OrNull(progress, null);
  const double edge = MeanEdgeLength(mesh);
  const double tau = options.time_step_factor * edge * edge;
  TriangleMesh out = mesh;
  report.Start("anisotropic geometric diffusion", options.steps);
  for (int step = 0; step < options.steps; ++step) {
    GeometricDiffusionStep(out, tau, options);
    report.Advance();
  }
  report.Finish();
  return out;
}

CoupledResult SimulateCoupled(const TriangleMesh& mesh, ReactionDiffusionModel& model,
                              const SimulationOptions& options,
                              const GeometricDiffusionOptions& geometry, Progress* progress) {
  NullProgress null;
  Progress& report = OrNull(progress, null);
  CoupledResult result{mesh, {}};
  const double edge = MeanEdgeLength(mesh);
  const double geometry_tau = geometry.time_step_factor * edge * edge;
  auto domain = std::make_unique<FemDomain>(FemDomain::FromMesh(result.mesh));
  auto operators = std::make_unique<FemOperators>(*domain);
  ReactionDiffusionSystem system(model, *operators, options);
  SettlingMonitor monitor(options);
  report.Start(fmt::format("{} reaction-diffusion with geometric diffusion", model.name()),
               options.max_steps);
  for (int step = 0; step < options.max_steps; ++step) {
    if (step < geometry.steps) {
      GeometricDiffusionStep(result.mesh, geometry_tau, geometry);
      // The new geometry's elements; the old ones stay alive until the system has moved over.
      auto next_domain = std::make_unique<FemDomain>(FemDomain::FromMesh(result.mesh));
      auto next_operators = std::make_unique<FemOperators>(*next_domain);
      system.SetOperators(*next_operators);
      operators = std::move(next_operators);
      domain = std::move(next_domain);
    }
    StepRecord record = system.Step();
    for (int i : record.iterations) result.pattern.total_iterations += i;
    const bool settled = record.step > geometry.steps && monitor.Update(record);
    result.pattern.history.push_back(std::move(record));
    report.Advance();
    if (settled) {
      result.pattern.settled = true;
      break;
    }
  }
  report.Finish();
  result.pattern.fields = system.fields();
  result.pattern.steps = system.steps();
  result.pattern.time = system.time();
  return result;
}

}  // namespace photomat
