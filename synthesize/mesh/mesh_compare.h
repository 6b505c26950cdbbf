#pragma once

#include <Eigen/Core>
#include <vector>

#include "synthesize/mesh/mesh.h"

namespace photomat {

// Comparisons of a deformed mesh (noisy, smoothed) with a reference of the same connectivity:
// what geometric diffusion is judged by.

// Distance from p to the triangle (a, b, c) (closest point by Voronoi regions, Ericson 2005).
double PointTriangleDistance(const Eigen::Vector3d& p, const Eigen::Vector3d& a,
                             const Eigen::Vector3d& b, const Eigen::Vector3d& c);

struct SurfaceDeviation {
  double mean = 0.0;
  double rms = 0.0;
  double max = 0.0;
};
// Distance of each vertex of `mesh` to the `reference` surface, searched among the reference
// triangles within `rings` edge rings of the corresponding vertex (the meshes share connectivity
// and vertices moved by less than that neighbourhood). Throws Error if the connectivity differs.
SurfaceDeviation DeviationFromReference(const TriangleMesh& mesh, const TriangleMesh& reference,
                                        int rings = 2);

// Interior edges of `mesh` whose faces' normals differ by more than `threshold_degrees`: the
// sharp features (a CAD part's creases).
std::vector<EdgeFaces> FeatureEdges(const TriangleMesh& mesh, double threshold_degrees);

struct AngleChange {
  // mean of angle(mesh) - angle(reference) over the edges, degrees: negative when the edges are
  // rounded off, the bias feature-preserving smoothing must avoid
  double mean_signed = 0.0;
  double mean = 0.0;    // mean |angle(mesh) - angle(reference)| over the edges, degrees
  double median = 0.0;  // per-edge |change|, degrees
  double percentile90 = 0.0;
  double max = 0.0;
  // Fraction of the edges whose |change| is at most the tolerance asked for.
  double within_tolerance = 0.0;
};
// How much the normal angles across `edges` (found on the reference) differ on `mesh`, edge by
// edge (an average hides rounded and sharpened edges that cancel).
AngleChange FeatureAngleChange(const TriangleMesh& mesh, const TriangleMesh& reference,
                               const std::vector<EdgeFaces>& edges, double tolerance_degrees = 5.0);

}  // namespace photomat
