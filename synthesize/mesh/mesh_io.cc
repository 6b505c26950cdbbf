#include "synthesize/mesh/mesh_io.h"

#include <assimp/material.h>
#include <assimp/postprocess.h>
#include <assimp/scene.h>
#include <fmt/format.h>
#include <spdlog/spdlog.h>

#include <algorithm>
#include <assimp/Exporter.hpp>
#include <assimp/Importer.hpp>
#include <cmath>
#include <map>
#include <memory>

#include "core/atomic_file.h"
#include "core/colour.h"
#include "core/error.h"
#include "core/text_parsing.h"

namespace photomat {
namespace {

// Merges vertices with bit-identical positions, keeps only used vertices (in order of first use)
// and drops triangles that become degenerate.
TriangleMesh WeldAndCompact(const std::vector<Eigen::Vector3d>& positions,
                            const std::vector<std::array<int, 3>>& triangles, int& dropped) {
  std::map<std::array<double, 3>, int> index_of;
  TriangleMesh mesh;
  auto vertex = [&](int i) {
    const auto& p = positions[i];
    const auto [it, inserted] = index_of.try_emplace({p.x(), p.y(), p.z()}, mesh.vertex_count());
    if (inserted) mesh.positions.push_back(p);
    return it->second;
  };
  dropped = 0;
  for (const auto& t : triangles) {
    const std::array<int, 3> w{vertex(t[0]), vertex(t[1]), vertex(t[2])};
    if (w[0] == w[1] || w[1] == w[2] || w[0] == w[2]) {
      ++dropped;
      continue;
    }
    mesh.triangles.push_back(w);
  }
  return mesh;
}

}  // namespace

TriangleMesh ReadMesh(const std::filesystem::path& path) {
  if (!std::filesystem::exists(path)) throw Error(path, "no such file");
  Assimp::Importer importer;
  // Validation first: a damaged file (face indices out of range) must be an error, never reach
  // the later steps that would index with them. Only triangles matter: points and lines are
  // removed, polygons triangulated, and node transforms applied so multi-part files come out in one
  // frame.
  importer.SetPropertyInteger(AI_CONFIG_PP_SBP_REMOVE,
                              aiPrimitiveType_POINT | aiPrimitiveType_LINE);
  const aiScene* scene =
      importer.ReadFile(path.string(), aiProcess_ValidateDataStructure | aiProcess_Triangulate |
                                           aiProcess_JoinIdenticalVertices | aiProcess_SortByPType |
                                           aiProcess_PreTransformVertices);
  if (scene == nullptr) {
    throw Error(path, fmt::format("cannot read the mesh: {}", importer.GetErrorString()));
  }
  std::vector<Eigen::Vector3d> positions;
  std::vector<std::array<int, 3>> triangles;
  for (unsigned m = 0; m < scene->mNumMeshes; ++m) {
    const aiMesh* part = scene->mMeshes[m];
    const int offset = static_cast<int>(positions.size());
    for (unsigned v = 0; v < part->mNumVertices; ++v) {
      const aiVector3D& p = part->mVertices[v];
      positions.emplace_back(p.x, p.y, p.z);
    }
    for (unsigned f = 0; f < part->mNumFaces; ++f) {
      const aiFace& face = part->mFaces[f];
      if (face.mNumIndices != 3) continue;
      triangles.push_back({offset + static_cast<int>(face.mIndices[0]),
                           offset + static_cast<int>(face.mIndices[1]),
                           offset + static_cast<int>(face.mIndices[2])});
    }
  }
  if (triangles.empty()) throw Error(path, "the file holds no triangle");
  int dropped = 0;
  TriangleMesh mesh = WeldAndCompact(positions, triangles, dropped);
  if (dropped > 0) {
    spdlog::warn("{}: dropped {} degenerate triangles (a repeated vertex)", path.string(), dropped);
  }
  ValidateMesh(mesh, path.string());
  return mesh;
}

namespace {

// An assimp scene owning one mesh (aiScene's destructor frees what it points to).
std::unique_ptr<aiScene> MakeScene(const TriangleMesh& mesh,
                                   std::span<const Eigen::Vector3f> colours, bool srgb_colours) {
  auto scene = std::make_unique<aiScene>();
  scene->mRootNode = new aiNode();
  scene->mRootNode->mNumMeshes = 1;
  scene->mRootNode->mMeshes = new unsigned[1]{0};
  scene->mNumMaterials = 1;
  scene->mMaterials = new aiMaterial* [1] { new aiMaterial() };
  scene->mNumMeshes = 1;
  scene->mMeshes = new aiMesh* [1] { new aiMesh() };
  aiMesh& out = *scene->mMeshes[0];
  out.mMaterialIndex = 0;
  out.mPrimitiveTypes = aiPrimitiveType_TRIANGLE;
  const unsigned n = static_cast<unsigned>(mesh.vertex_count());
  out.mNumVertices = n;
  out.mVertices = new aiVector3D[n];
  out.mNormals = new aiVector3D[n];
  const auto normals = VertexNormals(mesh);
  for (unsigned v = 0; v < n; ++v) {
    const auto& p = mesh.positions[v];
    out.mVertices[v] =
        aiVector3D(static_cast<float>(p.x()), static_cast<float>(p.y()), static_cast<float>(p.z()));
    out.mNormals[v] =
        aiVector3D(static_cast<float>(normals[v].x()), static_cast<float>(normals[v].y()),
                   static_cast<float>(normals[v].z()));
  }
  if (!colours.empty()) {
    out.mColors[0] = new aiColor4D[n];
    for (unsigned v = 0; v < n; ++v) {
      auto encode = [&](float c) {
        if (!srgb_colours) return std::clamp(c, 0.0f, 1.0f);
        // assimp truncates to 8 bits; half a code up makes the stored code the nearest one.
        const double code = std::round(LinearToSrgb(c) * 255.0);
        return static_cast<float>(std::min(code + 0.5, 255.0) / 255.0);
      };
      out.mColors[0][v] =
          aiColor4D(encode(colours[v].x()), encode(colours[v].y()), encode(colours[v].z()), 1.0f);
    }
  }
  out.mNumFaces = static_cast<unsigned>(mesh.triangle_count());
  out.mFaces = new aiFace[out.mNumFaces];
  for (unsigned f = 0; f < out.mNumFaces; ++f) {
    out.mFaces[f].mNumIndices = 3;
    out.mFaces[f].mIndices = new unsigned[3];
    for (int k = 0; k < 3; ++k) {
      out.mFaces[f].mIndices[k] = static_cast<unsigned>(mesh.triangles[f][k]);
    }
  }
  return scene;
}

}  // namespace

void WriteMesh(const std::filesystem::path& path, const TriangleMesh& mesh,
               std::span<const Eigen::Vector3f> linear_colours) {
  const std::string extension = LowerExtension(path);
  std::string format;
  if (extension == ".ply") {
    // ASCII: assimp 5.2's binary PLY exporter writes colours as floats under a uchar header.
    format = "ply";
  } else if (extension == ".glb") {
    format = "glb2";
  } else {
    throw Error(path, "unsupported mesh output: use .ply or .glb");
  }
  if (!linear_colours.empty() &&
      linear_colours.size() != static_cast<std::size_t>(mesh.vertex_count())) {
    throw Error(path, fmt::format("{} colours for {} vertices", linear_colours.size(),
                                  mesh.vertex_count()));
  }
  ValidateMesh(mesh, path.string());
  // PLY readers take 8-bit colours as display (sRGB) values; glTF's COLOR_0 is linear.
  const auto scene = MakeScene(mesh, linear_colours, format == "ply");
  WriteFileAtomically(path, [&](const std::filesystem::path& temp) {
    Assimp::Exporter exporter;
    if (exporter.Export(scene.get(), format, temp.string()) != aiReturn_SUCCESS) {
      throw Error(path, fmt::format("cannot write the mesh: {}", exporter.GetErrorString()));
    }
  });
}

}  // namespace photomat
