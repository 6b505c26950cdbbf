#include "relight/web/viewer_decoder.h"

#include <algorithm>

#include "relight/web/viewer_pyramid.h"

namespace photomat {
namespace {

int TexelsPerInputRow(const DenseLayer& layer) {
  return static_cast<int>((layer.weight.cols() + 3) / 4);
}

}  // namespace

ViewerDecoderLayout::ViewerDecoderLayout(const NeuralDecoder& decoder) {
  for (const DenseLayer& layer : decoder.layers()) {
    width = std::max(width, TexelsPerInputRow(layer) + 1);
    first_rows.push_back(height);
    height += static_cast<int>(layer.weight.rows());
  }
}

std::string ViewerDecoderTexture(const NeuralDecoder& decoder) {
  const ViewerDecoderLayout layout(decoder);
  std::vector<float> texels(static_cast<std::size_t>(layout.width) * layout.height * 4, 0.0f);
  for (std::size_t l = 0; l < decoder.layers().size(); ++l) {
    const DenseLayer& layer = decoder.layers()[l];
    const int bias_texel = TexelsPerInputRow(layer);
    for (Eigen::Index o = 0; o < layer.weight.rows(); ++o) {
      const std::size_t row_start =
          static_cast<std::size_t>(layout.first_rows[l] + o) * layout.width * 4;
      for (Eigen::Index i = 0; i < layer.weight.cols(); ++i) {
        texels[row_start + static_cast<std::size_t>(i)] = layer.weight(o, i);
      }
      texels[row_start + static_cast<std::size_t>(bias_texel) * 4] = layer.bias[o];
    }
  }
  std::string bytes;
  bytes.reserve(texels.size() * 4);
  for (float v : texels) AppendFloat32(bytes, v);
  return bytes;
}

nlohmann::json ViewerDecoderJson(const NeuralDecoder& decoder, const std::string& file) {
  const ViewerDecoderLayout layout(decoder);
  nlohmann::json layers = nlohmann::json::array();
  for (std::size_t l = 0; l < decoder.layers().size(); ++l) {
    const DenseLayer& layer = decoder.layers()[l];
    layers.push_back({{"inputs", layer.weight.cols()},
                      {"outputs", layer.weight.rows()},
                      {"first_row", layout.first_rows[l]}});
  }
  return {{"kind", "neural"},
          {"activation", "elu"},
          {"output_scale", decoder.output_scale()},
          {"coefficients", decoder.coefficients()},
          {"outputs", decoder.outputs()},
          {"file", file},
          {"texture", {{"width", layout.width}, {"height", layout.height}}},
          {"layers", std::move(layers)}};
}

}  // namespace photomat
