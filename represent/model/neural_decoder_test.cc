#include "represent/model/neural_decoder.h"

#include <gtest/gtest.h>

#include <cmath>

#include "core/error.h"
#include "core/random.h"
#include "represent/model/representation.h"

namespace photomat {
namespace {

// A decoder of k = 2 coefficients: 4 inputs -> 3 hidden (ELU) -> 3 outputs, random weights.
NeuralDecoder SmallDecoder(std::uint64_t seed, float scale = 2.0f) {
  Random random(seed);
  auto fill = [&](Eigen::Index rows, Eigen::Index cols) {
    Eigen::MatrixXf m(rows, cols);
    for (Eigen::Index i = 0; i < m.size(); ++i) m.data()[i] = static_cast<float>(random.Normal());
    return m;
  };
  std::vector<DenseLayer> layers;
  layers.push_back({fill(3, 4), fill(3, 1).col(0)});
  layers.push_back({fill(3, 3), fill(3, 1).col(0)});
  return NeuralDecoder(std::move(layers), scale);
}

TEST(NeuralDecoderTest, EvaluatesTheLayersWithEluBetween) {
  const NeuralDecoder decoder = SmallDecoder(7);
  EXPECT_EQ(decoder.coefficients(), 2);
  EXPECT_EQ(decoder.outputs(), 3);
  const float coefficients[] = {0.4f, -1.3f};
  const float lx = 0.25f;
  const float ly = -0.5f;
  float out[3];
  decoder.Evaluate(coefficients, lx, ly, out);
  // The same by hand, in double.
  const auto& l0 = decoder.layers()[0];
  const auto& l1 = decoder.layers()[1];
  const Eigen::Vector4d input(0.4, -1.3, 0.25, -0.5);
  Eigen::Vector3d hidden = l0.weight.cast<double>() * input + l0.bias.cast<double>();
  for (int i = 0; i < 3; ++i) hidden[i] = hidden[i] > 0 ? hidden[i] : std::expm1(hidden[i]);
  const Eigen::Vector3d expected =
      2.0 * (l1.weight.cast<double>() * hidden + l1.bias.cast<double>());
  for (int c = 0; c < 3; ++c) EXPECT_NEAR(out[c], expected[c], 1e-5 * (1 + std::abs(expected[c])));
}

TEST(NeuralDecoderTest, JsonRoundTripIsBitExact) {
  const NeuralDecoder decoder = SmallDecoder(11, 0.37f);
  const nlohmann::json json = nlohmann::json::parse(decoder.ToJson().dump());
  const NeuralDecoder back = NeuralDecoder::FromJson(JsonReader(json, "stack.exr"));
  ASSERT_EQ(back.layers().size(), decoder.layers().size());
  for (std::size_t i = 0; i < back.layers().size(); ++i) {
    EXPECT_EQ(back.layers()[i].weight, decoder.layers()[i].weight);
    EXPECT_EQ(back.layers()[i].bias, decoder.layers()[i].bias);
  }
  EXPECT_EQ(back.output_scale(), decoder.output_scale());
}

TEST(NeuralDecoderTest, MalformedDecodersNameTheFault) {
  nlohmann::json json = SmallDecoder(3).ToJson();
  json["layers"][1]["inputs"] = 4;
  json["layers"][1]["weight"].push_back(0.0);
  json["layers"][1]["weight"].push_back(0.0);
  json["layers"][1]["weight"].push_back(0.0);
  try {
    NeuralDecoder::FromJson(JsonReader(json, "cat.exr", "shading.decoder"));
    FAIL() << "a layer that does not chain was accepted";
  } catch (const Error& error) {
    EXPECT_NE(std::string(error.what()).find("cat.exr"), std::string::npos) << error.what();
    EXPECT_NE(std::string(error.what()).find("layer 1 takes 4 inputs, layer 0 gives 3"),
              std::string::npos)
        << error.what();
  }
  nlohmann::json short_bias = SmallDecoder(3).ToJson();
  short_bias["layers"][0]["bias"].erase(0);
  EXPECT_THROW(NeuralDecoder::FromJson(JsonReader(short_bias, "cat.exr")), Error);
  nlohmann::json zero_scale = SmallDecoder(3).ToJson();
  zero_scale["output_scale"] = 0.0;
  EXPECT_THROW(NeuralDecoder::FromJson(JsonReader(zero_scale, "cat.exr")), Error);
}

TEST(NeuralDecoderTest, NeuralRepresentationRelightsThroughTheDecoderAndHasNoNormals) {
  auto shading = std::make_shared<NeuralShading>(SmallDecoder(5));
  Image maps(2, 1, shading->MapNames());
  EXPECT_EQ(maps.channel_names(), (std::vector<std::string>{"neural.0", "neural.1"}));
  maps.pixel(0, 0)[0] = 0.3f;
  maps.pixel(0, 0)[1] = -0.2f;
  maps.pixel(1, 0)[0] = -1.0f;
  maps.pixel(1, 0)[1] = 0.8f;
  const Representation r("neural", maps, shading);
  EXPECT_EQ(r.basis().kind(), "direction");
  const LightDirection light = LightDirection::FromSlantTilt(40, 120);
  const Image relit = r.Relight(light);
  ASSERT_EQ(relit.channels(), 3);
  for (int x = 0; x < 2; ++x) {
    const float coefficients[] = {maps.at(x, 0, 0), maps.at(x, 0, 1)};
    float expected[3];
    shading->decoder().Evaluate(coefficients, static_cast<float>(light.x()),
                                static_cast<float>(light.y()), expected);
    for (int c = 0; c < 3; ++c) EXPECT_FLOAT_EQ(relit.at(x, 0, c), expected[c]);
  }
  EXPECT_FALSE(EstimateNormals(r));
  const auto back =
      PixelShadingFromJson(JsonReader(nlohmann::json::parse(shading->ToJson().dump()), "s.exr"));
  EXPECT_EQ(back->kind(), "neural");
  EXPECT_EQ(back->map_count(), 2);
}

}  // namespace
}  // namespace photomat
