#pragma once

#include <cstdint>
#include <filesystem>
#include <nlohmann/json.hpp>
#include <span>
#include <vector>

#include "core/light_direction.h"
#include "core/progress.h"
#include "represent/fitting/observations.h"
#include "represent/model/representation.h"

namespace photomat {

// The `neural` basis (NeuralRTI, Dulecha et al. 2020), trained per capture on the CPU with
// libtorch. A per-pixel encoder (a perceptron from the pixel's profile: its observations under the
// selected lights, all channels) gives k coefficients; a small shared decoder turns k coefficients
// and the light's (lx, ly) into the pixel's colour. Both are trained together, as NeuralRTI does,
// on a seeded random sample of the pixels (every observation of each: mean squared error,
// minibatches, Adam, early stopping on held-out sample pixels); then the trained encoder encodes
// every pixel in one batched pass. The encoder's outputs are the coefficient maps (neural.0 ..
// neural.{k-1}) and the decoder travels in the stack's description (NeuralShading,
// represent/model/neural_decoder.h), so relighting needs no libtorch.
struct NeuralFitOptions {
  int coefficients = 9;  // k, NeuralRTI's default
  // NeuralRTI's sizes: three hidden layers of 150 (encoder) and 50 (decoder), ELU.
  int encoder_width = 150;
  int encoder_layers = 3;
  int decoder_width = 50;
  int decoder_layers = 3;
  // IMPLEMENTER CHOICE: the networks train on this many pixels (all of them when there are fewer),
  // drawn with the seed; validation_fraction of them are the early-stopping set. The decoder is
  // shared and the encoder is one function of a profile, so a sample of a capture's profiles
  // trains them nearly as well as all of them at a fraction of the cost (DiLiGenT cat: 15,000 of
  // 45,200; a 12 MP capture: 15,000 of 12 million); encoding is one cheap forward pass per pixel.
  // 15,000 (20,000 until 2026-12-06) keeps cat's 60 epochs under the 3-minute aim with the
  // patience below; 20,000 predicts held-out lights about 5 % better in 1.4 times the time
  // (README "Patience").
  int sample_pixels = 15000;
  int max_epochs = 60;
  // Early stopping: training ends when the validation loss has not fallen below
  // (1 - min_improvement) x its best for `patience` epochs; the best epoch's weights are kept.
  // IMPLEMENTER CHOICE: 10. The validation loss of these small minibatches stalls for several
  // epochs and then falls again; with a patience of 4 one of three seeds stopped DiLiGenT cat's
  // training at epoch 16 (README "Patience", chosen on a split of the training lights only).
  int patience = 10;
  double min_improvement = 1e-3;
  // IMPLEMENTER CHOICE: the validation set is 10 % of the sampled pixels (all their observations),
  // drawn with the seed; they are encoded like every pixel but never trained on.
  double validation_fraction = 0.1;
  int batch_pixels = 64;  // pixels per minibatch
  // IMPLEMENTER CHOICE: each minibatch decodes its pixels under this many of the selected lights,
  // drawn with the seed (all of them when there are fewer): the decoder's cost per epoch follows
  // pixels x lights, and on 96 lights a random quarter per step trains about as far per epoch
  // at a quarter of the cost. The encoder always reads the whole profile; validation uses every
  // light. 0: every light.
  int lights_per_batch = 24;
  double learning_rate = 1e-3;
  // Learning-rate schedule: every epoch that does not improve the validation loss (short of
  // `patience` such epochs) multiplies Adam's learning rate by this. 1: a constant rate.
  double plateau_decay = 1.0;
  std::uint64_t seed = 0;  // weights' initialisation, sample, validation pixels, minibatch order
  // libtorch's intra-op threads (process-wide), fixed for the fit so that the same seed gives the
  // same bits on a machine. 0: the machine's hardware threads (std::thread::hardware_concurrency).
  int threads = 0;

  nlohmann::json ToJson() const;
};

struct NeuralFitReport {
  int epochs = 0;                // trained
  int best_epoch = 0;            // whose weights were kept (1-based)
  double training_loss = 0.0;    // mean squared error of the normalised values, best epoch
  double validation_loss = 0.0;  // the same on the validation pixels
  int training_pixels = 0;       // of the sample, trained on
  int validation_pixels = 0;     // of the sample, the early-stopping set
  int encoded_pixels = 0;        // every pixel of the capture
  int threads = 0;               // libtorch's intra-op threads used
  double seconds = 0.0;          // wall time of the whole fit (training and encoding)
  double cpu_seconds = 0.0;      // the process's CPU time over the same span
  nlohmann::json ToJson() const;
};

// Trains the neural basis on the images in `selected` of `observations` (any number of channels)
// and returns the representation; `report` (optional) gets the training's summary, which is also
// in the details ("neural", "neural_training"). Deterministic for a given seed and thread count.
// Throws Error naming `source` for fewer than Method kNeural's minimum images, no pixels, or
// options out of range.
Representation FitNeural(const Observations& observations,
                         const std::vector<LightDirection>& lights, std::span<const int> selected,
                         const NeuralFitOptions& options = {},
                         const std::filesystem::path& source = {}, Progress* progress = nullptr,
                         NeuralFitReport* report = nullptr);

}  // namespace photomat
