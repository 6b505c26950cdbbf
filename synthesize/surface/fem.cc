#include "synthesize/surface/fem.h"

#include <fmt/format.h>

#include <algorithm>

#include "core/error.h"

namespace photomat {

void FemDomain::AddElement(const std::array<int, 3>& nodes,
                           const std::array<Eigen::Vector3d, 3>& corners) {
  const std::array<Eigen::Vector3d, 3> edges = {corners[1] - corners[0], corners[2] - corners[1],
                                                corners[0] - corners[2]};
  const Eigen::Vector3d area_vector = 0.5 * edges[0].cross(-edges[2]);
  const double area = area_vector.norm();
  std::array<Eigen::Vector3d, 3> gradients;
  Eigen::Vector3d normal = Eigen::Vector3d::Zero();
  // A degenerate (zero-area) element contributes nothing: its gradients are undefined.
  if (area > 1e-14 * std::max(edges[0].squaredNorm(), 1e-300)) {
    normal = area_vector / area;
    // grad phi_k = n x (edge opposite k, counter-clockwise) / (2A).
    for (int k = 0; k < 3; ++k) gradients[k] = normal.cross(edges[(k + 1) % 3]) / (2.0 * area);
  } else {
    for (auto& g : gradients) g.setZero();
  }
  elements_.push_back(nodes);
  areas_.push_back(normal.isZero() ? 0.0 : area);
  gradients_.push_back(gradients);
  edges_.push_back(edges);
  normals_.push_back(normal);
}

void FemDomain::CheckNodesHaveArea(const std::string& source) const {
  std::vector<double> node_area(node_positions_.size(), 0.0);
  for (int e = 0; e < element_count(); ++e) {
    for (int v : elements_[e]) node_area[v] += areas_[e];
  }
  for (std::size_t v = 0; v < node_area.size(); ++v) {
    if (!(node_area[v] > 0.0)) {
      throw Error(source, fmt::format("vertex {} has no area (unused, or only in degenerate "
                                      "triangles): the diffusion equations need every vertex "
                                      "to carry surface",
                                      v));
    }
  }
}

FemDomain FemDomain::FromMesh(const TriangleMesh& mesh) {
  ValidateMesh(mesh, "mesh");
  FemDomain domain;
  domain.node_positions_ = mesh.positions;
  domain.elements_.reserve(mesh.triangles.size());
  for (const auto& t : mesh.triangles) {
    domain.AddElement(t, {mesh.positions[t[0]], mesh.positions[t[1]], mesh.positions[t[2]]});
  }
  domain.CheckNodesHaveArea("mesh");
  return domain;
}

FemDomain FemDomain::PeriodicGrid(int width, int height, double spacing) {
  if (width < 3 || height < 3 || width > 16384 || height > 16384 || !(spacing > 0.0)) {
    throw Error(
        fmt::format("periodic grid: need at least 3 x 3 nodes, at most 16384 a side, and a "
                    "positive spacing (got {} x {}, spacing {})",
                    width, height, spacing));
  }
  FemDomain domain;
  domain.grid_ = GridShape{width, height, spacing};
  for (int y = 0; y < height; ++y) {
    for (int x = 0; x < width; ++x)
      domain.node_positions_.emplace_back(x * spacing, y * spacing, 0);
  }
  auto node = [&](int x, int y) { return (y % height) * width + (x % width); };
  const Eigen::Vector3d o(0, 0, 0), ex(spacing, 0, 0), ey(0, spacing, 0), exy(spacing, spacing, 0);
  for (int y = 0; y < height; ++y) {
    for (int x = 0; x < width; ++x) {
      domain.AddElement({node(x, y), node(x + 1, y), node(x + 1, y + 1)}, {o, ex, exy});
      domain.AddElement({node(x, y), node(x + 1, y + 1), node(x, y + 1)}, {o, exy, ey});
    }
  }
  return domain;
}

double FemDomain::total_area() const {
  double sum = 0.0;
  for (double a : areas_) sum += a;
  return sum;
}

FemOperators::FemOperators(const FemDomain& domain) : domain_(&domain) {
  const int n = domain.node_count();
  std::vector<Eigen::Triplet<double>> pattern;
  pattern.reserve(domain.element_count() * 9);
  for (const auto& e : domain.elements()) {
    for (int a : e) {
      for (int b : e) pattern.emplace_back(a, b, 0.0);
    }
  }
  SparseMatrixD zero(n, n);
  zero.setFromTriplets(pattern.begin(), pattern.end());
  zero.makeCompressed();
  // Offsets of each element's local entries in the value array.
  element_entries_.resize(domain.element_count());
  for (int e = 0; e < domain.element_count(); ++e) {
    const auto& nodes = domain.elements()[e];
    for (int a = 0; a < 3; ++a) {
      for (int b = 0; b < 3; ++b) {
        const int column = nodes[b];
        const int* begin = zero.innerIndexPtr() + zero.outerIndexPtr()[column];
        const int* end = zero.innerIndexPtr() + zero.outerIndexPtr()[column + 1];
        const int* it = std::lower_bound(begin, end, nodes[a]);
        element_entries_[e][3 * a + b] = static_cast<int>(it - zero.innerIndexPtr());
      }
    }
  }
  mass_ = zero;
  lumped_mass_ = zero;
  stiffness_ = zero;
  lumped_mass_vector_ = Eigen::VectorXd::Zero(n);
  double* mass = mass_.valuePtr();
  double* lumped = lumped_mass_.valuePtr();
  double* stiffness = stiffness_.valuePtr();
  for (int e = 0; e < domain.element_count(); ++e) {
    const double area = domain.area(e);
    if (area == 0.0) continue;
    const auto& entries = element_entries_[e];
    const auto& edges = domain.edges(e);
    for (int a = 0; a < 3; ++a) {
      mass[entries[4 * a]] += area / 6.0;
      lumped[entries[4 * a]] += area / 3.0;
      lumped_mass_vector_[domain.elements()[e][a]] += area / 3.0;
      for (int b = 0; b < 3; ++b) {
        if (a != b) mass[entries[3 * a + b]] += area / 12.0;
      }
      // The angle at corner k lies between the edges leaving it; it faces the edge (k+1, k+2).
      const int k = a;
      const Eigen::Vector3d& out = edges[k];           // k -> k+1
      const Eigen::Vector3d in = -edges[(k + 2) % 3];  // k -> k+2
      const double cot = out.dot(in) / (2.0 * area);   // |out x in| = 2A
      const int i = (k + 1) % 3, j = (k + 2) % 3;
      stiffness[entries[3 * i + j]] -= 0.5 * cot;
      stiffness[entries[3 * j + i]] -= 0.5 * cot;
      stiffness[entries[3 * i + i]] += 0.5 * cot;
      stiffness[entries[3 * j + j]] += 0.5 * cot;
    }
  }
}

SparseMatrixD FemOperators::ZeroPattern() const {
  SparseMatrixD zero = mass_;
  std::fill(zero.valuePtr(), zero.valuePtr() + zero.nonZeros(), 0.0);
  return zero;
}

SparseMatrixD FemOperators::TensorStiffness(
    std::span<const Eigen::Matrix3d> element_tensors) const {
  const FemDomain& domain = *domain_;
  if (element_tensors.size() != static_cast<std::size_t>(domain.element_count())) {
    throw Error(fmt::format("tensor stiffness: {} tensors for {} elements", element_tensors.size(),
                            domain.element_count()));
  }
  SparseMatrixD matrix = ZeroPattern();
  double* values = matrix.valuePtr();
  for (int e = 0; e < domain.element_count(); ++e) {
    const double area = domain.area(e);
    if (area == 0.0) continue;
    for (int a = 0; a < 3; ++a) {
      const Eigen::Vector3d d_grad = element_tensors[e] * domain.gradient(e, a);
      for (int b = 0; b < 3; ++b) {
        values[element_entries_[e][3 * a + b]] += area * d_grad.dot(domain.gradient(e, b));
      }
    }
  }
  return matrix;
}

void FemOperators::AddWeightedMass(SparseMatrixD& matrix, const Eigen::VectorXd& c, double weight,
                                   bool lumped) const {
  const FemDomain& domain = *domain_;
  if (c.size() != domain.node_count() || matrix.nonZeros() != mass_.nonZeros()) {
    throw Error("weighted mass: field or matrix does not match the domain");
  }
  double* values = matrix.valuePtr();
  if (lumped) {
    for (int e = 0; e < domain.element_count(); ++e) {
      const auto& nodes = domain.elements()[e];
      const double third = weight * domain.area(e) / 3.0;
      for (int a = 0; a < 3; ++a) values[element_entries_[e][4 * a]] += third * c[nodes[a]];
    }
    return;
  }
  for (int e = 0; e < domain.element_count(); ++e) {
    const auto& nodes = domain.elements()[e];
    const double w = weight * domain.area(e);
    const double c0 = c[nodes[0]], c1 = c[nodes[1]], c2 = c[nodes[2]];
    const double sum = c0 + c1 + c2;
    const std::array<double, 3> cv = {c0, c1, c2};
    const auto& entries = element_entries_[e];
    for (int a = 0; a < 3; ++a) {
      // Diagonal: c_a A/10 + (others) A/30 = A (2 c_a + sum) / 30.
      values[entries[4 * a]] += w * (2.0 * cv[a] + sum) / 30.0;
      for (int b = a + 1; b < 3; ++b) {
        // Off-diagonal: (c_a + c_b) A/30 + c_k A/60 = A (c_a + c_b + sum) / 60.
        const double off = w * (cv[a] + cv[b] + sum) / 60.0;
        values[entries[3 * a + b]] += off;
        values[entries[3 * b + a]] += off;
      }
    }
  }
}

Eigen::VectorXd FemOperators::Load(const Eigen::VectorXd& f, bool lumped) const {
  if (lumped) return lumped_mass_vector_.cwiseProduct(f);
  return mass_ * f;
}

}  // namespace photomat
