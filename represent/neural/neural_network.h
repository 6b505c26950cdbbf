#pragma once

#include <torch/torch.h>

#include "represent/model/neural_decoder.h"

namespace photomat {

// The networks of the neural basis (NeuralRTI, Dulecha et al. 2020) in libtorch: the per-pixel
// encoder from a pixel's profile (its n observations x C channels) to k coefficients, and the
// shared decoder from k coefficients and the light's (lx, ly) to C channels. Each is a chain of
// fully connected layers with ELU between (none after the last).
torch::nn::Sequential MakePerceptron(int inputs, int width, int hidden_layers, int outputs);

// The Linear layers of a MakePerceptron network, copied into the Eigen decoder that relighting
// uses (represent/model/neural_decoder.h); `output_scale` undoes the training's normalisation.
NeuralDecoder ToNeuralDecoder(const torch::nn::Sequential& network, float output_scale);

}  // namespace photomat
