#pragma once

#include <filesystem>
#include <string>

namespace photomat {

// A glTF 2.0 asset (.gltf JSON + .bin buffer + the textures beside it) of one flat rectangular
// tile carrying the exported maps, for Blender, three.js and other glTF tools.
//
// Geometry: a quad in the glTF x-z plane facing +Y (up), centred at the origin, `width` wide
// (x) and `width * aspect` deep, image row 0 at -z (so Blender, which turns glTF's +Y up into +Z
// and -Z into +Y, shows the tile lying on the ground the right way up). Texture coordinates put
// the image's top-left at u = v = 0 (glTF's convention). Each vertex carries NORMAL (0, 1, 0) and
// TANGENT (1, 0, 0, 1): tangent = image right, bitangent = normal x tangent = -z = image up, the
// frame of an OpenGL-convention (+Y up) normal map, which is what glTF requires.
//
// glTF has no displacement slot: the height texture is attached to the material as
// extras.displacement {"texture": <index>, "scale": s, "offset": o}, displacement in scene units
// = o + s * texel (texel in [0, 1]), i.e. the height map in the tile's units (one pixel is
// width / image width); Blender imports it as a custom property of the material.
struct GltfTile {
  std::string name = "photomat tile";
  double width = 1.0;          // scene units (metres in Blender)
  double aspect = 1.0;         // depth / width: the image's height / width
  std::string base_color_uri;  // sRGB texture, relative to the .gltf
  std::string normal_uri;      // OpenGL-convention normal map
  std::string height_uri;      // normalised height texture; empty: none
  double displacement_scale = 0.0;
  double displacement_offset = 0.0;
  // A microfacet fit (pbr): glTF's metallicRoughnessTexture (G = roughness, B = metallic, linear;
  // metallicFactor = roughnessFactor = 1), and KHR_materials_specular where `specular_uri` is set:
  // specularColorTexture (grey, sRGB-encoded as the extension requires) times specularColorFactor
  // = specular_color_factor (grey), specularFactor 1, so that the dielectric F0 = min(0.04
  // specularColor, 1) (the extension's dielectric_f0 with the default IOR 1.5). IMPLEMENTER
  // CHOICE: the colour texture rather than specularTexture's alpha, because Blender's importer
  // (3.4) converts specularColor into its Principled Specular and ignores specularTexture.
  // Empty: the plain metallic 0, roughness 1 material.
  std::string metallic_roughness_uri;
  std::string specular_uri;
  double specular_color_factor = 1.0;
};

// Writes `path` (.gltf) and the buffer beside it (same stem, .bin), each atomically. The textures
// must be written by the caller. Throws Error naming the file.
void WriteGltfTile(const std::filesystem::path& path, const GltfTile& tile);

}  // namespace photomat
