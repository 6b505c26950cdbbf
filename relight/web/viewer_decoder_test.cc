#include "relight/web/viewer_decoder.h"

#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <cstring>
#include <memory>

#include "core/error.h"
#include "core/json_file.h"
#include "core/random.h"
#include "relight/web/viewer_export.h"
#include "relight/web/viewer_pyramid.h"
#include "tests/support/test_support.h"

namespace photomat {
namespace {

namespace fs = std::filesystem;
using testing::TempDir;

// NeuralRTI's decoder shape (k + 2 -> 50 -> 50 -> 50 -> 3) with seeded weights of the size a
// trained one has.
NeuralDecoder RandomDecoder(int k, int width, int outputs, std::uint64_t seed) {
  Random random(seed);
  std::vector<DenseLayer> layers;
  int inputs = k + 2;
  for (int out : {width, width, width, outputs}) {
    DenseLayer layer{Eigen::MatrixXf(out, inputs), Eigen::VectorXf(out)};
    const double scale = 1.0 / std::sqrt(static_cast<double>(inputs));
    for (Eigen::Index i = 0; i < layer.weight.size(); ++i) {
      layer.weight.data()[i] = static_cast<float>(random.Uniform(-scale, scale));
    }
    for (Eigen::Index i = 0; i < layer.bias.size(); ++i) {
      layer.bias[i] = static_cast<float>(random.Uniform(-0.1, 0.1));
    }
    layers.push_back(std::move(layer));
    inputs = out;
  }
  return NeuralDecoder(std::move(layers), 0.75f);
}

Representation NeuralStack(const NeuralDecoder& decoder, int width, int height,
                           std::uint64_t seed) {
  Random random(seed);
  Image maps(width, height, NeuralMapNames(decoder.coefficients()));
  for (std::size_t p = 0; p < maps.pixel_count(); ++p) {
    for (int j = 0; j < maps.channels(); ++j) {
      maps.pixel(p)[j] = static_cast<float>(random.Uniform(-1, 1));
    }
  }
  return Representation("neural", std::move(maps), std::make_shared<NeuralShading>(decoder));
}

// The fragment shader's evaluation (viewer/src/viewer.js, neuralShader), from the texture alone:
// per neuron, vec4 dot products over the row's texels, then the bias texel; ELU between layers.
std::vector<float> EvaluateFromTexture(const std::vector<float>& texels,
                                       const nlohmann::json& shading,
                                       const std::vector<float>& codes, float lx, float ly) {
  const int width = shading["texture"]["width"].get<int>();
  std::vector<float> in = codes;
  in.push_back(lx);
  in.push_back(ly);
  const auto& layers = shading["layers"];
  for (std::size_t l = 0; l < layers.size(); ++l) {
    const int inputs = layers[l]["inputs"].get<int>();
    const int outputs = layers[l]["outputs"].get<int>();
    const int first_row = layers[l]["first_row"].get<int>();
    EXPECT_EQ(static_cast<int>(in.size()), inputs);
    const int chunks = (inputs + 3) / 4;
    in.resize(static_cast<std::size_t>(chunks) * 4, 0.0f);
    std::vector<float> out(outputs);
    for (int o = 0; o < outputs; ++o) {
      const std::size_t row = static_cast<std::size_t>(first_row + o) * width * 4;
      float sum = texels[row + static_cast<std::size_t>(chunks) * 4];
      for (int i = 0; i < 4 * chunks; ++i) sum += texels[row + i] * in[i];
      out[o] = l + 1 < layers.size() ? (sum > 0.0f ? sum : std::expm1(sum)) : sum;
    }
    in = std::move(out);
  }
  for (float& v : in) v *= shading["output_scale"].get<float>();
  return in;
}

TEST(ViewerDecoderTest, TextureHoldsEveryWeightAndBiasBitForBitWithZeroPadding) {
  const NeuralDecoder decoder = RandomDecoder(9, 50, 3, 11);
  const ViewerDecoderLayout layout(decoder);
  // 11 inputs -> 3 texels of weights + 1 of bias; 50 inputs -> 13 + 1.
  EXPECT_EQ(layout.width, 14);
  EXPECT_EQ(layout.height, 153);
  EXPECT_EQ(layout.first_rows, (std::vector<int>{0, 50, 100, 150}));
  const std::string bytes = ViewerDecoderTexture(decoder);
  ASSERT_EQ(bytes.size(), std::size_t{14} * 153 * 4 * 4);
  std::vector<float> texels(bytes.size() / 4);
  std::memcpy(texels.data(), bytes.data(), bytes.size());  // the test host is little-endian
  std::size_t nonzero_written = 0;
  for (std::size_t l = 0; l < decoder.layers().size(); ++l) {
    const DenseLayer& layer = decoder.layers()[l];
    const int chunks = static_cast<int>((layer.weight.cols() + 3) / 4);
    for (Eigen::Index o = 0; o < layer.weight.rows(); ++o) {
      const float* row = &texels[static_cast<std::size_t>(layout.first_rows[l] + o) * 14 * 4];
      for (int i = 0; i < 14 * 4; ++i) {
        float expected = 0.0f;
        if (i < layer.weight.cols()) expected = layer.weight(o, i);
        if (i == 4 * chunks) expected = layer.bias[o];
        ASSERT_EQ(row[i], expected) << "layer " << l << " neuron " << o << " value " << i;
        nonzero_written += expected != 0.0f;
      }
    }
  }
  EXPECT_EQ(nonzero_written, 11u * 50 + 2 * 50u * 50 + 50u * 3 + 3 * 50u + 3);
}

TEST(ViewerDecoderTest, ExportedViewerCarriesTheDecoderAndItsTextureEvaluatesAsRelight) {
  TempDir dir;
  const NeuralDecoder decoder = RandomDecoder(9, 50, 3, 12);
  const Representation stack = NeuralStack(decoder, 7, 5, 13);
  ExportViewer(dir / "v", {stack});
  const nlohmann::json manifest = ReadJsonFile(dir / "v" / "viewer.json");
  ASSERT_EQ(manifest["methods"].size(), 1u);
  const nlohmann::json& method = manifest["methods"][0];
  EXPECT_EQ(method["basis"], nlohmann::json({{"kind", "direction"}}));
  EXPECT_EQ(method["layout"]["shading_maps"], 9);
  EXPECT_EQ(method["data"]["layers"], 3);  // 9 maps in 3 RGBA layers
  const nlohmann::json& shading = method["shading"];
  EXPECT_EQ(shading["kind"], "neural");
  EXPECT_EQ(shading["activation"], "elu");
  EXPECT_EQ(shading["output_scale"].get<float>(), 0.75f);
  EXPECT_EQ(shading["coefficients"], 9);
  EXPECT_EQ(shading["outputs"], 3);
  EXPECT_EQ(shading["file"], "maps/neural.decoder.f32");
  const std::vector<float> texels = ReadFloat32File(dir / "v" / "maps" / "neural.decoder.f32");
  EXPECT_EQ(texels.size(), std::size_t{14} * 153 * 4);

  // The check lights verify basis.js's "direction" against c = l to double rounding.
  const nlohmann::json& check = method["check"];
  for (std::size_t i = 0; i < check["lights"].size(); ++i) {
    EXPECT_EQ(check["lights"][i], check["coefficients"][i]);
  }

  // What the shader computes from the files equals Relight on every pixel under several lights.
  const std::vector<float> maps = ReadFloat32File(dir / "v" / "maps" / "neural.f32");
  double worst = 0.0;
  for (const auto& [slant, tilt] : {std::pair{0.0, 0.0}, {30.0, 45.0}, {75.0, 200.0}}) {
    const LightDirection light = LightDirection::FromSlantTilt(slant, tilt);
    const Image relit = stack.Relight(light);
    for (int y = 0; y < 5; ++y) {
      for (int x = 0; x < 7; ++x) {
        std::vector<float> codes;
        for (int j = 0; j < 9; ++j) {
          codes.push_back(maps[((static_cast<std::size_t>(j / 4) * 5 + y) * 7 + x) * 4 + j % 4]);
        }
        const std::vector<float> out = EvaluateFromTexture(
            texels, shading, codes, static_cast<float>(light.x()), static_cast<float>(light.y()));
        for (int c = 0; c < 3; ++c) {
          worst = std::max(worst, static_cast<double>(std::abs(out[c] - relit.at(x, y, c))));
        }
      }
    }
  }
  // Only the order of the float sums differs from Eigen's: measured 3.7e-8 on outputs of order
  // 0.1 to 1; bound 1e-5 (float rounding of 50-term sums, three layers deep, with a wide margin).
  std::printf("largest difference from Relight: %.3g\n", worst);
  EXPECT_LT(worst, 1e-5);
}

TEST(ViewerDecoderTest, TiledNeuralExportsCarryTheDecoderToo) {
  TempDir dir;
  const NeuralDecoder decoder = RandomDecoder(5, 16, 3, 14);
  ViewerExportOptions options;
  options.tiling = ViewerTiling::kAlways;
  options.tile_size = 8;
  ExportViewer(dir / "v", {NeuralStack(decoder, 20, 12, 15)}, options);
  const nlohmann::json method = ReadJsonFile(dir / "v" / "viewer.json")["methods"][0];
  EXPECT_TRUE(method["data"].contains("pyramid"));
  EXPECT_EQ(method["shading"]["file"], "maps/neural.decoder.f32");
  EXPECT_EQ(ReadFloat32File(dir / "v" / "maps" / "neural.decoder.f32").size() * 4,
            ViewerDecoderTexture(decoder).size());
}

}  // namespace
}  // namespace photomat
