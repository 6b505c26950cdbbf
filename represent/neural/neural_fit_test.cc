#include "represent/neural/neural_fit.h"

#include <fmt/format.h>
#include <gtest/gtest.h>

#include <cmath>
#include <numeric>

#include "core/error.h"
#include "represent/evaluation/evaluation.h"
#include "represent/fitting/fit.h"
#include "represent/neural/neural_network.h"
#include "tests/support/synthetic_sets.h"

namespace photomat {
namespace {

// Small networks and few epochs: the tests check properties, not the final quality.
NeuralFitOptions TinyOptions() {
  NeuralFitOptions options;
  options.coefficients = 6;
  options.encoder_width = 32;
  options.decoder_width = 24;
  options.max_epochs = 3;
  options.batch_pixels = 32;
  options.seed = 5;
  return options;
}

std::vector<int> AllImages(int n) {
  std::vector<int> all(n);
  std::iota(all.begin(), all.end(), 0);
  return all;
}

TEST(NeuralFitTest, EigenDecoderEqualsTheTorchForward) {
  torch::manual_seed(3);
  torch::nn::Sequential network = MakePerceptron(9 + 2, 50, 3, 3);
  // Biases and weights larger than the initialisation's, so that every ELU branch is taken.
  {
    torch::NoGradGuard no_grad;
    for (torch::Tensor& p : network->parameters()) p.mul_(2.0);
  }
  const float scale = 0.75f;
  const NeuralDecoder decoder = ToNeuralDecoder(network, scale);
  ASSERT_EQ(decoder.coefficients(), 9);
  ASSERT_EQ(decoder.outputs(), 3);
  const torch::Tensor inputs = torch::randn({200, 11});
  torch::Tensor expected;
  {
    torch::NoGradGuard no_grad;
    expected = (network->forward(inputs) * scale).contiguous();
  }
  double largest = 0.0;
  for (int r = 0; r < 200; ++r) {
    std::vector<float> in(11);
    for (int j = 0; j < 11; ++j) in[j] = inputs[r][j].item<float>();
    float out[3];
    decoder.Evaluate(std::span<const float>(in.data(), 9), in[9], in[10], out);
    for (int c = 0; c < 3; ++c) {
      const double want = expected[r][c].item<float>();
      largest = std::max(largest, std::abs(out[c] - want) / std::max(1.0, std::abs(want)));
    }
  }
  // Float evaluation in another order than torch's: rounding only.
  EXPECT_LT(largest, 1e-6);
  RecordProperty("largest_relative_difference", fmt::format("{:.3g}", largest));
}

TEST(NeuralFitTest, TheSameSeedGivesTheSameBits) {
  const auto synthetic = testing::LambertianSet(SurfacePattern::kBumps, 16);
  const Observations observations(synthetic.set);
  const auto all = AllImages(synthetic.set.size());
  const Representation a = FitNeural(observations, synthetic.set.lights(), all, TinyOptions());
  const Representation b = FitNeural(observations, synthetic.set.lights(), all, TinyOptions());
  ASSERT_EQ(a.maps().channels(), 6);
  EXPECT_EQ(a.maps().channel_names()[0], "neural.0");
  bool identical = true;
  for (std::size_t p = 0; p < a.maps().pixel_count(); ++p) {
    for (int j = 0; j < 6; ++j) identical &= a.maps().pixel(p)[j] == b.maps().pixel(p)[j];
  }
  EXPECT_TRUE(identical);
  EXPECT_EQ(a.shading()->ToJson(), b.shading()->ToJson());
  NeuralFitOptions other = TinyOptions();
  other.seed = 6;
  const Representation c = FitNeural(observations, synthetic.set.lights(), all, other);
  EXPECT_NE(a.shading()->ToJson(), c.shading()->ToJson());
}

TEST(NeuralFitTest, ReportsTrainingAndStopsEarly) {
  const auto synthetic = testing::LambertianSet(SurfacePattern::kBumps, 16);
  const Observations observations(synthetic.set);
  NeuralFitOptions options = TinyOptions();
  options.max_epochs = 200;
  options.patience = 1;
  options.min_improvement = 0.5;  // demands halving the loss every epoch: stops early
  NeuralFitReport report;
  const Representation r =
      FitNeural(observations, synthetic.set.lights(), AllImages(synthetic.set.size()), options, {},
                nullptr, &report);
  EXPECT_LT(report.epochs, 200);
  EXPECT_GE(report.best_epoch, 1);
  EXPECT_LE(report.best_epoch, report.epochs);
  EXPECT_EQ(report.validation_pixels, 26);  // 10 % of 256
  EXPECT_EQ(report.training_pixels + report.validation_pixels, 256);
  EXPECT_EQ(r.details()["neural_training"]["epochs"], report.epochs);
}

// Training on a seeded sample of the pixels: the sample's size is the option's, its draw the
// seed's (the same bits twice), and every pixel of the capture, sampled or not, gets coefficients
// that relight it as well as the sampled ones are (the encoder generalises across pixels).
TEST(NeuralFitTest, TrainsOnASeededSampleAndEncodesEveryPixel) {
  const auto synthetic = testing::LambertianSet(SurfacePattern::kBumps, 24);
  const Observations observations(synthetic.set);
  const auto all = AllImages(synthetic.set.size());
  NeuralFitOptions options = TinyOptions();
  options.sample_pixels = 200;
  options.max_epochs = 100;
  options.threads = 1;
  options.patience = 10;
  options.learning_rate = 3e-3;
  NeuralFitReport report;
  const Representation a =
      FitNeural(observations, synthetic.set.lights(), all, options, {}, nullptr, &report);
  EXPECT_EQ(report.training_pixels + report.validation_pixels, 200);
  EXPECT_EQ(report.validation_pixels, 20);
  EXPECT_EQ(report.encoded_pixels, 576);
  EXPECT_EQ(report.threads, 1);
  const Representation b = FitNeural(observations, synthetic.set.lights(), all, options);
  bool identical = true;
  for (std::size_t p = 0; p < a.maps().pixel_count(); ++p) {
    for (int j = 0; j < 6; ++j) identical &= a.maps().pixel(p)[j] == b.maps().pixel(p)[j];
  }
  EXPECT_TRUE(identical);
  // Every pixel is encoded: eta over all 576 pixels at the training lights, 376 of which were
  // never trained on, measured 0.2042 (a training on all 576: 0.1850); bound 0.25, a 22 % margin.
  double eta = 0.0;
  for (int i : all) {
    eta += NormalisedRmsError(observations, i,
                              RelightObservedPixels(a, observations, synthetic.set.lights()[i]));
  }
  eta /= static_cast<double>(all.size());
  std::printf("eta over every pixel %.4f, training loss %.4g\n", eta, report.training_loss);
  RecordProperty("eta_every_pixel", fmt::format("{:.4f}", eta));
  EXPECT_LT(eta, 0.25);
}

TEST(NeuralFitTest, RefusesTooFewImagesNamingTheSource) {
  const auto synthetic = testing::LambertianSet(SurfacePattern::kBumps, 8);
  const Observations observations(synthetic.set);
  const std::vector<int> five = {0, 1, 2, 3, 4};
  try {
    FitNeural(observations, synthetic.set.lights(), five, TinyOptions(), "capture.lp");
    FAIL() << "five images were accepted";
  } catch (const Error& error) {
    EXPECT_NE(std::string(error.what()).find("capture.lp"), std::string::npos) << error.what();
    EXPECT_NE(std::string(error.what()).find("at least 6 images"), std::string::npos)
        << error.what();
  }
}

TEST(NeuralFitTest, RefusesOptionsOutOfRangeNamingTheFault) {
  const auto synthetic = testing::LambertianSet(SurfacePattern::kBumps, 8);
  const Observations observations(synthetic.set);
  const auto all = AllImages(synthetic.set.size());
  auto fault_of = [&](NeuralFitOptions options) {
    try {
      FitNeural(observations, synthetic.set.lights(), all, options, "capture.lp");
    } catch (const Error& error) {
      return std::string(error.what());
    }
    return std::string("accepted");
  };
  NeuralFitOptions decay = TinyOptions();
  decay.plateau_decay = 1.5;
  EXPECT_NE(fault_of(decay).find("plateau decay"), std::string::npos) << fault_of(decay);
  NeuralFitOptions sample = TinyOptions();
  sample.sample_pixels = 1;
  EXPECT_NE(fault_of(sample).find("a sample of 1 pixels"), std::string::npos) << fault_of(sample);
  NeuralFitOptions threads = TinyOptions();
  threads.threads = -1;
  EXPECT_NE(fault_of(threads).find("threads"), std::string::npos) << fault_of(threads);
}

// Issue 19's claim: on the shadowed specular capture (highlights and cast shadows, which PTM's
// biquadratic cannot follow), the neural basis predicts lights it never saw better than PTM.
// Every 6th light of the 36 is held out; both fit the other 30. The training's options were
// chosen on a validation split of the 30 training lights only (every 5th held out, fitted on 24,
// seeds 1 and 2; PTM 0.300 there): 150 epochs, patience 10 gave 0.335 and 0.322; k = 4, decoder
// widths 24 or 100, learning rate 1e-3, minibatches of 8, a 20 % validation set or a halving
// learning rate on plateaus were worse; 400 epochs with patience 30 gave 0.253 and 0.274, the
// best, kept. On the held-out lights: neural 0.1986 (239 epochs, best 209), PTM 0.2848 (before:
// 0.3026 against 0.2848, an expected failure). Bound: 0.22, a 10 % margin over the measured.
TEST(NeuralFitTest, BeatsPtmOnHeldOutSpecularLights) {
  const auto synthetic = testing::ShadowedSpecularSet(16);
  const Observations observations(synthetic.set);
  std::vector<int> kept;
  std::vector<int> held_out;
  for (int i = 0; i < synthetic.set.size(); ++i) (i % 6 == 0 ? held_out : kept).push_back(i);
  // A small capture (256 pixels): small minibatches for enough steps, one thread (the steps are
  // too small to share), every light per step.
  NeuralFitOptions options;
  options.max_epochs = 400;
  options.patience = 30;
  options.batch_pixels = 16;
  options.lights_per_batch = 0;
  options.learning_rate = 3e-3;
  options.threads = 1;
  options.seed = 1;
  NeuralFitReport report;
  const Representation neural =
      FitNeural(observations, synthetic.set.lights(), kept, options, {}, nullptr, &report);
  const Representation ptm =
      FitObservations(observations, synthetic.set.lights(), Method::Parse("ptm"), kept);
  double eta_neural = 0.0;
  double eta_ptm = 0.0;
  for (int i : held_out) {
    const LightDirection& light = synthetic.set.lights()[i];
    eta_neural +=
        NormalisedRmsError(observations, i, RelightObservedPixels(neural, observations, light));
    eta_ptm += NormalisedRmsError(observations, i, RelightObservedPixels(ptm, observations, light));
  }
  eta_neural /= static_cast<double>(held_out.size());
  eta_ptm /= static_cast<double>(held_out.size());
  RecordProperty("eta_neural", fmt::format("{:.4f}", eta_neural));
  RecordProperty("eta_ptm", fmt::format("{:.4f}", eta_ptm));
  RecordProperty("epochs", report.epochs);
  std::printf("held-out eta: neural %.4f (epochs %d, best %d), ptm %.4f\n", eta_neural,
              report.epochs, report.best_epoch, eta_ptm);
  EXPECT_LT(eta_neural, eta_ptm);
  EXPECT_LT(eta_neural, 0.22);
}

}  // namespace
}  // namespace photomat
