#include "synthesize/mesh/loop_subdivision.h"

#include <algorithm>
#include <cmath>
#include <numbers>

#include "core/error.h"

namespace photomat {
namespace {

TriangleMesh LoopSubdivideOnce(const TriangleMesh& mesh) {
  const int n = mesh.vertex_count();
  const auto edges = EdgeFaceAdjacency(mesh);
  const auto& p = mesh.positions;

  // Vertex points. Boundary vertices follow only their two boundary neighbours, so holes keep
  // their outline (the cubic B-spline curve rule).
  std::vector<Eigen::Vector3d> ring_sum(n, Eigen::Vector3d::Zero());
  std::vector<int> valence(n, 0);
  std::vector<Eigen::Vector3d> boundary_sum(n, Eigen::Vector3d::Zero());
  std::vector<int> boundary_count(n, 0);
  for (const auto& e : edges) {
    const int a = e.vertices[0], b = e.vertices[1];
    ring_sum[a] += p[b];
    ring_sum[b] += p[a];
    ++valence[a];
    ++valence[b];
    if (e.faces[1] < 0) {
      boundary_sum[a] += p[b];
      boundary_sum[b] += p[a];
      ++boundary_count[a];
      ++boundary_count[b];
    }
  }
  TriangleMesh out;
  out.positions.resize(n + edges.size());
  for (int v = 0; v < n; ++v) {
    if (boundary_count[v] == 2) {
      out.positions[v] = 0.75 * p[v] + 0.125 * boundary_sum[v];
    } else if (boundary_count[v] > 0 || valence[v] < 3) {
      out.positions[v] = p[v];  // a corner of a non-manifold boundary: keep it
    } else {
      const double k = valence[v];
      const double c = 0.375 + 0.25 * std::cos(2.0 * std::numbers::pi / k);
      const double beta = (0.625 - c * c) / k;
      out.positions[v] = (1.0 - k * beta) * p[v] + beta * ring_sum[v];
    }
  }

  // Edge points, and the opposite corners that place them.
  auto opposite = [&](int face, int a, int b) {
    for (int v : mesh.triangles[face]) {
      if (v != a && v != b) return v;
    }
    throw Error("Loop subdivision: degenerate triangle");
  };
  std::vector<std::pair<std::array<int, 2>, int>> edge_index;
  edge_index.reserve(edges.size());
  for (std::size_t i = 0; i < edges.size(); ++i) {
    const auto& e = edges[i];
    const int a = e.vertices[0], b = e.vertices[1];
    Eigen::Vector3d point;
    if (e.faces[1] < 0) {
      point = 0.5 * (p[a] + p[b]);
    } else {
      point = 0.375 * (p[a] + p[b]) +
              0.125 * (p[opposite(e.faces[0], a, b)] + p[opposite(e.faces[1], a, b)]);
    }
    out.positions[n + i] = point;
    edge_index.push_back({e.vertices, n + static_cast<int>(i)});
  }
  // `edges` is sorted by vertex pair, so a binary search finds an edge's new vertex.
  auto midpoint = [&](int a, int b) {
    const std::array<int, 2> key{std::min(a, b), std::max(a, b)};
    const auto it = std::lower_bound(edge_index.begin(), edge_index.end(), std::make_pair(key, -1));
    return it->second;
  };
  out.triangles = SplitTriangles(mesh.triangles, midpoint);
  return out;
}

}  // namespace

TriangleMesh LoopSubdivide(const TriangleMesh& mesh, int levels) {
  if (levels < 0 || levels > 6) throw Error("Loop subdivision: levels must be in 0..6");
  TriangleMesh out = mesh;
  for (int i = 0; i < levels; ++i) out = LoopSubdivideOnce(out);
  return out;
}

}  // namespace photomat
