#include "relight/export/gltf_tile.h"

#include <fmt/format.h>

#include <array>
#include <cstdint>
#include <cstring>
#include <nlohmann/json.hpp>

#include "core/atomic_file.h"
#include "core/error.h"

namespace photomat {
namespace {

namespace fs = std::filesystem;

// glTF enumerations (glTF 2.0 specification, 5.1.2 and 3.6.2).
constexpr int kFloat = 5126;
constexpr int kUnsignedShort = 5123;
constexpr int kArrayBuffer = 34962;
constexpr int kElementArrayBuffer = 34963;
constexpr int kTriangles = 4;
constexpr int kLinear = 9729;
constexpr int kLinearMipmapLinear = 9987;
constexpr int kClampToEdge = 33071;

template <typename T, std::size_t N>
void Append(std::string& buffer, const std::array<T, N>& values) {
  buffer.append(reinterpret_cast<const char*>(values.data()), sizeof(T) * N);
}

}  // namespace

namespace {

// The tile's square mesh: its binary buffer and the buffer views and accessors that describe it.
struct TileMesh {
  std::string buffer;
  nlohmann::json buffer_views = nlohmann::json::array();
  nlohmann::json accessors = nlohmann::json::array();
  nlohmann::json attributes;  // the primitive's, accessor indices by name
  std::size_t indices = 0;    // the accessor of the triangle indices
};

TileMesh MakeTileMesh(const GltfTile& tile) {
  const float hx = static_cast<float>(tile.width / 2),
              hz = static_cast<float>(tile.width * tile.aspect / 2);
  // Vertices: top-left, top-right, bottom-right, bottom-left of the image.
  const std::array<float, 12> positions = {-hx, 0, -hz, hx, 0, -hz, hx, 0, hz, -hx, 0, hz};
  const std::array<float, 12> normals = {0, 1, 0, 0, 1, 0, 0, 1, 0, 0, 1, 0};
  const std::array<float, 16> tangents = {1, 0, 0, 1, 1, 0, 0, 1, 1, 0, 0, 1, 1, 0, 0, 1};
  const std::array<float, 8> uvs = {0, 0, 1, 0, 1, 1, 0, 1};
  // Counter-clockwise seen from +Y: front faces point up.
  const std::array<std::uint16_t, 6> indices = {0, 3, 2, 0, 2, 1};
  TileMesh mesh;
  Append(mesh.buffer, positions);
  Append(mesh.buffer, normals);
  Append(mesh.buffer, tangents);
  Append(mesh.buffer, uvs);
  const std::size_t index_offset = mesh.buffer.size();
  Append(mesh.buffer, indices);

  const auto add_attribute = [&](std::size_t offset, std::size_t bytes, int count,
                                 const char* type) {
    mesh.buffer_views.push_back(
        {{"buffer", 0}, {"byteOffset", offset}, {"byteLength", bytes}, {"target", kArrayBuffer}});
    mesh.accessors.push_back({{"bufferView", mesh.buffer_views.size() - 1},
                              {"componentType", kFloat},
                              {"count", count},
                              {"type", type}});
    return mesh.accessors.size() - 1;
  };
  const auto position = add_attribute(0, sizeof positions, 4, "VEC3");
  mesh.accessors[position]["min"] = {-hx, 0.0f, -hz};
  mesh.accessors[position]["max"] = {hx, 0.0f, hz};
  const auto normal = add_attribute(sizeof positions, sizeof normals, 4, "VEC3");
  const auto tangent = add_attribute(sizeof positions + sizeof normals, sizeof tangents, 4, "VEC4");
  const auto uv =
      add_attribute(sizeof positions + sizeof normals + sizeof tangents, sizeof uvs, 4, "VEC2");
  mesh.attributes = {
      {"POSITION", position}, {"NORMAL", normal}, {"TANGENT", tangent}, {"TEXCOORD_0", uv}};
  mesh.buffer_views.push_back({{"buffer", 0},
                               {"byteOffset", index_offset},
                               {"byteLength", sizeof indices},
                               {"target", kElementArrayBuffer}});
  mesh.accessors.push_back({{"bufferView", mesh.buffer_views.size() - 1},
                            {"componentType", kUnsignedShort},
                            {"count", indices.size()},
                            {"type", "SCALAR"},
                            {"min", {0}},
                            {"max", {3}}});
  mesh.indices = mesh.accessors.size() - 1;
  return mesh;
}

// The tile's material and the images and textures it uses: base colour and normal, and, when
// the tile has them, the height (as a displacement in "extras"), metallic-roughness and the
// specular colour (KHR_materials_specular).
struct TileMaterial {
  nlohmann::json material;
  nlohmann::json images;
  nlohmann::json textures;
  nlohmann::json extensions_used = nlohmann::json::array();
};

TileMaterial MakeTileMaterial(const GltfTile& tile) {
  using nlohmann::json;
  TileMaterial out;
  out.images = json::array({{{"uri", tile.base_color_uri}}, {{"uri", tile.normal_uri}}});
  out.textures = json::array({{{"sampler", 0}, {"source", 0}}, {{"sampler", 0}, {"source", 1}}});
  out.material = {
      {"name", tile.name},
      {"pbrMetallicRoughness",
       {{"baseColorTexture", {{"index", 0}}}, {"metallicFactor", 0.0}, {"roughnessFactor", 1.0}}},
      {"normalTexture", {{"index", 1}}},
  };
  // The next texture's index, its image added.
  const auto add_texture = [&](const std::string& uri) {
    out.images.push_back({{"uri", uri}});
    out.textures.push_back({{"sampler", 0}, {"source", out.images.size() - 1}});
    return out.textures.size() - 1;
  };
  if (!tile.height_uri.empty()) {
    out.material["extras"] = {{"displacement",
                               {{"texture", add_texture(tile.height_uri)},
                                {"scale", tile.displacement_scale},
                                {"offset", tile.displacement_offset}}}};
  }
  if (!tile.metallic_roughness_uri.empty()) {
    json& pbr = out.material["pbrMetallicRoughness"];
    pbr["metallicRoughnessTexture"] = {{"index", add_texture(tile.metallic_roughness_uri)}};
    pbr["metallicFactor"] = 1.0;
  }
  if (!tile.specular_uri.empty()) {
    const double f = tile.specular_color_factor;
    out.material["extensions"]["KHR_materials_specular"] = {
        {"specularFactor", 1.0},
        {"specularColorTexture", {{"index", add_texture(tile.specular_uri)}}},
        {"specularColorFactor", {f, f, f}}};
    out.extensions_used.push_back("KHR_materials_specular");
  }
  return out;
}

}  // namespace

void WriteGltfTile(const fs::path& path, const GltfTile& tile) {
  if (!(tile.width > 0.0) || !(tile.aspect > 0.0) || tile.base_color_uri.empty() ||
      tile.normal_uri.empty()) {
    throw Error(path, "a glTF tile needs a positive size, a base colour and a normal texture");
  }
  const TileMesh mesh = MakeTileMesh(tile);
  const TileMaterial material = MakeTileMaterial(tile);
  const std::string bin_name = path.stem().string() + ".bin";
  nlohmann::json document = {
      {"asset", {{"version", "2.0"}, {"generator", "photomat"}}},
      {"scene", 0},
      {"scenes", {{{"name", tile.name}, {"nodes", {0}}}}},
      {"nodes", {{{"name", tile.name}, {"mesh", 0}}}},
      {"meshes",
       {{{"name", tile.name},
         {"primitives",
          {{{"attributes", mesh.attributes},
            {"indices", mesh.indices},
            {"material", 0},
            {"mode", kTriangles}}}}}}},
      {"materials", {material.material}},
      {"textures", material.textures},
      {"images", material.images},
      {"samplers",
       {{{"magFilter", kLinear},
         {"minFilter", kLinearMipmapLinear},
         {"wrapS", kClampToEdge},
         {"wrapT", kClampToEdge}}}},
      {"buffers", {{{"uri", bin_name}, {"byteLength", mesh.buffer.size()}}}},
      {"bufferViews", mesh.buffer_views},
      {"accessors", mesh.accessors},
  };
  if (!material.extensions_used.empty()) document["extensionsUsed"] = material.extensions_used;
  WriteTextFileAtomically(path.parent_path() / bin_name, mesh.buffer);
  WriteTextFileAtomically(path, document.dump(2) + "\n");
}

}  // namespace photomat
