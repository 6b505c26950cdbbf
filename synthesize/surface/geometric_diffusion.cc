#include "synthesize/surface/geometric_diffusion.h"

#include <fmt/format.h>
#include <tbb/parallel_for.h>

#include <Eigen/Eigenvalues>
#include <Eigen/IterativeLinearSolvers>
#include <Eigen/LU>
#include <Eigen/QR>
#include <algorithm>
#include <cmath>
#include <memory>

#include "core/error.h"
#include "synthesize/surface/fem.h"

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

std::vector<Eigen::Vector3d> FilterFaceNormals(const TriangleMesh& mesh,
                                               const NormalFilterOptions& options) {
  if (options.iterations < 0 || !(options.spatial_factor > 0.0) || !(options.range_sigma >= 0.02) ||
      !(options.noise_factor >= 0.0)) {
    throw Error(
        "normal filter: iterations and the noise factor must not be negative, the spatial "
        "sigma positive and the range sigma at least 0.02");
  }
  const int faces = mesh.triangle_count();
  std::vector<Eigen::Vector3d> normals = FaceNormals(mesh);
  std::vector<Eigen::Vector3d> centroids(faces);
  std::vector<double> areas(faces);
  std::vector<std::vector<int>> vertex_faces(mesh.vertex_count());
  for (int f = 0; f < faces; ++f) {
    const auto& t = mesh.triangles[f];
    centroids[f] = (mesh.positions[t[0]] + mesh.positions[t[1]] + mesh.positions[t[2]]) / 3.0;
    areas[f] = TriangleArea(mesh, f);
    for (int v : t) vertex_faces[v].push_back(f);
  }
  // Neighbourhood: the faces sharing at least a vertex (the face itself included).
  std::vector<std::vector<int>> neighbourhood(faces);
  tbb::parallel_for(0, faces, [&](int f) {
    auto& near = neighbourhood[f];
    for (int v : mesh.triangles[f])
      near.insert(near.end(), vertex_faces[v].begin(), vertex_faces[v].end());
    std::sort(near.begin(), near.end());
    near.erase(std::unique(near.begin(), near.end()), near.end());
  });
  const auto adjacency = EdgeFaceAdjacency(mesh);
  double spacing = 0.0;
  int pairs = 0;
  for (const auto& edge : adjacency) {
    if (edge.faces[1] < 0) continue;
    spacing += (centroids[edge.faces[0]] - centroids[edge.faces[1]]).norm();
    ++pairs;
  }
  if (pairs == 0 || !(spacing > 0.0)) return normals;  // no two faces share an edge
  const double sigma_s = options.spatial_factor * spacing / pairs;
  const double spatial = 1.0 / (2.0 * sigma_s * sigma_s);
  double sigma_r = options.range_sigma;
  if (options.noise_factor > 0.0) {
    std::vector<double> differences;
    for (const auto& edge : adjacency) {
      if (edge.faces[1] >= 0) {
        differences.push_back((normals[edge.faces[0]] - normals[edge.faces[1]]).norm());
      }
    }
    const auto middle = differences.begin() + differences.size() / 2;
    std::nth_element(differences.begin(), middle, differences.end());
    constexpr double kSmallestRangeSigma = 0.02;  // about 1 degree
    sigma_r = std::clamp(options.noise_factor * *middle, kSmallestRangeSigma, sigma_r);
  }
  const double range = 1.0 / (2.0 * sigma_r * sigma_r);
  std::vector<Eigen::Vector3d> next(faces);
  for (int pass = 0; pass < options.iterations; ++pass) {
    tbb::parallel_for(0, faces, [&](int f) {
      Eigen::Vector3d sum = Eigen::Vector3d::Zero();
      for (int g : neighbourhood[f]) {
        const double weight =
            areas[g] * std::exp(-spatial * (centroids[f] - centroids[g]).squaredNorm() -
                                range * (normals[f] - normals[g]).squaredNorm());
        sum += weight * normals[g];
      }
      next[f] = sum.norm() > 0.0 ? Eigen::Vector3d(sum.normalized()) : normals[f];
    });
    normals.swap(next);
  }
  return normals;
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

// Per triangle: the direction across the feature d1 and along it d2 (in the triangle's plane),
// their edge-stopping weights, and the filtered normal n.
struct ElementFrame {
  Eigen::Vector3d across, along, normal;
  double g_across = 1.0, g_along = 1.0;
};

std::vector<ElementFrame> FilteredNormalFrames(const TriangleMesh& mesh,
                                               const GeometricDiffusionOptions& options) {
  const int elements = mesh.triangle_count();
  const auto filtered = FilterFaceNormals(mesh, options.normal_filter);
  const auto face_normals = FaceNormals(mesh);
  std::vector<Eigen::Vector3d> vertex_normals(mesh.vertex_count(), Eigen::Vector3d::Zero());
  for (int e = 0; e < elements; ++e) {
    const double area = TriangleArea(mesh, e);
    for (int v : mesh.triangles[e]) vertex_normals[v] += area * filtered[e];
  }
  for (auto& n : vertex_normals) {
    if (n.norm() > 0.0) n.normalize();
  }
  const double lambda = options.crease_curvature / MeanEdgeLength(mesh);
  std::vector<ElementFrame> frames(elements);
  tbb::parallel_for(0, elements, [&](int e) {
    const auto& t = mesh.triangles[e];
    const Eigen::Vector3d& n = face_normals[e];
    const Eigen::Vector3d u = n.unitOrthogonal();
    const Eigen::Vector3d w = n.cross(u);
    // Shape operator S (symmetric 2 x 2 in the basis u, w) fitted by least squares to the change
    // of the filtered vertex normals along the three edges: dn = S de.
    Eigen::Matrix<double, 6, 3> lhs;
    Eigen::Matrix<double, 6, 1> rhs;
    for (int k = 0; k < 3; ++k) {
      const Eigen::Vector3d de = mesh.positions[t[(k + 1) % 3]] - mesh.positions[t[k]];
      const Eigen::Vector3d dn = vertex_normals[t[(k + 1) % 3]] - vertex_normals[t[k]];
      lhs.row(2 * k) << de.dot(u), de.dot(w), 0.0;
      lhs.row(2 * k + 1) << 0.0, de.dot(u), de.dot(w);
      rhs(2 * k) = dn.dot(u);
      rhs(2 * k + 1) = dn.dot(w);
    }
    const Eigen::Vector3d form = lhs.colPivHouseholderQr().solve(rhs);
    Eigen::Matrix2d shape;
    shape << form[0], form[1], form[1], form[2];
    const Eigen::SelfAdjointEigenSolver<Eigen::Matrix2d> eigen(shape);
    const int first = std::abs(eigen.eigenvalues()[1]) >= std::abs(eigen.eigenvalues()[0]) ? 1 : 0;
    const Eigen::Vector2d c = eigen.eigenvectors().col(first);
    ElementFrame& frame = frames[e];
    frame.across = (c.x() * u + c.y() * w).normalized();
    frame.along = n.cross(frame.across);
    frame.g_across = options.alpha * EdgeStopping(eigen.eigenvalues()[first], lambda);
    frame.g_along = options.beta * EdgeStopping(eigen.eigenvalues()[1 - first], lambda);
    frame.normal = filtered[e];
  });
  return frames;
}

// One step of the default method: (M + tau K) x^{n+1} = M x^n on the 3 n coordinates together,
// K_(ia)(jb) = sum over elements of area sum_k (grad phi_i . d_k)(grad phi_j . d_k) C_k(a, b),
// C_k = n n^T + w g_k (I - n n^T); M lumped.
int FilteredNormalStep(TriangleMesh& mesh, double tau, const GeometricDiffusionOptions& options) {
  const FemDomain domain = FemDomain::FromMesh(mesh);
  const auto frames = FilteredNormalFrames(mesh, options);
  const int n = mesh.vertex_count();
  std::vector<Eigen::Triplet<double>> triplets;
  triplets.reserve(static_cast<std::size_t>(mesh.triangle_count()) * 84);
  Eigen::VectorXd mass = Eigen::VectorXd::Zero(3 * n);
  const Eigen::Matrix3d identity = Eigen::Matrix3d::Identity();
  for (int e = 0; e < mesh.triangle_count(); ++e) {
    const auto& t = mesh.triangles[e];
    const ElementFrame& frame = frames[e];
    const double area = domain.area(e);
    const Eigen::Matrix3d normal_part = frame.normal * frame.normal.transpose();
    const Eigen::Matrix3d membrane = options.tangential_weight * (identity - normal_part);
    const Eigen::Matrix3d across = normal_part + frame.g_across * membrane;
    const Eigen::Matrix3d along = normal_part + frame.g_along * membrane;
    for (int i = 0; i < 3; ++i) {
      const Eigen::Vector3d& gi = domain.gradient(e, i);
      for (int j = 0; j < 3; ++j) {
        const Eigen::Vector3d& gj = domain.gradient(e, j);
        const Eigen::Matrix3d block = area * (gi.dot(frame.across) * gj.dot(frame.across) * across +
                                              gi.dot(frame.along) * gj.dot(frame.along) * along);
        for (int a = 0; a < 3; ++a) {
          for (int b = 0; b < 3; ++b)
            triplets.emplace_back(3 * t[i] + a, 3 * t[j] + b, block(a, b));
        }
      }
      mass.segment<3>(3 * t[i]).array() += area / 3.0;
    }
  }
  SparseMatrixD system(3 * n, 3 * n);
  for (int k = 0; k < 3 * n; ++k) triplets.emplace_back(k, k, mass[k] / tau);
  system.setFromTriplets(triplets.begin(), triplets.end());
  system *= tau;
  Eigen::VectorXd x(3 * n);
  for (int v = 0; v < n; ++v) x.segment<3>(3 * v) = mesh.positions[v];
  const Eigen::VectorXd rhs = mass.cwiseProduct(x);
  Eigen::ConjugateGradient<SparseMatrixD, Eigen::Lower | Eigen::Upper,
                           Eigen::IncompleteCholesky<double>>
      solver;
  solver.setTolerance(options.solver.tolerance);
  solver.setMaxIterations(options.solver.max_iterations);
  solver.compute(system);
  if (solver.info() != Eigen::Success) {
    throw Error("geometric diffusion: the incomplete Cholesky factorisation failed");
  }
  const Eigen::VectorXd next = solver.solveWithGuess(rhs, x);
  if (!next.allFinite())
    throw Error("geometric diffusion: the solve produced non-finite positions");
  for (int v = 0; v < n; ++v) mesh.positions[v] = next.segment<3>(3 * v);
  return static_cast<int>(solver.iterations());
}

}  // namespace

int GeometricDiffusionStep(TriangleMesh& mesh, double tau,
                           const GeometricDiffusionOptions& options) {
  if (!options.isotropic && options.detection == FeatureDetection::kFilteredNormals) {
    return FilteredNormalStep(mesh, tau, options);
  }
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
