#include "synthesize/mesh/mesh_compare.h"

#include <algorithm>
#include <cmath>
#include <limits>

#include "core/error.h"

namespace photomat {

double PointTriangleDistance(const Eigen::Vector3d& p, const Eigen::Vector3d& a,
                             const Eigen::Vector3d& b, const Eigen::Vector3d& c) {
  const Eigen::Vector3d ab = b - a, ac = c - a, ap = p - a;
  const double d1 = ab.dot(ap), d2 = ac.dot(ap);
  if (d1 <= 0.0 && d2 <= 0.0) return ap.norm();
  const Eigen::Vector3d bp = p - b;
  const double d3 = ab.dot(bp), d4 = ac.dot(bp);
  if (d3 >= 0.0 && d4 <= d3) return bp.norm();
  const double vc = d1 * d4 - d3 * d2;
  if (vc <= 0.0 && d1 >= 0.0 && d3 <= 0.0) return (p - (a + d1 / (d1 - d3) * ab)).norm();
  const Eigen::Vector3d cp = p - c;
  const double d5 = ab.dot(cp), d6 = ac.dot(cp);
  if (d6 >= 0.0 && d5 <= d6) return cp.norm();
  const double vb = d5 * d2 - d1 * d6;
  if (vb <= 0.0 && d2 >= 0.0 && d6 <= 0.0) return (p - (a + d2 / (d2 - d6) * ac)).norm();
  const double va = d3 * d6 - d5 * d4;
  if (va <= 0.0 && (d4 - d3) >= 0.0 && (d5 - d6) >= 0.0) {
    const double w = (d4 - d3) / ((d4 - d3) + (d5 - d6));
    return (p - (b + w * (c - b))).norm();
  }
  const double denominator = 1.0 / (va + vb + vc);
  const double v = vb * denominator, w = vc * denominator;
  return (p - (a + ab * v + ac * w)).norm();
}

SurfaceDeviation DeviationFromReference(const TriangleMesh& mesh, const TriangleMesh& reference,
                                        int rings) {
  if (mesh.vertex_count() != reference.vertex_count() || mesh.triangles != reference.triangles) {
    throw Error("surface deviation: the meshes do not share connectivity");
  }
  const int n = reference.vertex_count();
  std::vector<std::vector<int>> vertex_faces(n);
  for (int t = 0; t < reference.triangle_count(); ++t) {
    for (int v : reference.triangles[t]) vertex_faces[v].push_back(t);
  }
  const auto neighbours = VertexNeighbours(reference);
  SurfaceDeviation deviation;
  double sum = 0.0, sum2 = 0.0;
  std::vector<int> ring, next, faces;
  std::vector<int> seen(n, -1);
  for (int v = 0; v < n; ++v) {
    ring.assign(1, v);
    seen[v] = v;
    std::vector<int> all = ring;
    for (int r = 0; r < rings; ++r) {
      next.clear();
      for (int u : ring) {
        for (int w : neighbours[u]) {
          if (seen[w] != v) {
            seen[w] = v;
            next.push_back(w);
          }
        }
      }
      all.insert(all.end(), next.begin(), next.end());
      ring.swap(next);
    }
    faces.clear();
    for (int u : all) faces.insert(faces.end(), vertex_faces[u].begin(), vertex_faces[u].end());
    double best = std::numeric_limits<double>::infinity();
    for (int t : faces) {
      const auto& tri = reference.triangles[t];
      best = std::min(
          best, PointTriangleDistance(mesh.positions[v], reference.positions[tri[0]],
                                      reference.positions[tri[1]], reference.positions[tri[2]]));
    }
    sum += best;
    sum2 += best * best;
    deviation.max = std::max(deviation.max, best);
  }
  deviation.mean = sum / n;
  deviation.rms = std::sqrt(sum2 / n);
  return deviation;
}

std::vector<EdgeFaces> FeatureEdges(const TriangleMesh& mesh, double threshold_degrees) {
  std::vector<EdgeFaces> edges;
  for (const auto& edge : EdgeFaceAdjacency(mesh)) {
    if (edge.faces[1] >= 0 && NormalAngleDegrees(mesh, edge) > threshold_degrees) {
      edges.push_back(edge);
    }
  }
  return edges;
}

AngleChange FeatureAngleChange(const TriangleMesh& mesh, const TriangleMesh& reference,
                               const std::vector<EdgeFaces>& edges, double tolerance_degrees) {
  AngleChange change;
  if (edges.empty()) return change;
  std::vector<double> differences;
  differences.reserve(edges.size());
  double signed_sum = 0.0;
  for (const auto& edge : edges) {
    const double delta = NormalAngleDegrees(mesh, edge) - NormalAngleDegrees(reference, edge);
    signed_sum += delta;
    differences.push_back(std::abs(delta));
  }
  const double count = static_cast<double>(differences.size());
  change.mean_signed = signed_sum / count;
  double sum = 0.0;
  int within = 0;
  for (double d : differences) {
    sum += d;
    within += d <= tolerance_degrees ? 1 : 0;
  }
  change.mean = sum / count;
  change.within_tolerance = within / count;
  std::sort(differences.begin(), differences.end());
  // Nearest-rank percentiles.
  auto percentile = [&](double p) {
    const auto rank = static_cast<std::size_t>(std::ceil(p * count));
    return differences[std::clamp<std::size_t>(rank, 1, differences.size()) - 1];
  };
  change.median = percentile(0.5);
  change.percentile90 = percentile(0.9);
  change.max = differences.back();
  return change;
}

}  // namespace photomat
