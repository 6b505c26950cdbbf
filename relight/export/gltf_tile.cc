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

void WriteGltfTile(const fs::path& path, const GltfTile& tile) {
  if (!(tile.width > 0.0) || !(tile.aspect > 0.0) || tile.base_color_uri.empty() ||
      tile.normal_uri.empty()) {
    throw Error(path, "a glTF tile needs a positive size, a base colour and a normal texture");
  }
  const float hx = static_cast<float>(tile.width / 2),
              hz = static_cast<float>(tile.width * tile.aspect / 2);
  // Vertices: top-left, top-right, bottom-right, bottom-left of the image.
  const std::array<float, 12> positions = {-hx, 0, -hz, hx, 0, -hz, hx, 0, hz, -hx, 0, hz};
  const std::array<float, 12> normals = {0, 1, 0, 0, 1, 0, 0, 1, 0, 0, 1, 0};
  const std::array<float, 16> tangents = {1, 0, 0, 1, 1, 0, 0, 1, 1, 0, 0, 1, 1, 0, 0, 1};
  const std::array<float, 8> uvs = {0, 0, 1, 0, 1, 1, 0, 1};
  // Counter-clockwise seen from +Y: front faces point up.
  const std::array<std::uint16_t, 6> indices = {0, 3, 2, 0, 2, 1};
  std::string buffer;
  Append(buffer, positions);
  Append(buffer, normals);
  Append(buffer, tangents);
  Append(buffer, uvs);
  const std::size_t index_offset = buffer.size();
  Append(buffer, indices);
  const std::string bin_name = path.stem().string() + ".bin";

  using nlohmann::json;
  json buffer_views = json::array();
  json accessors = json::array();
  const auto add_attribute = [&](std::size_t offset, std::size_t bytes, int count,
                                 const char* type) {
    buffer_views.push_back(
        {{"buffer", 0}, {"byteOffset", offset}, {"byteLength", bytes}, {"target", kArrayBuffer}});
    accessors.push_back({{"bufferView", buffer_views.size() - 1},
                         {"componentType", kFloat},
                         {"count", count},
                         {"type", type}});
    return accessors.size() - 1;
  };
  const auto position = add_attribute(0, sizeof positions, 4, "VEC3");
  accessors[position]["min"] = {-hx, 0.0f, -hz};
  accessors[position]["max"] = {hx, 0.0f, hz};
  const auto normal = add_attribute(sizeof positions, sizeof normals, 4, "VEC3");
  const auto tangent = add_attribute(sizeof positions + sizeof normals, sizeof tangents, 4, "VEC4");
  const auto uv =
      add_attribute(sizeof positions + sizeof normals + sizeof tangents, sizeof uvs, 4, "VEC2");
  buffer_views.push_back({{"buffer", 0},
                          {"byteOffset", index_offset},
                          {"byteLength", sizeof indices},
                          {"target", kElementArrayBuffer}});
  accessors.push_back({{"bufferView", buffer_views.size() - 1},
                       {"componentType", kUnsignedShort},
                       {"count", indices.size()},
                       {"type", "SCALAR"},
                       {"min", {0}},
                       {"max", {3}}});

  json images = json::array({{{"uri", tile.base_color_uri}}, {{"uri", tile.normal_uri}}});
  json textures = json::array({{{"sampler", 0}, {"source", 0}}, {{"sampler", 0}, {"source", 1}}});
  json material = {
      {"name", tile.name},
      {"pbrMetallicRoughness",
       {{"baseColorTexture", {{"index", 0}}}, {"metallicFactor", 0.0}, {"roughnessFactor", 1.0}}},
      {"normalTexture", {{"index", 1}}},
  };
  // The next texture's index, its image added.
  const auto add_texture = [&](const std::string& uri) {
    images.push_back({{"uri", uri}});
    textures.push_back({{"sampler", 0}, {"source", images.size() - 1}});
    return textures.size() - 1;
  };
  if (!tile.height_uri.empty()) {
    material["extras"] = {{"displacement",
                           {{"texture", add_texture(tile.height_uri)},
                            {"scale", tile.displacement_scale},
                            {"offset", tile.displacement_offset}}}};
  }
  json extensions_used = json::array();
  if (!tile.metallic_roughness_uri.empty()) {
    json& pbr = material["pbrMetallicRoughness"];
    pbr["metallicRoughnessTexture"] = {{"index", add_texture(tile.metallic_roughness_uri)}};
    pbr["metallicFactor"] = 1.0;
  }
  if (!tile.specular_uri.empty()) {
    const double f = tile.specular_color_factor;
    material["extensions"]["KHR_materials_specular"] = {
        {"specularFactor", 1.0},
        {"specularColorTexture", {{"index", add_texture(tile.specular_uri)}}},
        {"specularColorFactor", {f, f, f}}};
    extensions_used.push_back("KHR_materials_specular");
  }
  json document = {
      {"asset", {{"version", "2.0"}, {"generator", "photomat"}}},
      {"scene", 0},
      {"scenes", {{{"name", tile.name}, {"nodes", {0}}}}},
      {"nodes", {{{"name", tile.name}, {"mesh", 0}}}},
      {"meshes",
       {{{"name", tile.name},
         {"primitives",
          {{{"attributes",
             {{"POSITION", position},
              {"NORMAL", normal},
              {"TANGENT", tangent},
              {"TEXCOORD_0", uv}}},
            {"indices", accessors.size() - 1},
            {"material", 0},
            {"mode", kTriangles}}}}}}},
      {"materials", {material}},
      {"textures", textures},
      {"images", images},
      {"samplers",
       {{{"magFilter", kLinear},
         {"minFilter", kLinearMipmapLinear},
         {"wrapS", kClampToEdge},
         {"wrapT", kClampToEdge}}}},
      {"buffers", {{{"uri", bin_name}, {"byteLength", buffer.size()}}}},
      {"bufferViews", buffer_views},
      {"accessors", accessors},
  };
  if (!extensions_used.empty()) document["extensionsUsed"] = extensions_used;
  WriteTextFileAtomically(path.parent_path() / bin_name, buffer);
  WriteTextFileAtomically(path, document.dump(2) + "\n");
}

}  // namespace photomat
