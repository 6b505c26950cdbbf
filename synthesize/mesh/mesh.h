#pragma once

#include <Eigen/Core>
#include <Eigen/Geometry>
#include <array>
#include <cstdint>
#include <functional>
#include <string>
#include <vector>

namespace photomat {

// A triangle mesh: shared vertex positions and triangles of three vertex indices, counter-clockwise
// seen from outside (so face normals point out). The type every surface algorithm of photomat takes
// (reaction-diffusion on surfaces, solid textures carved into objects); per-vertex fields live
// beside it as vectors indexed like `positions`.
struct TriangleMesh {
  std::vector<Eigen::Vector3d> positions;
  std::vector<std::array<int, 3>> triangles;

  int vertex_count() const { return static_cast<int>(positions.size()); }
  int triangle_count() const { return static_cast<int>(triangles.size()); }
};

// Throws Error naming `source` when a triangle has an index out of range or repeats a vertex, a
// position is not finite, or there is no triangle.
void ValidateMesh(const TriangleMesh& mesh, const std::string& source);

struct BoundingBox {
  Eigen::Vector3d min = Eigen::Vector3d::Zero();
  Eigen::Vector3d max = Eigen::Vector3d::Zero();
  Eigen::Vector3d Centre() const { return 0.5 * (min + max); }
  double Diagonal() const { return (max - min).norm(); }
};
BoundingBox ComputeBoundingBox(const TriangleMesh& mesh);

double TriangleArea(const TriangleMesh& mesh, int triangle);
double SurfaceArea(const TriangleMesh& mesh);
// Volume enclosed by a closed, outward-oriented mesh (divergence theorem).
double EnclosedVolume(const TriangleMesh& mesh);
// Unit face normals (zero for a degenerate triangle).
std::vector<Eigen::Vector3d> FaceNormals(const TriangleMesh& mesh);
// Unit vertex normals: area-weighted sums of the adjacent face normals.
std::vector<Eigen::Vector3d> VertexNormals(const TriangleMesh& mesh);

// Each undirected edge once, as (lower index, higher index), sorted.
std::vector<std::array<int, 2>> UniqueEdges(const TriangleMesh& mesh);
double MeanEdgeLength(const TriangleMesh& mesh);
// Edges used by one triangle only (holes, like the scanned bunny's base).
int CountBoundaryEdges(const TriangleMesh& mesh);

// For each undirected edge shared by exactly two triangles: the two triangles. Used for dihedral
// angles (feature edges) and Loop subdivision.
struct EdgeFaces {
  std::array<int, 2> vertices;  // lower index first
  std::array<int, 2> faces;     // faces[1] is -1 on a boundary edge
};
std::vector<EdgeFaces> EdgeFaceAdjacency(const TriangleMesh& mesh);
// Angle in degrees between the normals of the two faces of an interior edge: 0 on a flat surface,
// 90 on a cube's edge.
double NormalAngleDegrees(const TriangleMesh& mesh, const EdgeFaces& edge);

// How to bring meshes of different units to one size before choosing diffusion constants and time
// steps.
enum class MeshNormalization {
  kBoundingBox,  // bounding-box diagonal becomes `size`
  kArea,         // surface area becomes size^2
};
// Centres the mesh on its bounding-box centre, then scales it uniformly.
void NormalizeMesh(TriangleMesh& mesh, MeshNormalization normalization, double size);
// "bbox" or "area"; Error otherwise.
MeshNormalization ParseMeshNormalization(const std::string& text);

// The four triangles each of `triangles` splits into at the new vertices of its edges,
// edge_vertex(a, b) for the edge from a to b (called for the edges a-b, b-c, c-a of each triangle
// in turn): the three corners, then the middle one, all oriented as the triangle. The topology of
// midpoint and Loop subdivision; they differ in where the vertices go.
std::vector<std::array<int, 3>> SplitTriangles(const std::vector<std::array<int, 3>>& triangles,
                                               const std::function<int(int, int)>& edge_vertex);

// Splits every triangle into four at its edge midpoints, `levels` times (a midpoint shared by two
// triangles is one vertex). Positions of existing vertices are kept (they stay the first
// vertex_count() vertices), new ones lie on the edges: unlike Loop subdivision the surface does
// not move, so sharp features stay sharp.
TriangleMesh SubdivideMidpoints(const TriangleMesh& mesh, int levels);

// An icosahedron subdivided `subdivisions` times (each time 4 triangles per triangle), projected
// onto the sphere of `radius` around the origin: 10 * 4^n + 2 vertices of nearly equal spacing.
TriangleMesh MakeIcosphere(double radius, int subdivisions);
// A torus around the z axis: tube centre at `major_radius`, tube radius `minor_radius`,
// major_segments x minor_segments vertices.
TriangleMesh MakeTorus(double major_radius, double minor_radius, int major_segments,
                       int minor_segments);

// Flat-faced polyhedra centred at the origin with vertices on the sphere of `circumradius`, every
// triangle split into four at its edge midpoints `subdivisions` times but kept flat: meshes with
// exactly known sharp edges (a cube's 90 degree normal angle, an icosahedron's 41.8) for feature-
// preserving smoothing. A cube's square faces are two triangles each before subdivision.
enum class Polyhedron { kCube, kIcosahedron };
TriangleMesh MakeFacetedPolyhedron(Polyhedron shape, double circumradius, int subdivisions);

// Moves every vertex along its normal by Gaussian noise of standard deviation `sigma` (seeded): the
// noisy scans that geometric diffusion removes.
void AddNormalNoise(TriangleMesh& mesh, double sigma, std::uint64_t seed);

// The vertices of each vertex's one-ring, sorted (adjacency for smoothing and curvature).
std::vector<std::vector<int>> VertexNeighbours(const TriangleMesh& mesh);

}  // namespace photomat
