#include "relight/export/export.h"

#include <fmt/format.h>
#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include <cmath>
#include <cstring>
#include <set>

#include "core/atomic_file.h"
#include "core/colour.h"
#include "core/error.h"
#include "core/image_io.h"
#include "core/json_file.h"
#include "relight/export/gltf_tile.h"
#include "relight/formats/interchange.h"
#include "relight/formats/ptm_file.h"
#include "relight/formats/stack_file.h"
#include "represent/evaluation/evaluation.h"
#include "represent/fitting/fit.h"
#include "represent/model/shading.h"
#include "tests/support/synthetic_sets.h"
#include "tests/support/test_support.h"

namespace photomat {
namespace {

namespace fs = std::filesystem;
using ::testing::HasSubstr;

double AngleDegrees(PixelValues<const float> a, PixelValues<const float> b) {
  return AngleBetweenDegrees(Eigen::Vector3d(a[0], a[1], a[2]), Eigen::Vector3d(b[0], b[1], b[2]));
}

// Must show: the 16-bit PNG normal map decodes back to the normals within 0.05 degree.
TEST(NormalMapTest, SixteenBitPngKeepsNormalsWithinAFiftiethOfADegree) {
  testing::TempDir dir;
  SyntheticMaterialOptions options;
  options.pattern = SurfacePattern::kBricks;
  options.width = options.height = 64;
  options.max_slope_degrees = 70;  // normals all over the hemisphere
  const Image normals = MakeSyntheticMaterial(options).normals;
  for (NormalConvention convention : {NormalConvention::kOpenGl, NormalConvention::kDirectX}) {
    const auto path = dir / ("normal_" + std::string(ToString(convention)) + ".png");
    ImageWriteOptions png16;
    png16.sample_type = SampleType::kUint16;
    WriteImage(path, EncodeNormalMap(normals, convention), png16);
    const LoadedImage read = ReadImage(path);
    EXPECT_EQ(read.info.bits_per_sample, 16);
    const Image decoded = DecodeNormalMap(read.image, convention);
    double worst = 0.0;
    for (std::size_t p = 0; p < normals.pixel_count(); ++p) {
      worst = std::max(worst, AngleDegrees(decoded.pixel(p), normals.pixel(p)));
    }
    EXPECT_LT(worst, 0.05) << ToString(convention);
    ::testing::Test::RecordProperty("worst_degrees_" + std::string(ToString(convention)),
                                    std::to_string(worst));
  }
  // OpenGL stores +Y up as green above one half; DirectX the opposite.
  Image up(1, 1, 3);
  up.values()[1] = 0.6f, up.values()[2] = 0.8f;
  EXPECT_GT(EncodeNormalMap(up, NormalConvention::kOpenGl).values()[1], 0.5f);
  EXPECT_LT(EncodeNormalMap(up, NormalConvention::kDirectX).values()[1], 0.5f);
  EXPECT_EQ(EncodeNormalMap(Image(1, 1, 3), NormalConvention::kOpenGl).values()[2], 1.0f);
}

TEST(MaterialMapsTest, EveryKindOfRepresentationGivesNormalsAlbedoAndHeight) {
  const auto synthetic = testing::LambertianSet(SurfacePattern::kBumps, 64);
  const Mask all = synthetic.set.MaskOrAll();
  MaterialMapOptions options;
  options.sample_lights = synthetic.set.lights();
  options.height = HeightIntegrator::kFrankotChellappa;  // the synthetic sample is periodic
  // Gradient carries them; 3I and PTM through EstimateNormals; Eigen-k and HSH by a Lambertian
  // fit to their relit images.
  for (const char* method : {"gradient", "3i", "ptm", "eigen6", "hsh9"}) {
    const Representation r = Fit(synthetic.set, Method::Parse(method));
    const MaterialMaps maps = ExtractMaterialMaps(r, options);
    const double limit = std::string(method) == "ptm" ? 2.0 : 0.5;  // PTM: the luminance maximum
    const double mean = CompareNormals(maps.normals, synthetic.material.normals, all).mean_degrees;
    EXPECT_LT(mean, limit) << method << " from " << maps.normals_source;
    double albedo_error = 0.0;
    for (std::size_t p = 0; p < maps.albedo.pixel_count(); ++p) {
      for (int c = 0; c < 3; ++c) {
        albedo_error = std::max(
            albedo_error,
            double{std::abs(maps.albedo.pixel(p)[c] - synthetic.material.albedo.pixel(p)[c])});
      }
    }
    EXPECT_LT(albedo_error, 0.02) << method;
    ::testing::Test::RecordProperty(std::string(method) + "_normals_mean_deg_albedo_max_error",
                                    fmt::format("{:.3f} {:.4f}", mean, albedo_error));
    EXPECT_EQ(maps.height.channel_names(), std::vector<std::string>{"height"});
  }
  // The gradient stack's height recovers the surface (Frankot-Chellappa on a periodic sample).
  const MaterialMaps gradient =
      ExtractMaterialMaps(Fit(synthetic.set, Method::Parse("gradient")), options);
  double low = INFINITY, high = -INFINITY, mean = 0.0;
  const Image& truth = synthetic.material.height;
  const auto n = static_cast<double>(truth.pixel_count());
  for (std::size_t p = 0; p < truth.pixel_count(); ++p) {
    low = std::min(low, double{truth.pixel(p)[0]});
    high = std::max(high, double{truth.pixel(p)[0]});
    mean += (gradient.height.pixel(p)[0] - truth.pixel(p)[0]) / n;
  }
  double squared = 0.0;
  for (std::size_t p = 0; p < truth.pixel_count(); ++p) {
    squared += std::pow(gradient.height.pixel(p)[0] - truth.pixel(p)[0] - mean, 2) / n;
  }
  EXPECT_LT(std::sqrt(squared) / (high - low), 0.01);
}

// The structural rules of glTF 2.0 that matter for a viewer to load the file (specification
// sections 3.5-3.9, 5.x): a validator in miniature.
void ExpectValidGltf(const fs::path& path) {
  const nlohmann::json gltf = ReadJsonFile(path);
  const fs::path folder = path.parent_path();
  ASSERT_EQ(gltf.at("asset").at("version"), "2.0");
  const auto index_in = [&](const nlohmann::json& index, const char* array) {
    EXPECT_TRUE(index.is_number_unsigned()) << array;
    EXPECT_LT(index.get<std::size_t>(), gltf.at(array).size()) << array;
    return index.get<std::size_t>();
  };
  // Buffers exist with their declared length.
  std::vector<std::string> buffers;
  for (const auto& buffer : gltf.at("buffers")) {
    const std::string bytes = ReadTextFile(folder / buffer.at("uri").get<std::string>());
    EXPECT_EQ(bytes.size(), buffer.at("byteLength").get<std::size_t>());
    buffers.push_back(bytes);
  }
  for (const auto& view : gltf.at("bufferViews")) {
    const std::size_t buffer = index_in(view.at("buffer"), "buffers");
    EXPECT_LE(view.value("byteOffset", 0u) + view.at("byteLength").get<std::size_t>(),
              buffers[buffer].size());
    if (view.contains("target")) {
      EXPECT_THAT(view["target"].get<int>(), ::testing::AnyOf(34962, 34963));
    }
  }
  const std::map<std::string, int> components = {
      {"SCALAR", 1}, {"VEC2", 2}, {"VEC3", 3}, {"VEC4", 4}, {"MAT4", 16}};
  const std::map<int, int> component_bytes = {{5120, 1}, {5121, 1}, {5122, 2},
                                              {5123, 2}, {5125, 4}, {5126, 4}};
  // Each accessor's data, as doubles.
  std::vector<std::vector<double>> data;
  for (const auto& accessor : gltf.at("accessors")) {
    const auto& view =
        gltf.at("bufferViews").at(index_in(accessor.at("bufferView"), "bufferViews"));
    const int size = component_bytes.at(accessor.at("componentType").get<int>());
    const int count = components.at(accessor.at("type").get<std::string>());
    const std::size_t offset = view.value("byteOffset", 0u) + accessor.value("byteOffset", 0u);
    const std::size_t n = accessor.at("count").get<std::size_t>();
    EXPECT_GT(n, 0u);
    EXPECT_EQ(offset % size, 0u) << "misaligned accessor";
    EXPECT_LE(accessor.value("byteOffset", 0u) + n * count * size,
              view.at("byteLength").get<std::size_t>());
    const std::string& bytes = buffers[view.at("buffer").get<std::size_t>()];
    std::vector<double> values;
    for (std::size_t i = 0; i < n * count; ++i) {
      if (accessor["componentType"] == 5126) {
        float f;
        std::memcpy(&f, bytes.data() + offset + 4 * i, 4);
        values.push_back(f);
      } else {
        std::uint16_t u;
        std::memcpy(&u, bytes.data() + offset + 2 * i, 2);
        values.push_back(u);
      }
    }
    if (accessor.contains("min")) {
      for (std::size_t i = 0; i < values.size(); ++i) {
        EXPECT_GE(values[i], accessor["min"][i % count].get<double>());
        EXPECT_LE(values[i], accessor["max"][i % count].get<double>());
      }
    }
    data.push_back(values);
  }
  for (const auto& node : gltf.at("scenes").at(index_in(gltf.at("scene"), "scenes")).at("nodes")) {
    index_in(gltf.at("nodes").at(index_in(node, "nodes")).at("mesh"), "meshes");
  }
  for (const auto& mesh : gltf.at("meshes")) {
    for (const auto& primitive : mesh.at("primitives")) {
      const auto& attributes = primitive.at("attributes");
      const std::map<std::string, std::string> types = {
          {"POSITION", "VEC3"}, {"NORMAL", "VEC3"}, {"TANGENT", "VEC4"}, {"TEXCOORD_0", "VEC2"}};
      std::size_t vertices = 0;
      for (const auto& [name, type] : types) {
        ASSERT_TRUE(attributes.contains(name)) << name;
        const auto& accessor = gltf.at("accessors").at(index_in(attributes[name], "accessors"));
        EXPECT_EQ(accessor.at("type"), type) << name;
        EXPECT_EQ(accessor.at("componentType"), 5126) << name;
        vertices = accessor.at("count");
      }
      const auto& position = gltf["accessors"][attributes["POSITION"].get<std::size_t>()];
      EXPECT_TRUE(position.contains("min") && position.contains("max"));  // required
      const auto& normal = data[attributes["NORMAL"].get<std::size_t>()];
      const auto& tangent = data[attributes["TANGENT"].get<std::size_t>()];
      for (std::size_t v = 0; v < vertices; ++v) {
        EXPECT_NEAR(std::hypot(normal[3 * v], normal[3 * v + 1], normal[3 * v + 2]), 1.0, 1e-6);
        EXPECT_EQ(std::abs(tangent[4 * v + 3]), 1.0);
      }
      const auto& indices = gltf["accessors"][index_in(primitive.at("indices"), "accessors")];
      EXPECT_EQ(indices.at("type"), "SCALAR");
      for (double i : data[primitive["indices"].get<std::size_t>()]) EXPECT_LT(i, vertices);
      EXPECT_EQ(primitive.value("mode", 4), 4);
      const auto& material = gltf["materials"][index_in(primitive.at("material"), "materials")];
      for (const auto* info : {&material.at("pbrMetallicRoughness").at("baseColorTexture"),
                               &material.at("normalTexture")}) {
        const auto& texture = gltf.at("textures").at(index_in(info->at("index"), "textures"));
        index_in(texture.at("sampler"), "samplers");
        const auto& image = gltf.at("images").at(index_in(texture.at("source"), "images"));
        EXPECT_NO_THROW(ReadImage(folder / image.at("uri").get<std::string>()));
      }
    }
  }
}

TEST(ExportTest, WritesEveryMapAValidGltfTileAndAStackWithHeight) {
  testing::TempDir dir;
  const auto synthetic = testing::LambertianSet(SurfacePattern::kBricks, 48);
  const Representation gradient = Fit(synthetic.set, Method::Parse("gradient"));
  const LoadedStack stack{gradient, {synthetic.set.lights(), "linear", "synthetic"}};
  const nlohmann::json description = ExportMaps(stack, dir.path());
  for (const char* file : {"normal.png", "albedo.png", "height.exr", "height.png", "tile.gltf",
                           "tile.bin", "stack.exr", "export.json"}) {
    EXPECT_TRUE(fs::exists(dir / file)) << file;
  }
  EXPECT_EQ(ReadJsonFile(dir / "export.json"), description);
  ExpectValidGltf(dir / "tile.gltf");
  // The tile's frame: faces +Y, tangent along +x (image right), bitangent N x T = -z (image up,
  // where row 0 and v = 0 are).
  const nlohmann::json gltf = ReadJsonFile(dir / "tile.gltf");
  EXPECT_EQ(gltf["materials"][0]["extras"]["displacement"]["texture"], 2);
  EXPECT_EQ(gltf["images"][2]["uri"], "height.png");
  // The normal map decodes to the fitted normals; the height PNG spans its range.
  const Image normals =
      DecodeNormalMap(ReadImage(dir / "normal.png").image, NormalConvention::kOpenGl);
  EXPECT_LT(
      CompareNormals(normals, synthetic.material.normals, synthetic.set.MaskOrAll()).mean_degrees,
      0.1);
  const LoadedImage height_png = ReadImage(dir / "height.png");
  EXPECT_EQ(height_png.info.bits_per_sample, 16);
  EXPECT_EQ(height_png.info.attributes.count("photomat:height_min"), 1u);
  // export.json gives the image's size and describes the height map, with its range.
  EXPECT_EQ(description["width"], 48);
  EXPECT_EQ(description["height"], 48);
  const nlohmann::json& height_map = description["height_map"];
  EXPECT_EQ(height_map["file"], "height.exr");
  EXPECT_EQ(height_map["integrator"], "poisson");
  const double min = std::stod(height_png.info.attributes.at("photomat:height_min"));
  EXPECT_NEAR(height_map["min"].get<double>(), min, 1e-8 * std::abs(min));  // 9 digits there
  EXPECT_LT(height_map["min"].get<double>(), height_map["max"].get<double>());
  // stack.exr relights as the stack did and carries the height layer.
  const LoadedStack reloaded = LoadRepresentation(dir / "stack.exr");
  EXPECT_EQ(reloaded.extra_layers.channel_names(), std::vector<std::string>{"height"});
  const Image height = ReadImage(dir / "height.exr").image;
  EXPECT_EQ(reloaded.extra_layers.values()[100], height.values()[100]);
  const auto light = LightDirection::FromSlantTilt(50, 70);
  const Image a = gradient.Relight(light), b = reloaded.representation.Relight(light);
  EXPECT_TRUE(std::equal(a.values().begin(), a.values().end(), b.values().begin()));
}

TEST(ExportTest, DirectXNormalsKeepAnOpenGlTextureForGltf) {
  testing::TempDir dir;
  const auto synthetic = testing::LambertianSet(SurfacePattern::kBumps, 16);
  const LoadedStack stack{Fit(synthetic.set, Method::Parse("ptm")),
                          {synthetic.set.lights(), "linear", "synthetic"}};
  ExportOptions options;
  options.normal_convention = NormalConvention::kDirectX;
  options.height = HeightIntegrator::kFrankotChellappa;
  const nlohmann::json description = ExportMaps(stack, dir.path(), options);
  EXPECT_EQ(description["normals"]["convention"], "directx");
  EXPECT_EQ(ReadJsonFile(dir / "tile.gltf")["images"][1]["uri"], "normal_gltf.png");
  const Image directx = ReadImage(dir / "normal.png").image;
  const Image opengl = ReadImage(dir / "normal_gltf.png").image;
  for (std::size_t p = 0; p < directx.pixel_count(); p += 7) {
    EXPECT_NEAR(directx.pixel(p)[1], 1.0f - opengl.pixel(p)[1], 2e-5);
  }
  // The derived normals and albedo travel in stack.exr beside the PTM maps.
  const LoadedStack reloaded = LoadRepresentation(dir / "stack.exr");
  EXPECT_EQ(reloaded.extra_layers.channels(), 7);
  ExpectValidGltf(dir / "tile.gltf");
}

TEST(ExportTest, PtmFilesExportThroughTheirEncoding) {
  testing::TempDir dir;
  const auto synthetic = testing::LambertianSet(SurfacePattern::kBumps, 24);
  WritePtmFile(dir / "s.ptm",
               PtmFromRepresentation(FitEncoded(synthetic.set, Method::Parse("ptm"))));
  const LoadedStack stack = LoadStackFile(dir / "s.ptm");
  EXPECT_EQ(stack.provenance.colour_space, "srgb");
  fs::create_directories(dir / "out");
  ExportMaps(stack, dir / "out");
  // The albedo is decoded from the PTM's sRGB values back to linear light.
  const Image albedo = ReadImage(dir / "out" / "albedo.png").image;
  double error = 0.0;
  for (std::size_t p = 0; p < albedo.pixel_count(); ++p) {
    error += std::abs(albedo.pixel(p)[1] - synthetic.material.albedo.pixel(p)[1]) /
             static_cast<double>(albedo.pixel_count());
  }
  EXPECT_LT(error, 0.05);
  EXPECT_THAT(
      [&] { LoadStackFile(dir / "s.ptm", "hsh9"); },
      ::testing::ThrowsMessage<Error>(HasSubstr("s.ptm: holds a ptm representation, not hsh9")));
}

// A pbr stack of known maps: the synthetic GGX material's truth.
Representation TruthPbr(int size) {
  SyntheticMaterialOptions options;
  options.pattern = SurfacePattern::kBumps;
  options.width = options.height = size;
  options.f0_min = 0.03;
  options.f0_max = 0.1;
  const SyntheticMaterial m = MakeSyntheticMaterial(options);
  Image maps(size, size, MicrofacetShading().MapNames());
  for (std::size_t p = 0; p < maps.pixel_count(); ++p) {
    for (int c = 0; c < 3; ++c) maps.pixel(p)[MicrofacetShading::kBase + c] = m.albedo.pixel(p)[c];
    maps.pixel(p)[MicrofacetShading::kRoughness] = m.roughness.pixel(p)[0];
    maps.pixel(p)[MicrofacetShading::kF0] = m.f0.pixel(p)[0];
    for (int c = 0; c < 3; ++c) {
      maps.pixel(p)[MicrofacetShading::kNormal + c] = m.normals.pixel(p)[c];
    }
  }
  return Representation("pbr", std::move(maps), std::make_shared<MicrofacetShading>());
}

TEST(ExportTest, PbrTileCarriesRoughnessAndSpecularThatDecodeToTheMaps) {
  testing::TempDir dir;
  const Representation pbr = TruthPbr(32);
  const nlohmann::json description = ExportMaps(LoadedStack{pbr, {}}, dir.path());
  ExpectValidGltf(dir / "tile.gltf");
  const nlohmann::json gltf = ReadJsonFile(dir / "tile.gltf");
  const auto& material = gltf["materials"][0];
  EXPECT_EQ(material["pbrMetallicRoughness"]["metallicFactor"], 1.0);
  EXPECT_EQ(gltf["extensionsUsed"], nlohmann::json::array({"KHR_materials_specular"}));
  const auto& specular = material["extensions"]["KHR_materials_specular"];
  const double factor = specular["specularColorFactor"][0];
  const auto uri = [&](const nlohmann::json& info) {
    const auto& texture = gltf["textures"][info["index"].get<std::size_t>()];
    return gltf["images"][texture["source"].get<std::size_t>()]["uri"].get<std::string>();
  };
  const std::string mr = uri(material["pbrMetallicRoughness"]["metallicRoughnessTexture"]);
  const std::string sc = uri(specular["specularColorTexture"]);
  EXPECT_EQ(mr, "metallic_roughness.png");
  EXPECT_EQ(sc, "specular.png");
  // Decode as a glTF viewer does: roughness = G, metallic = B (linear); the dielectric F0 =
  // min(0.04 specularColorFactor specularColorTexture, 1) specularFactor, the texture sRGB.
  ImageReadOptions linear;
  linear.colour_space = ColourSpace::kLinear;
  const Image mr_image = ReadImage(dir / mr, linear).image;
  const Image sc_image = ReadImage(dir / sc, linear).image;
  double worst_roughness = 0.0, worst_f0 = 0.0;
  for (std::size_t p = 0; p < mr_image.pixel_count(); ++p) {
    const auto maps = pbr.maps().pixel(p);
    EXPECT_EQ(mr_image.pixel(p)[2], 0.0f);
    worst_roughness = std::max<double>(
        worst_roughness, std::abs(mr_image.pixel(p)[1] - maps[MicrofacetShading::kRoughness]));
    const double f0 = std::min(0.04 * factor * SrgbToLinear(sc_image.pixel(p)[0]), 1.0) *
                      specular["specularFactor"].get<double>();
    worst_f0 = std::max(worst_f0, std::abs(f0 / maps[MicrofacetShading::kF0] - 1.0));
  }
  // 16-bit quantisation: roughness within 1/65535; F0 relative within the sRGB code step at
  // the smallest F0 (measured below 1e-4).
  EXPECT_LT(worst_roughness, 1.0 / 65535);
  EXPECT_LT(worst_f0, 1e-3);
  // The Blender / Substance maps: specular level F0 / 0.08, float roughness and F0.
  const Image level = ReadImage(dir / "specular_level.png").image;
  const Image f0 = ReadImage(dir / "f0.exr").image;
  EXPECT_NEAR(level.pixel(5)[0], f0.pixel(5)[0] / 0.08, 1.0 / 65535);
  EXPECT_EQ(f0.pixel(5)[0], pbr.maps().pixel(5)[MicrofacetShading::kF0]);
  EXPECT_EQ(description["pbr"]["specular"]["specular_color_factor"], factor);
  // The base colour is the albedo map of the tile.
  const Image albedo = ReadImage(dir / "albedo.png").image;
  EXPECT_NEAR(albedo.pixel(7)[1], pbr.maps().pixel(7)[MicrofacetShading::kBase + 1], 0.01);
}

TEST(ExportTest, PbrHasNoPtmOrRtiForm) {
  const Representation pbr = TruthPbr(8);
  EXPECT_THAT([&] { PtmFromRepresentation(pbr); },
              ::testing::ThrowsMessage<Error>(HasSubstr("nonlinear microfacet shading")));
}

}  // namespace
}  // namespace photomat
