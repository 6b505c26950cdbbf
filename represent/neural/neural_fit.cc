#include "represent/neural/neural_fit.h"

#include <fmt/format.h>
#include <torch/torch.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <limits>
#include <numeric>

#include "core/error.h"
#include "core/random.h"
#include "represent/model/method.h"
#include "represent/model/neural_decoder.h"
#include "represent/neural/neural_network.h"

namespace photomat {
namespace {

namespace fs = std::filesystem;

void CheckOptions(const NeuralFitOptions& o, const fs::path& source) {
  auto fail = [&](const std::string& fault) { throw Error(source, "neural: " + fault); };
  if (o.coefficients < 1 || o.coefficients > NeuralDecoder::kMaxWidth - 2) {
    fail(fmt::format("k = {} coefficients: expected 1 to {}", o.coefficients,
                     NeuralDecoder::kMaxWidth - 2));
  }
  if (o.decoder_width < 1 || o.decoder_width > NeuralDecoder::kMaxWidth || o.encoder_width < 1) {
    fail("layer widths must be positive (the decoder's at most 256)");
  }
  if (o.encoder_layers < 0 || o.decoder_layers < 0) fail("negative layer counts");
  if (o.max_epochs < 1) fail(fmt::format("{} epochs: expected at least 1", o.max_epochs));
  if (o.patience < 1 || o.batch_pixels < 1 || o.threads < 1 || o.lights_per_batch < 0) {
    fail("patience, batch size and threads must be positive");
  }
  if (!(o.validation_fraction > 0.0 && o.validation_fraction < 0.5)) {
    fail("the validation fraction must be in (0, 0.5)");
  }
  if (!(o.learning_rate > 0.0)) fail("the learning rate must be positive");
}

// Seeded Fisher-Yates (core's Random: the same order on every platform).
void Shuffle(std::vector<std::int64_t>& values, Random& random) {
  for (std::size_t i = values.size(); i > 1; --i) {
    std::swap(values[i - 1], values[random.Index(i)]);
  }
}

// The training data: every selected observation of every pixel, divided by `scale`.
struct TrainingData {
  torch::Tensor values;  // m x n x C
  torch::Tensor inputs;  // m x (n C): the encoder's input, the same values per pixel
  torch::Tensor lights;  // n x 2: (lx, ly) of the selected lights
  float scale = 1.0f;
};

TrainingData MakeTrainingData(const Observations& observations,
                              const std::vector<LightDirection>& lights,
                              std::span<const int> selected, const fs::path& source) {
  const std::int64_t m = observations.pixels();
  const auto n = static_cast<std::int64_t>(selected.size());
  const std::int64_t channels = observations.channels();
  const Eigen::MatrixXf& matrix = observations.matrix();
  double sum_squares = 0.0;
  for (int i : selected) sum_squares += matrix.col(i).cast<double>().squaredNorm();
  const double rms = std::sqrt(sum_squares / static_cast<double>(m * n * channels));
  if (!(rms > 0.0) || !std::isfinite(rms)) {
    throw Error(source, "neural: every observed value is zero (or not finite)");
  }
  TrainingData data;
  data.scale = static_cast<float>(rms);
  data.values = torch::empty({m, n, channels}, torch::kFloat32);
  float* out = data.values.data_ptr<float>();
  for (std::int64_t p = 0; p < m; ++p) {
    for (std::int64_t i = 0; i < n; ++i) {
      for (std::int64_t c = 0; c < channels; ++c) {
        out[(p * n + i) * channels + c] = matrix(c * m + p, selected[i]) / data.scale;
      }
    }
  }
  data.inputs = data.values.view({m, n * channels});
  data.lights = torch::empty({n, 2}, torch::kFloat32);
  for (std::int64_t i = 0; i < n; ++i) {
    data.lights[i][0] = static_cast<float>(lights[selected[i]].x());
    data.lights[i][1] = static_cast<float>(lights[selected[i]].y());
  }
  return data;
}

// The decoder's output for `codes` (B x k) under every light (n x 2): B x n x C.
torch::Tensor DecodeAllLights(torch::nn::Sequential& decoder, const torch::Tensor& codes,
                              const torch::Tensor& lights, std::int64_t channels) {
  const std::int64_t b = codes.size(0);
  const std::int64_t n = lights.size(0);
  const std::int64_t k = codes.size(1);
  const torch::Tensor input =
      torch::cat({codes.unsqueeze(1).expand({b, n, k}), lights.unsqueeze(0).expand({b, n, 2})}, 2);
  return decoder->forward(input.reshape({b * n, k + 2})).view({b, n, channels});
}

std::vector<torch::Tensor> CopyParameters(const std::vector<torch::Tensor>& parameters) {
  std::vector<torch::Tensor> copies;
  for (const torch::Tensor& p : parameters) copies.push_back(p.detach().clone());
  return copies;
}

}  // namespace

nlohmann::json NeuralFitOptions::ToJson() const {
  return {{"coefficients", coefficients},
          {"encoder", {{"width", encoder_width}, {"hidden_layers", encoder_layers}}},
          {"decoder", {{"width", decoder_width}, {"hidden_layers", decoder_layers}}},
          {"activation", "elu"},
          {"max_epochs", max_epochs},
          {"patience", patience},
          {"min_improvement", min_improvement},
          {"validation_fraction", validation_fraction},
          {"batch_pixels", batch_pixels},
          {"lights_per_batch", lights_per_batch},
          {"learning_rate", learning_rate},
          {"optimiser", "adam"},
          {"seed", seed},
          {"threads", threads}};
}

nlohmann::json NeuralFitReport::ToJson() const {
  return {{"epochs", epochs},
          {"best_epoch", best_epoch},
          {"training_loss", training_loss},
          {"validation_loss", validation_loss},
          {"training_pixels", training_pixels},
          {"validation_pixels", validation_pixels},
          {"seconds", seconds}};
}

Representation FitNeural(const Observations& observations,
                         const std::vector<LightDirection>& lights, std::span<const int> selected,
                         const NeuralFitOptions& options, const fs::path& source,
                         Progress* progress, NeuralFitReport* report_out) {
  const auto start_time = std::chrono::steady_clock::now();
  CheckOptions(options, source);
  const int minimum = Method{Method::Kind::kNeural}.MinimumImages();
  if (static_cast<int>(selected.size()) < minimum) {
    throw Error(source,
                fmt::format("neural needs at least {} images; {} given", minimum, selected.size()));
  }
  const std::int64_t m = observations.pixels();
  if (m < 2) throw Error(source, "neural: fewer than 2 pixels to train on");
  NullProgress no_progress;
  Progress& bar = OrNull(progress, no_progress);

  // IMPLEMENTER CHOICE: libtorch's thread count is process-wide; it is set here for every fit
  // (a fixed count gives fixed reduction orders: the same bits run after run).
  torch::set_num_threads(options.threads);
  torch::manual_seed(options.seed);
  const std::int64_t channels = observations.channels();
  const std::int64_t n = static_cast<std::int64_t>(selected.size());
  const TrainingData data = MakeTrainingData(observations, lights, selected, source);
  torch::nn::Sequential encoder =
      MakePerceptron(static_cast<int>(n * channels), options.encoder_width, options.encoder_layers,
                     options.coefficients);
  torch::nn::Sequential decoder =
      MakePerceptron(options.coefficients + 2, options.decoder_width, options.decoder_layers,
                     static_cast<int>(channels));
  std::vector<torch::Tensor> parameters = encoder->parameters();
  for (const torch::Tensor& p : decoder->parameters()) parameters.push_back(p);
  torch::optim::Adam optimiser(parameters, torch::optim::AdamOptions(options.learning_rate));

  // Validation pixels: a seeded draw; the rest train.
  Random random(options.seed);
  std::vector<std::int64_t> order(static_cast<std::size_t>(m));
  std::iota(order.begin(), order.end(), std::int64_t{0});
  Shuffle(order, random);
  const auto validation_count = std::max<std::int64_t>(
      1, static_cast<std::int64_t>(std::llround(options.validation_fraction * m)));
  std::vector<std::int64_t> validation(order.begin(), order.begin() + validation_count);
  std::vector<std::int64_t> training(order.begin() + validation_count, order.end());
  std::sort(validation.begin(), validation.end());

  auto loss_of = [&](const torch::Tensor& index) {
    const torch::Tensor codes = encoder->forward(data.inputs.index_select(0, index));
    return torch::mse_loss(DecodeAllLights(decoder, codes, data.lights, channels),
                           data.values.index_select(0, index));
  };
  // The same under a subset of the lights (`light_index`, ascending).
  auto loss_under = [&](const torch::Tensor& index, const torch::Tensor& light_index) {
    const torch::Tensor codes = encoder->forward(data.inputs.index_select(0, index));
    return torch::mse_loss(
        DecodeAllLights(decoder, codes, data.lights.index_select(0, light_index), channels),
        data.values.index_select(0, index).index_select(1, light_index));
  };
  const std::int64_t lights_per_batch =
      options.lights_per_batch > 0 ? std::min<std::int64_t>(options.lights_per_batch, n) : n;
  std::vector<std::int64_t> light_order(static_cast<std::size_t>(n));
  std::iota(light_order.begin(), light_order.end(), std::int64_t{0});
  // Mean squared error over `pixels`, without gradients, in batches.
  auto mean_loss = [&](const std::vector<std::int64_t>& pixels) {
    torch::NoGradGuard no_grad;
    constexpr std::size_t kBatch = 1024;
    double sum = 0.0;
    for (std::size_t first = 0; first < pixels.size(); first += kBatch) {
      const std::size_t count = std::min(kBatch, pixels.size() - first);
      const torch::Tensor index = torch::tensor(
          std::vector<std::int64_t>(pixels.begin() + first, pixels.begin() + first + count),
          torch::kInt64);
      sum += loss_of(index).item<double>() * static_cast<double>(count);
    }
    return sum / static_cast<double>(pixels.size());
  };

  NeuralFitReport report;
  report.training_pixels = static_cast<int>(training.size());
  report.validation_pixels = static_cast<int>(validation.size());
  double best = std::numeric_limits<double>::infinity();
  std::vector<torch::Tensor> best_parameters = CopyParameters(parameters);
  int stale = 0;
  const auto batch = static_cast<std::size_t>(options.batch_pixels);
  const std::size_t batches = (training.size() + batch - 1) / batch;
  for (int epoch = 1; epoch <= options.max_epochs; ++epoch) {
    bar.Start(std::isfinite(best) ? fmt::format("neural: epoch {}/{} (validation loss {:.4g})",
                                                epoch, options.max_epochs, best)
                                  : fmt::format("neural: epoch {}/{}", epoch, options.max_epochs),
              batches);
    Shuffle(training, random);
    double training_sum = 0.0;
    for (std::size_t first = 0; first < training.size(); first += batch) {
      const std::size_t count = std::min(batch, training.size() - first);
      const torch::Tensor index = torch::tensor(
          std::vector<std::int64_t>(training.begin() + first, training.begin() + first + count),
          torch::kInt64);
      optimiser.zero_grad();
      torch::Tensor loss;
      if (lights_per_batch < n) {
        Shuffle(light_order, random);
        std::vector<std::int64_t> chosen(light_order.begin(),
                                         light_order.begin() + lights_per_batch);
        std::sort(chosen.begin(), chosen.end());
        loss = loss_under(index, torch::tensor(chosen, torch::kInt64));
      } else {
        loss = loss_of(index);
      }
      loss.backward();
      optimiser.step();
      training_sum += loss.item<double>() * static_cast<double>(count);
      bar.Advance();
    }
    bar.Finish();
    const double validation_loss = mean_loss(validation);
    report.epochs = epoch;
    if (validation_loss < best * (1.0 - options.min_improvement)) {
      best = validation_loss;
      best_parameters = CopyParameters(parameters);
      report.best_epoch = epoch;
      report.training_loss = training_sum / static_cast<double>(training.size());
      report.validation_loss = validation_loss;
      stale = 0;
    } else if (++stale >= options.patience) {
      break;
    }
  }
  {
    torch::NoGradGuard no_grad;
    for (std::size_t i = 0; i < parameters.size(); ++i) parameters[i].copy_(best_parameters[i]);
  }

  // The coefficient maps: every pixel encoded by the kept encoder.
  const int k = options.coefficients;
  Image maps(observations.width(), observations.height(), NeuralMapNames(k));
  {
    torch::NoGradGuard no_grad;
    constexpr std::int64_t kBatch = 4096;
    for (std::int64_t first = 0; first < m; first += kBatch) {
      const std::int64_t count = std::min(kBatch, m - first);
      const torch::Tensor codes =
          encoder->forward(data.inputs.narrow(0, first, count)).contiguous();
      const float* c = codes.data_ptr<float>();
      for (std::int64_t p = 0; p < count; ++p) {
        auto pixel = maps.pixel(observations.pixel_indices()[first + p]);
        for (int j = 0; j < k; ++j) pixel[j] = c[p * k + j];
      }
    }
  }
  report.seconds =
      std::chrono::duration<double>(std::chrono::steady_clock::now() - start_time).count();
  if (report_out) *report_out = report;
  auto shading = std::make_shared<NeuralShading>(ToNeuralDecoder(decoder, data.scale));
  nlohmann::json details = {{"neural", options.ToJson()}, {"neural_training", report.ToJson()}};
  return Representation("neural", std::move(maps), std::move(shading), std::move(details));
}

}  // namespace photomat
