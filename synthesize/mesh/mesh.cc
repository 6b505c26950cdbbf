#include "synthesize/mesh/mesh.h"

#include <fmt/format.h>

#include <algorithm>
#include <cmath>
#include <map>
#include <numbers>

#include "core/error.h"
#include "core/random.h"

namespace photomat {

void ValidateMesh(const TriangleMesh& mesh, const std::string& source) {
  if (mesh.triangles.empty()) throw Error(source, "the mesh has no triangle");
  const int n = mesh.vertex_count();
  for (int v = 0; v < n; ++v) {
    if (!mesh.positions[v].allFinite()) {
      throw Error(source, fmt::format("vertex {} has a non-finite position", v));
    }
  }
  for (int t = 0; t < mesh.triangle_count(); ++t) {
    const auto& tri = mesh.triangles[t];
    for (int k = 0; k < 3; ++k) {
      if (tri[k] < 0 || tri[k] >= n) {
        throw Error(source, fmt::format("triangle {} refers to vertex {} of {}", t, tri[k], n));
      }
    }
    if (tri[0] == tri[1] || tri[1] == tri[2] || tri[0] == tri[2]) {
      throw Error(source, fmt::format("triangle {} repeats a vertex ({} {} {})", t, tri[0], tri[1],
                                      tri[2]));
    }
  }
}

BoundingBox ComputeBoundingBox(const TriangleMesh& mesh) {
  BoundingBox box;
  if (mesh.positions.empty()) return box;
  box.min = box.max = mesh.positions.front();
  for (const auto& p : mesh.positions) {
    box.min = box.min.cwiseMin(p);
    box.max = box.max.cwiseMax(p);
  }
  return box;
}

namespace {

Eigen::Vector3d AreaVector(const TriangleMesh& mesh, int triangle) {
  const auto& t = mesh.triangles[triangle];
  const auto& p = mesh.positions;
  return 0.5 * (p[t[1]] - p[t[0]]).cross(p[t[2]] - p[t[0]]);
}

}  // namespace

double TriangleArea(const TriangleMesh& mesh, int triangle) {
  return AreaVector(mesh, triangle).norm();
}

double SurfaceArea(const TriangleMesh& mesh) {
  double area = 0.0;
  for (int t = 0; t < mesh.triangle_count(); ++t) area += TriangleArea(mesh, t);
  return area;
}

double EnclosedVolume(const TriangleMesh& mesh) {
  double volume = 0.0;
  for (const auto& t : mesh.triangles) {
    volume += mesh.positions[t[0]].dot(mesh.positions[t[1]].cross(mesh.positions[t[2]]));
  }
  return volume / 6.0;
}

std::vector<Eigen::Vector3d> FaceNormals(const TriangleMesh& mesh) {
  std::vector<Eigen::Vector3d> normals(mesh.triangles.size());
  for (int t = 0; t < mesh.triangle_count(); ++t) {
    const Eigen::Vector3d a = AreaVector(mesh, t);
    const double norm = a.norm();
    normals[t] = norm > 0.0 ? (a / norm).eval() : Eigen::Vector3d::Zero();
  }
  return normals;
}

std::vector<Eigen::Vector3d> VertexNormals(const TriangleMesh& mesh) {
  std::vector<Eigen::Vector3d> normals(mesh.positions.size(), Eigen::Vector3d::Zero());
  for (int t = 0; t < mesh.triangle_count(); ++t) {
    const Eigen::Vector3d a = AreaVector(mesh, t);
    for (int v : mesh.triangles[t]) normals[v] += a;
  }
  for (auto& n : normals) {
    const double norm = n.norm();
    n = norm > 0.0 ? (n / norm).eval() : Eigen::Vector3d::UnitZ();
  }
  return normals;
}

std::vector<std::array<int, 2>> UniqueEdges(const TriangleMesh& mesh) {
  std::vector<std::array<int, 2>> edges;
  edges.reserve(mesh.triangles.size() * 3);
  for (const auto& t : mesh.triangles) {
    for (int k = 0; k < 3; ++k) {
      const int a = t[k];
      const int b = t[(k + 1) % 3];
      edges.push_back({std::min(a, b), std::max(a, b)});
    }
  }
  std::sort(edges.begin(), edges.end());
  edges.erase(std::unique(edges.begin(), edges.end()), edges.end());
  return edges;
}

double MeanEdgeLength(const TriangleMesh& mesh) {
  const auto edges = UniqueEdges(mesh);
  if (edges.empty()) return 0.0;
  double sum = 0.0;
  for (const auto& e : edges) sum += (mesh.positions[e[0]] - mesh.positions[e[1]]).norm();
  return sum / static_cast<double>(edges.size());
}

std::vector<EdgeFaces> EdgeFaceAdjacency(const TriangleMesh& mesh) {
  // (edge, face) pairs sorted by edge: consecutive equal edges are the faces sharing it.
  std::vector<std::pair<std::array<int, 2>, int>> pairs;
  pairs.reserve(mesh.triangles.size() * 3);
  for (int t = 0; t < mesh.triangle_count(); ++t) {
    const auto& tri = mesh.triangles[t];
    for (int k = 0; k < 3; ++k) {
      const int a = tri[k];
      const int b = tri[(k + 1) % 3];
      pairs.push_back({{std::min(a, b), std::max(a, b)}, t});
    }
  }
  std::sort(pairs.begin(), pairs.end());
  std::vector<EdgeFaces> edges;
  for (std::size_t i = 0; i < pairs.size();) {
    std::size_t j = i;
    while (j < pairs.size() && pairs[j].first == pairs[i].first) ++j;
    // Non-manifold edges (more than two faces) keep their first two faces.
    edges.push_back({pairs[i].first, {pairs[i].second, j - i > 1 ? pairs[i + 1].second : -1}});
    i = j;
  }
  return edges;
}

int CountBoundaryEdges(const TriangleMesh& mesh) {
  int count = 0;
  for (const auto& e : EdgeFaceAdjacency(mesh)) count += e.faces[1] < 0 ? 1 : 0;
  return count;
}

double NormalAngleDegrees(const TriangleMesh& mesh, const EdgeFaces& edge) {
  if (edge.faces[1] < 0) return 0.0;
  const Eigen::Vector3d a = AreaVector(mesh, edge.faces[0]).normalized();
  const Eigen::Vector3d b = AreaVector(mesh, edge.faces[1]).normalized();
  return std::atan2(a.cross(b).norm(), a.dot(b)) * 180.0 / std::numbers::pi;
}

void NormalizeMesh(TriangleMesh& mesh, MeshNormalization normalization, double size) {
  if (!(size > 0.0)) throw Error(fmt::format("mesh size must be positive, not {}", size));
  const BoundingBox box = ComputeBoundingBox(mesh);
  const double current = normalization == MeshNormalization::kBoundingBox
                             ? box.Diagonal()
                             : std::sqrt(SurfaceArea(mesh));
  if (!(current > 0.0)) throw Error("cannot normalise a mesh of zero size");
  const double scale = size / current;
  const Eigen::Vector3d centre = box.Centre();
  for (auto& p : mesh.positions) p = (p - centre) * scale;
}

MeshNormalization ParseMeshNormalization(const std::string& text) {
  if (text == "bbox") return MeshNormalization::kBoundingBox;
  if (text == "area") return MeshNormalization::kArea;
  throw Error(fmt::format("unknown normalisation \"{}\": expected bbox or area", text));
}

namespace {

// Splits every triangle into four at its edge midpoints (shared midpoints reused).
TriangleMesh SplitMidpoints(const TriangleMesh& mesh) {
  TriangleMesh out;
  out.positions = mesh.positions;
  std::map<std::pair<int, int>, int> midpoint;
  auto middle = [&](int a, int b) {
    const std::pair<int, int> key(std::min(a, b), std::max(a, b));
    const auto [it, inserted] = midpoint.try_emplace(key, out.vertex_count());
    if (inserted) out.positions.push_back(0.5 * (mesh.positions[a] + mesh.positions[b]));
    return it->second;
  };
  out.triangles = SplitTriangles(mesh.triangles, middle);
  return out;
}

}  // namespace

std::vector<std::array<int, 3>> SplitTriangles(const std::vector<std::array<int, 3>>& triangles,
                                               const std::function<int(int, int)>& edge_vertex) {
  std::vector<std::array<int, 3>> out;
  out.reserve(triangles.size() * 4);
  for (const auto& t : triangles) {
    const int ab = edge_vertex(t[0], t[1]);
    const int bc = edge_vertex(t[1], t[2]);
    const int ca = edge_vertex(t[2], t[0]);
    out.push_back({t[0], ab, ca});
    out.push_back({t[1], bc, ab});
    out.push_back({t[2], ca, bc});
    out.push_back({ab, bc, ca});
  }
  return out;
}

TriangleMesh SubdivideMidpoints(const TriangleMesh& mesh, int levels) {
  TriangleMesh current = mesh;
  for (int level = 0; level < levels; ++level) current = SplitMidpoints(current);
  return current;
}

TriangleMesh MakeIcosphere(double radius, int subdivisions) {
  if (!(radius > 0.0) || subdivisions < 0 || subdivisions > 9) {
    throw Error(
        fmt::format("icosphere: radius must be positive and subdivisions in 0..9 (got {}, "
                    "{})",
                    radius, subdivisions));
  }
  const double g = (1.0 + std::sqrt(5.0)) / 2.0;
  TriangleMesh mesh;
  mesh.positions = {{-1, g, 0},  {1, g, 0},  {-1, -g, 0}, {1, -g, 0}, {0, -1, g},  {0, 1, g},
                    {0, -1, -g}, {0, 1, -g}, {g, 0, -1},  {g, 0, 1},  {-g, 0, -1}, {-g, 0, 1}};
  mesh.triangles = {{0, 11, 5}, {0, 5, 1},  {0, 1, 7},   {0, 7, 10}, {0, 10, 11},
                    {1, 5, 9},  {5, 11, 4}, {11, 10, 2}, {10, 7, 6}, {7, 1, 8},
                    {3, 9, 4},  {3, 4, 2},  {3, 2, 6},   {3, 6, 8},  {3, 8, 9},
                    {4, 9, 5},  {2, 4, 11}, {6, 2, 10},  {8, 6, 7},  {9, 8, 1}};
  mesh = SubdivideMidpoints(mesh, subdivisions);
  for (auto& p : mesh.positions) p = p.normalized() * radius;
  return mesh;
}

TriangleMesh MakeFacetedPolyhedron(Polyhedron shape, double circumradius, int subdivisions) {
  if (!(circumradius > 0.0) || subdivisions < 0 || subdivisions > 9) {
    throw Error(fmt::format(
        "polyhedron: circumradius must be positive and subdivisions in 0..9 (got {}, {})",
        circumradius, subdivisions));
  }
  TriangleMesh mesh;
  if (shape == Polyhedron::kCube) {
    for (int i = 0; i < 8; ++i) {
      mesh.positions.push_back({i & 1 ? 1.0 : -1.0, i & 2 ? 1.0 : -1.0, i & 4 ? 1.0 : -1.0});
    }
    // Corner index = x + 2 y + 4 z (bits set for +1); each face counter-clockwise from outside.
    const std::array<std::array<int, 4>, 6> faces = {
        {{0, 2, 3, 1}, {4, 5, 7, 6}, {0, 1, 5, 4}, {2, 6, 7, 3}, {0, 4, 6, 2}, {1, 3, 7, 5}}};
    for (const auto& f : faces) {
      mesh.triangles.push_back({f[0], f[1], f[2]});
      mesh.triangles.push_back({f[0], f[2], f[3]});
    }
  } else {
    mesh = MakeIcosphere(1.0, 0);
  }
  const double scale = circumradius / mesh.positions[0].norm();
  for (auto& p : mesh.positions) p *= scale;
  return SubdivideMidpoints(mesh, subdivisions);
}

TriangleMesh MakeTorus(double major_radius, double minor_radius, int major_segments,
                       int minor_segments) {
  if (!(major_radius > minor_radius) || !(minor_radius > 0.0) || major_segments < 3 ||
      minor_segments < 3) {
    throw Error("torus: need major radius > minor radius > 0 and at least 3 segments each way");
  }
  TriangleMesh mesh;
  const double two_pi = 2.0 * std::numbers::pi;
  for (int i = 0; i < major_segments; ++i) {
    const double u = two_pi * i / major_segments;
    for (int j = 0; j < minor_segments; ++j) {
      const double v = two_pi * j / minor_segments;
      const double r = major_radius + minor_radius * std::cos(v);
      mesh.positions.push_back({r * std::cos(u), r * std::sin(u), minor_radius * std::sin(v)});
    }
  }
  auto index = [&](int i, int j) {
    return (i % major_segments) * minor_segments + (j % minor_segments);
  };
  for (int i = 0; i < major_segments; ++i) {
    for (int j = 0; j < minor_segments; ++j) {
      const int a = index(i, j), b = index(i + 1, j), c = index(i + 1, j + 1), d = index(i, j + 1);
      mesh.triangles.push_back({a, b, c});
      mesh.triangles.push_back({a, c, d});
    }
  }
  return mesh;
}

void AddNormalNoise(TriangleMesh& mesh, double sigma, std::uint64_t seed) {
  const auto normals = VertexNormals(mesh);
  Random random(seed);
  for (int v = 0; v < mesh.vertex_count(); ++v) {
    mesh.positions[v] += sigma * random.Normal() * normals[v];
  }
}

std::vector<std::vector<int>> VertexNeighbours(const TriangleMesh& mesh) {
  std::vector<std::vector<int>> neighbours(mesh.positions.size());
  for (const auto& e : UniqueEdges(mesh)) {
    neighbours[e[0]].push_back(e[1]);
    neighbours[e[1]].push_back(e[0]);
  }
  for (auto& n : neighbours) std::sort(n.begin(), n.end());
  return neighbours;
}

}  // namespace photomat
