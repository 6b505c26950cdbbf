#pragma once

#include <Eigen/Core>
#include <memory>
#include <nlohmann/json.hpp>
#include <span>
#include <string>
#include <string_view>
#include <vector>

#include "core/image.h"
#include "core/json_file.h"
#include "represent/model/shading.h"

namespace photomat {

// One fully connected layer of the decoder: out = weight * in + bias.
struct DenseLayer {
  Eigen::MatrixXf weight;  // outputs x inputs (torch::nn::Linear's layout)
  Eigen::VectorXf bias;    // outputs
};

// The decoder of the `neural` basis (NeuralRTI, Dulecha et al. 2020), evaluated with Eigen so that
// relighting, the stacks, synthesis and export need no libtorch (only the training,
// represent/neural, does). A multilayer perceptron from a pixel's k coefficients and the light's
// (lx, ly) to its C output channels: ELU (alpha 1) after every layer but the last, whose output
// is multiplied by `output_scale` (the training divides the captured values by it).
class NeuralDecoder {
 public:
  // Widest layer the decoder evaluates (its buffers live on the stack: relighting calls it once
  // per pixel and light).
  static constexpr int kMaxWidth = 256;

  // Throws Error if the layers do not chain (each layer's inputs the previous one's outputs), a
  // layer is wider than kMaxWidth, the first takes fewer than 3 inputs (k >= 1 plus lx, ly), or a
  // value is not finite.
  NeuralDecoder(std::vector<DenseLayer> dense_layers, float scale);

  int coefficients() const { return static_cast<int>(layers_.front().weight.cols()) - 2; }
  int outputs() const { return static_cast<int>(layers_.back().weight.rows()); }
  const std::vector<DenseLayer>& layers() const { return layers_; }
  float output_scale() const { return output_scale_; }

  // `codes` holds the k coefficients, `out` gets C values.
  void Evaluate(std::span<const float> codes, float lx, float ly, std::span<float> out) const;

  // {"activation": "elu", "output_scale": s, "layers": [{"inputs", "outputs", "weight" (row-major),
  // "bias"}, ...]}: floats as JSON numbers (written as doubles, so they read back bit for bit).
  nlohmann::json ToJson() const;
  // Throws Error naming the reader's file and JSON path for a malformed decoder.
  static NeuralDecoder FromJson(const JsonReader& json);

 private:
  std::vector<DenseLayer> layers_;
  float output_scale_ = 1.0f;
};

// The `neural` shading: maps neural.0 .. neural.{k-1} (the encoder's coefficients of each pixel),
// relit by the shared decoder at the light's (lx, ly). Not linear in its maps, so it relights
// through PixelShading like `pbr`; it has no normal maps.
class NeuralShading final : public PixelShading {
 public:
  explicit NeuralShading(NeuralDecoder decoder) : decoder_(std::move(decoder)) {}

  std::string_view kind() const override { return "neural"; }
  int map_count() const override { return decoder_.coefficients(); }
  int output_channels() const override { return decoder_.outputs(); }
  std::vector<std::string> MapNames() const override;
  std::optional<int> normal_offset() const override { return std::nullopt; }
  void Shade(PixelValues<const float> maps, std::span<const float> light,
             std::span<float> out) const override;
  // {"kind": "neural", "decoder": NeuralDecoder::ToJson()}.
  nlohmann::json ToJson() const override;

  const NeuralDecoder& decoder() const { return decoder_; }

 private:
  NeuralDecoder decoder_;
};

// Map names of k neural coefficients: "neural.0" .. "neural.{k-1}".
std::vector<std::string> NeuralMapNames(int coefficients);

}  // namespace photomat
