#pragma once

#include <Eigen/Core>
#include <span>
#include <vector>

#include "core/progress.h"
#include "synthesize/mesh/mesh.h"
#include "synthesize/volume/volume.h"

namespace photomat {

// Objects carved out of a solid texture (issue 8, item 5): the surface of a mesh placed inside a
// volume takes, at every vertex, the volume's value there, as if the object had been cut out of a
// block of the material.

// Where the mesh sits in the volume. Mesh axes are volume axes (x, y, z); the mesh's bounding box
// is scaled uniformly (shapes are not stretched) so that its longest side spans `periods` times
// the volume's smallest side, and centred on the volume. Voxel (i, j, k) is the unit cube
// [i, i + 1) x [j, j + 1) x [k, k + 1) with its value at the centre.
struct CarvePlacement {
  // Volume periods across the longest side of the mesh; above 1 the volume repeats, which needs
  // a tileable one (every synthesised and procedural solid of photomat tiles).
  double periods = 1.0;
  // A tileable volume wraps around its faces; otherwise samples beyond the outer voxel centres
  // repeat the face values (and `periods` may not exceed 1).
  bool tileable = true;
};

struct CarveOptions {
  CarvePlacement placement;
  // Sampling density: a mesh whose mean edge is longer than this many voxels (after placement) is
  // subdivided (every triangle into four at its edge midpoints, so the shape does not change)
  // until it is not, so that per-vertex colours show the texture rather than a few samples of it.
  // IMPLEMENTER CHOICE: 1 voxel, the volume's own resolution. 0 keeps the mesh as it is.
  double max_mean_edge_voxels = 1.0;
  // Subdivision stops before the mesh would exceed this many triangles.
  int max_triangles = 4'000'000;
};

// The affine map from mesh coordinates to continuous volume coordinates (voxel units, voxel
// centres at i + 1/2): volume = scale * (mesh - mesh_centre) + volume_centre.
struct CarveMapping {
  double scale = 1.0;
  Eigen::Vector3d mesh_centre = Eigen::Vector3d::Zero();
  Eigen::Vector3d volume_centre = Eigen::Vector3d::Zero();

  Eigen::Vector3d ToVolume(const Eigen::Vector3d& position) const {
    return scale * (position - mesh_centre) + volume_centre;
  }
};

// Throws Error for a non-positive `periods`, or periods above 1 for a volume that does not tile.
CarveMapping PlaceMesh(const TriangleMesh& mesh, const ImageExtent& volume,
                       const CarvePlacement& placement);

// Every channel of `volume` at continuous volume coordinates `at` (voxel units), trilinearly
// interpolated between voxel centres, wrapping (tileable) or clamped at the faces.
void SampleTrilinear(const Image& volume, const Eigen::Vector3d& at, bool tileable,
                     std::span<float> out);

struct CarvedMesh {
  TriangleMesh mesh;  // the input mesh, subdivided as needed (positions in the mesh's units)
  int subdivision_levels = 0;
  CarveMapping mapping;
  // vertex_count x volume.channels(), the volume's values at every vertex.
  std::vector<float> values;
  int channels = 0;

  std::span<const float> at(int vertex) const {
    return {values.data() + static_cast<std::size_t>(vertex) * static_cast<std::size_t>(channels),
            static_cast<std::size_t>(channels)};
  }
};

// Carves `mesh` out of `volume`. Throws Error for an empty volume, an invalid mesh (ValidateMesh)
// or a bad placement.
CarvedMesh CarveMesh(const TriangleMesh& mesh, const Image& volume, const CarveOptions& options,
                     Progress* progress = nullptr);

// Linear RGB colours to show: the volume's R, G, B channels when it names them, else its first
// three, else its first as grey (volume_io.h's DisplayChannels); with `normalise` the shown
// channels' joint range over the vertices is stretched over [0, 1] (for non-colour channels:
// normals, PTM terms), as for slice pictures; otherwise colours are clamped to [0, 1].
std::vector<Eigen::Vector3f> CarvedColours(const CarvedMesh& carved, const Image& volume,
                                           bool normalise);

}  // namespace photomat
