#pragma once

#include <nlohmann/json.hpp>
#include <string>
#include <vector>

#include "represent/model/neural_decoder.h"

namespace photomat {

// The `neural` basis's decoder (represent/model/neural_decoder.h) as the web viewer's fragment
// shader reads it: one RGBA32F texture of every layer's weights and biases, fetched with
// texelFetch, so that each fragment evaluates decoder(coefficients, lx, ly) as NeuralShading does.
//
// IMPLEMENTER CHOICE: a texture, not uniform arrays: NeuralRTI's decoder (k + 2 -> 50 -> 50 -> 50
// -> 3) holds about 5,800 floats, beyond the 1,024 uniform floats (256 vec4) WebGL2 guarantees;
// texels of 4 weights let the shader form each neuron's sum with vec4 dot products.
//
// Layout (the file is the texture, as a method's maps file is): texel rows of width `width`, one
// row per neuron; layer L's neurons are rows first_row[L] .. first_row[L] + outputs - 1. In the
// row of neuron o, texel t < ceil(inputs / 4) holds weights (o, 4t .. 4t + 3) (0 past the last
// input) and texel ceil(inputs / 4) holds (bias_o, 0, 0, 0). width = max over layers of
// ceil(inputs / 4) + 1; texels past a layer's bias texel are 0. Float32 little-endian (RGBA
// texels, rows from the first).
struct ViewerDecoderLayout {
  int width = 0;   // texels per row
  int height = 0;  // rows: every layer's outputs
  std::vector<int> first_rows;

  explicit ViewerDecoderLayout(const NeuralDecoder& decoder);
};

// The texture's bytes (width x height RGBA float32 texels).
std::string ViewerDecoderTexture(const NeuralDecoder& decoder);

// viewer.json's description of the decoder whose texture is at `file` (relative to the viewer):
// {"kind": "neural", "activation": "elu", "output_scale": s, "coefficients": k, "outputs": C,
//  "file": file, "texture": {"width", "height"},
//  "layers": [{"inputs", "outputs", "first_row"}, ...]}
nlohmann::json ViewerDecoderJson(const NeuralDecoder& decoder, const std::string& file);

}  // namespace photomat
