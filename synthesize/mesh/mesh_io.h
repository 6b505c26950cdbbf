#pragma once

#include <Eigen/Core>
#include <filesystem>
#include <span>
#include <vector>

#include "synthesize/mesh/mesh.h"

namespace photomat {

// Mesh files go through the Open Asset Import Library (assimp): OBJ, PLY, OFF, STL and the other
// formats it reads.

// Reads every triangle of every mesh in the file into one mesh. Vertices at the same position are
// merged (OBJ files split vertices at texture seams, which would cut the surface apart for
// diffusion); vertices no triangle uses are dropped (the Stanford bunny's OBJ lists 35,947
// vertices of which 34,834 are used); triangles that repeat a vertex after merging are dropped.
// Throws Error naming `path` when the file is missing, unreadable, not a mesh, or has no triangle.
TriangleMesh ReadMesh(const std::filesystem::path& path);

// Writes the mesh with one linear RGB colour per vertex (empty: no colours) and vertex normals,
// atomically. The format follows the extension: ".ply" (ASCII PLY; colours as 8-bit sRGB
// "red green blue alpha", as MeshLab and Blender read them) or ".glb" (binary glTF 2.0;
// colours as the linear COLOR_0 attribute the glTF specification defines). Throws Error naming
// `path` for another extension, a colour count that is not the vertex count, or a failed write.
void WriteMesh(const std::filesystem::path& path, const TriangleMesh& mesh,
               std::span<const Eigen::Vector3f> linear_colours = {});

}  // namespace photomat
