#include "represent/neural/neural_network.h"

#include <utility>
#include <vector>

namespace photomat {

torch::nn::Sequential MakePerceptron(int inputs, int width, int hidden_layers, int outputs) {
  torch::nn::Sequential network;
  int in = inputs;
  for (int i = 0; i < hidden_layers; ++i) {
    network->push_back(torch::nn::Linear(in, width));
    network->push_back(torch::nn::ELU());
    in = width;
  }
  network->push_back(torch::nn::Linear(in, outputs));
  return network;
}

NeuralDecoder ToNeuralDecoder(const torch::nn::Sequential& network, float output_scale) {
  torch::NoGradGuard no_grad;
  std::vector<DenseLayer> layers;
  for (const auto& module : network->children()) {
    const auto* linear = module->as<torch::nn::Linear>();
    if (!linear) continue;
    const torch::Tensor weight = linear->weight.detach().to(torch::kFloat32).contiguous();
    const torch::Tensor bias = linear->bias.detach().to(torch::kFloat32).contiguous();
    const auto rows = weight.size(0);
    const auto cols = weight.size(1);
    DenseLayer layer;
    // torch stores the weight row-major (outputs x inputs).
    layer.weight =
        Eigen::Map<const Eigen::Matrix<float, Eigen::Dynamic, Eigen::Dynamic, Eigen::RowMajor>>(
            weight.data_ptr<float>(), rows, cols);
    layer.bias = Eigen::Map<const Eigen::VectorXf>(bias.data_ptr<float>(), rows);
    layers.push_back(std::move(layer));
  }
  return NeuralDecoder(std::move(layers), output_scale);
}

}  // namespace photomat
