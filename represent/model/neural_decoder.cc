#include "represent/model/neural_decoder.h"

#include <fmt/format.h>

#include <algorithm>
#include <array>
#include <cmath>

#include "core/error.h"

namespace photomat {
namespace {

// ELU with alpha 1 (torch::nn::ELU's default): x for x > 0, exp(x) - 1 otherwise.
float Elu(float x) { return x > 0.0f ? x : std::expm1(x); }

bool AllFinite(const Eigen::MatrixXf& values) { return values.array().isFinite().all(); }

}  // namespace

NeuralDecoder::NeuralDecoder(std::vector<DenseLayer> dense_layers, float scale)
    : layers_(std::move(dense_layers)), output_scale_(scale) {
  if (layers_.empty()) throw Error("neural decoder: no layers");
  if (layers_.front().weight.cols() < 3) {
    throw Error(
        fmt::format("neural decoder: the first layer takes {} inputs; it needs k >= 1 "
                    "coefficients and the light's lx, ly",
                    layers_.front().weight.cols()));
  }
  for (std::size_t i = 0; i < layers_.size(); ++i) {
    const DenseLayer& layer = layers_[i];
    if (layer.bias.size() != layer.weight.rows()) {
      throw Error(fmt::format("neural decoder: layer {} has {} outputs but {} biases", i,
                              layer.weight.rows(), layer.bias.size()));
    }
    if (i > 0 && layer.weight.cols() != layers_[i - 1].weight.rows()) {
      throw Error(fmt::format("neural decoder: layer {} takes {} inputs, layer {} gives {}", i,
                              layer.weight.cols(), i - 1, layers_[i - 1].weight.rows()));
    }
    if (layer.weight.rows() > kMaxWidth || layer.weight.cols() > kMaxWidth) {
      throw Error(fmt::format("neural decoder: layer {} is {} x {}, wider than {}", i,
                              layer.weight.rows(), layer.weight.cols(), kMaxWidth));
    }
    if (!AllFinite(layer.weight) || !AllFinite(layer.bias)) {
      throw Error(fmt::format("neural decoder: layer {} has a value that is not finite", i));
    }
  }
  if (!std::isfinite(output_scale_) || output_scale_ <= 0.0f) {
    throw Error(fmt::format("neural decoder: output scale {} is not positive", output_scale_));
  }
}

void NeuralDecoder::Evaluate(std::span<const float> codes, float lx, float ly,
                             std::span<float> out) const {
  std::array<float, kMaxWidth> a{};
  std::array<float, kMaxWidth> b{};
  const int k = coefficients();
  std::copy_n(codes.begin(), k, a.begin());
  a[k] = lx;
  a[k + 1] = ly;
  float* in = a.data();
  float* next = b.data();
  for (std::size_t i = 0; i < layers_.size(); ++i) {
    const DenseLayer& layer = layers_[i];
    const auto width_in = layer.weight.cols();
    const auto width_out = layer.weight.rows();
    Eigen::Map<Eigen::VectorXf> result(next, width_out);
    result.noalias() = layer.weight * Eigen::Map<const Eigen::VectorXf>(in, width_in) + layer.bias;
    if (i + 1 < layers_.size()) {
      for (Eigen::Index j = 0; j < width_out; ++j) result[j] = Elu(result[j]);
    }
    std::swap(in, next);
  }
  for (int c = 0; c < outputs(); ++c) out[c] = in[c] * output_scale_;
}

nlohmann::json NeuralDecoder::ToJson() const {
  nlohmann::json layers_json = nlohmann::json::array();
  for (const DenseLayer& layer : layers_) {
    nlohmann::json weight = nlohmann::json::array();
    for (Eigen::Index r = 0; r < layer.weight.rows(); ++r) {
      for (Eigen::Index c = 0; c < layer.weight.cols(); ++c) weight.push_back(layer.weight(r, c));
    }
    nlohmann::json bias = nlohmann::json::array();
    for (Eigen::Index r = 0; r < layer.bias.size(); ++r) bias.push_back(layer.bias[r]);
    layers_json.push_back({{"inputs", layer.weight.cols()},
                           {"outputs", layer.weight.rows()},
                           {"weight", std::move(weight)},
                           {"bias", std::move(bias)}});
  }
  return {
      {"activation", "elu"}, {"output_scale", output_scale_}, {"layers", std::move(layers_json)}};
}

NeuralDecoder NeuralDecoder::FromJson(const JsonReader& json) {
  if (json["activation"].String() != "elu") json["activation"].Fail("expected \"elu\"");
  const JsonReader layers_json = json["layers"];
  std::vector<DenseLayer> parsed;
  for (std::size_t i = 0; i < layers_json.ArraySize(); ++i) {
    const JsonReader layer_json = layers_json[i];
    const int inputs = layer_json["inputs"].Integer();
    const int width_out = layer_json["outputs"].Integer();
    if (inputs < 1 || width_out < 1 || inputs > kMaxWidth || width_out > kMaxWidth) {
      layer_json.Fail(fmt::format("a {} x {} layer: expected 1 to {} inputs and outputs", width_out,
                                  inputs, kMaxWidth));
    }
    const std::vector<double> weight = layer_json["weight"].Numbers();
    const std::vector<double> bias = layer_json["bias"].Numbers();
    if (weight.size() != static_cast<std::size_t>(inputs) * width_out) {
      layer_json["weight"].Fail(
          fmt::format("{} values for a {} x {} layer", weight.size(), width_out, inputs));
    }
    if (bias.size() != static_cast<std::size_t>(width_out)) {
      layer_json["bias"].Fail(fmt::format("{} values for {} outputs", bias.size(), width_out));
    }
    DenseLayer layer{Eigen::MatrixXf(width_out, inputs), Eigen::VectorXf(width_out)};
    for (int r = 0; r < width_out; ++r) {
      for (int c = 0; c < inputs; ++c) {
        layer.weight(r, c) = static_cast<float>(weight[static_cast<std::size_t>(r) * inputs + c]);
      }
      layer.bias[r] = static_cast<float>(bias[r]);
    }
    parsed.push_back(std::move(layer));
  }
  try {
    return NeuralDecoder(std::move(parsed), static_cast<float>(json["output_scale"].Number()));
  } catch (const Error& error) {
    json.Fail(error.fault());
  }
}

std::vector<std::string> NeuralMapNames(int coefficients) {
  std::vector<std::string> names;
  for (int j = 0; j < coefficients; ++j) names.push_back(fmt::format("neural.{}", j));
  return names;
}

std::vector<std::string> NeuralShading::MapNames() const {
  return NeuralMapNames(decoder_.coefficients());
}

void NeuralShading::Shade(PixelValues<const float> maps, std::span<const float> light,
                          std::span<float> out) const {
  std::array<float, NeuralDecoder::kMaxWidth> coefficients{};
  const int k = decoder_.coefficients();
  for (int j = 0; j < k; ++j) coefficients[j] = maps[j];
  decoder_.Evaluate(std::span<const float>(coefficients.data(), k), light[0], light[1], out);
}

nlohmann::json NeuralShading::ToJson() const {
  return {{"kind", "neural"}, {"decoder", decoder_.ToJson()}};
}

}  // namespace photomat
