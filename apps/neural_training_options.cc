#include "apps/neural_training_options.h"

namespace photomat::app {

void AddNeuralTrainingOptions(CLI::App& command, NeuralFitOptions& options) {
  command
      .add_option("--neural-k", options.coefficients,
                  "Coefficients per pixel (the maps neural.0 .. neural.{k-1})")
      ->capture_default_str();
  command
      .add_option("--neural-epochs", options.max_epochs,
                  "Most training epochs (training stops earlier when the validation loss stops "
                  "falling)")
      ->capture_default_str();
  command
      .add_option("--neural-patience", options.patience,
                  "Epochs without a better validation loss before training stops")
      ->capture_default_str();
  command
      .add_option("--neural-sample-pixels", options.sample_pixels,
                  "Pixels the networks train on, drawn with the seed (every pixel is encoded)")
      ->capture_default_str();
  command.add_option("--neural-batch-pixels", options.batch_pixels, "Pixels per minibatch")
      ->capture_default_str();
  command
      .add_option("--neural-lights-per-batch", options.lights_per_batch,
                  "Lights each minibatch decodes its pixels under, drawn with the seed (0: all)")
      ->capture_default_str();
  command.add_option("--neural-learning-rate", options.learning_rate, "Adam's learning rate")
      ->capture_default_str();
  command
      .add_option("--neural-threads", options.threads,
                  "libtorch's threads (0: the machine's; the same seed and count give the same "
                  "bits)")
      ->capture_default_str();
  command
      .add_option("--seed", options.seed,
                  "Seed of the initial weights, the pixel sample, the validation pixels and the "
                  "minibatch order")
      ->capture_default_str();
}

}  // namespace photomat::app
