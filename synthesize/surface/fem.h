#pragma once

#include <Eigen/Core>
#include <Eigen/SparseCore>
#include <array>
#include <optional>
#include <span>
#include <vector>

#include "synthesize/mesh/mesh.h"

namespace photomat {

// Linear (P1) triangle finite elements on a surface (Bajaj, Zhang and Xu, section 3, with the
// spec's P1 substitute for the Loop-limit basis; Loop-subdivide the mesh first for a finer basis).
// One hat function per node; every operator is assembled element by element from the element's
// area and the constant gradients of its three hat functions.

using SparseMatrixD = Eigen::SparseMatrix<double>;

// The shape of a periodic grid domain (a flat torus: nodes x + width * y, spacing `spacing`).
struct GridShape {
  int width = 0;
  int height = 0;
  double spacing = 1.0;
};

class FemDomain {
 public:
  // The mesh's triangles as elements. Throws Error if a vertex ends up with no area (isolated or
  // only in degenerate triangles): its equation would be singular.
  static FemDomain FromMesh(const TriangleMesh& mesh);
  // A width x height periodic grid of spacing `spacing`, each cell split into two right triangles
  // along the same diagonal, wrapping at the edges: the same equations produce tileable textures.
  // (On this grid the cotangent stiffness is the 5-point Laplacian and the lumped mass is
  // spacing^2: with lumped mass, the classic finite-difference scheme. Use lumped mass here: the
  // consistent mass couples nodes along the split diagonal only, and Gray-Scott fronts then grow
  // along that diagonal.)
  static FemDomain PeriodicGrid(int width, int height, double spacing);

  int node_count() const { return static_cast<int>(node_positions_.size()); }
  int element_count() const { return static_cast<int>(elements_.size()); }
  const std::vector<std::array<int, 3>>& elements() const { return elements_; }
  double area(int element) const { return areas_[element]; }
  // The gradient of the hat function of the element's k-th node (constant on the element).
  const Eigen::Vector3d& gradient(int element, int k) const { return gradients_[element][k]; }
  // Unit normal of the element (+z on a grid).
  const Eigen::Vector3d& normal(int element) const { return normals_[element]; }
  // Edge vectors of the element, corner k to corner k+1 (unwrapped on a periodic grid).
  const std::array<Eigen::Vector3d, 3>& edges(int element) const { return edges_[element]; }
  // Node positions (grid: (x, y, 0) * spacing), for initial conditions that depend on place.
  const std::vector<Eigen::Vector3d>& node_positions() const { return node_positions_; }
  const std::optional<GridShape>& grid() const { return grid_; }
  double total_area() const;

 private:
  void AddElement(const std::array<int, 3>& nodes, const std::array<Eigen::Vector3d, 3>& corners);
  void CheckNodesHaveArea(const std::string& source) const;

  std::vector<std::array<int, 3>> elements_;
  std::vector<double> areas_;
  std::vector<std::array<Eigen::Vector3d, 3>> gradients_;
  std::vector<std::array<Eigen::Vector3d, 3>> edges_;
  std::vector<Eigen::Vector3d> normals_;
  std::vector<Eigen::Vector3d> node_positions_;
  std::optional<GridShape> grid_;
};

// The assembled operators of a domain, all on one sparsity pattern (every pair of nodes sharing an
// element, diagonal included), so a time step combines them entry by entry without re-building
// structure. Matrices are symmetric and stored whole.
class FemOperators {
 public:
  // Keeps a pointer to `domain`, which must outlive the operators.
  explicit FemOperators(const FemDomain& domain);

  const FemDomain& domain() const { return *domain_; }
  // Consistent mass (phi_i, phi_j): A/6 on the diagonal and A/12 off it, per element.
  const SparseMatrixD& mass() const { return mass_; }
  // Lumped mass: A/3 per element node, as a diagonal matrix on the same pattern and as a vector.
  const SparseMatrixD& lumped_mass() const { return lumped_mass_; }
  const Eigen::VectorXd& lumped_mass_vector() const { return lumped_mass_vector_; }
  // Cotangent stiffness (grad phi_i, grad phi_j): K_ij = -(cot alpha_ij + cot beta_ij) / 2,
  // K_ii = -sum_j K_ij.
  const SparseMatrixD& stiffness() const { return stiffness_; }
  // A zero matrix with the pattern.
  SparseMatrixD ZeroPattern() const;

  // Tensor stiffness (D grad phi_i, grad phi_j) with one 3x3 tensor per element (D = identity
  // gives stiffness()).
  SparseMatrixD TensorStiffness(std::span<const Eigen::Matrix3d> element_tensors) const;
  // Adds weight * (c phi_i, phi_j) for the piecewise-linear field c (one value per node) into
  // `matrix` (which must have the pattern), with the exact P1 integrals
  // int phi_i^3 = A/10, int phi_i^2 phi_j = A/30, int phi_i phi_j phi_k = A/60; `lumped` adds the
  // diagonal c_i * (A/3 per element) instead.
  void AddWeightedMass(SparseMatrixD& matrix, const Eigen::VectorXd& c, double weight,
                       bool lumped) const;
  // The load vector (f, phi_j) of a piecewise-linear f: mass * f (lumped: m_j f_j).
  Eigen::VectorXd Load(const Eigen::VectorXd& f, bool lumped) const;
  // mass() or lumped_mass().
  const SparseMatrixD& Mass(bool lumped) const { return lumped ? lumped_mass_ : mass_; }

 private:
  const FemDomain* domain_;
  // For each element, the offsets into valuePtr() of its 3x3 local matrix, row-major.
  std::vector<std::array<int, 9>> element_entries_;
  SparseMatrixD mass_, lumped_mass_, stiffness_;
  Eigen::VectorXd lumped_mass_vector_;
};

}  // namespace photomat
