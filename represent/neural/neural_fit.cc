#include "represent/neural/neural_fit.h"

#include <fmt/format.h>
#include <torch/torch.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <ctime>
#include <limits>
#include <numeric>
#include <thread>

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
  if (o.patience < 1 || o.batch_pixels < 1 || o.threads < 0 || o.lights_per_batch < 0) {
    fail("patience and batch size must be positive, threads not negative");
  }
  if (o.sample_pixels < 2) {
    fail(fmt::format("a sample of {} pixels: expected at least 2", o.sample_pixels));
  }
  if (!(o.validation_fraction > 0.0 && o.validation_fraction < 0.5)) {
    fail("the validation fraction must be in (0, 0.5)");
  }
  if (!(o.learning_rate > 0.0)) fail("the learning rate must be positive");
  if (!(o.plateau_decay > 0.0 && o.plateau_decay <= 1.0)) {
    fail("the learning rate's plateau decay must be in (0, 1]");
  }
}

// Seeded Fisher-Yates (core's Random: the same order on every platform).
void Shuffle(std::vector<std::int64_t>& values, Random& random) {
  for (std::size_t i = values.size(); i > 1; --i) {
    std::swap(values[i - 1], values[random.Index(i)]);
  }
}

// The encoder's input for `pixels` (indices into the observations): each pixel's observations
// under the selected lights, light-major and channels inner (n C values), divided by `scale`.
torch::Tensor ProfilesOf(const Observations& observations, std::span<const int> selected,
                         std::span<const std::int64_t> pixels, float scale) {
  const std::int64_t m = observations.pixels();
  const auto n = static_cast<std::int64_t>(selected.size());
  const std::int64_t channels = observations.channels();
  const auto count = static_cast<std::int64_t>(pixels.size());
  const Eigen::MatrixXf& matrix = observations.matrix();
  torch::Tensor profiles = torch::empty({count, n * channels}, torch::kFloat32);
  float* out = profiles.data_ptr<float>();
  for (std::int64_t i = 0; i < n; ++i) {
    for (std::int64_t c = 0; c < channels; ++c) {
      const auto column = matrix.col(selected[i]);
      for (std::int64_t q = 0; q < count; ++q) {
        out[q * n * channels + i * channels + c] = column[c * m + pixels[q]] / scale;
      }
    }
  }
  return profiles;
}

// The RMS of every selected observation: the values are divided by it so that the networks see
// values near 1 whatever the capture's exposure.
float ObservationScale(const Observations& observations, std::span<const int> selected,
                       const fs::path& source) {
  const Eigen::MatrixXf& matrix = observations.matrix();
  double sum_squares = 0.0;
  for (int i : selected) sum_squares += matrix.col(i).cast<double>().squaredNorm();
  const double count = static_cast<double>(matrix.rows()) * static_cast<double>(selected.size());
  const double rms = std::sqrt(sum_squares / count);
  if (!(rms > 0.0) || !std::isfinite(rms)) {
    throw Error(source, "neural: every observed value is zero (or not finite)");
  }
  return static_cast<float>(rms);
}

// The training data: every selected observation of the sampled pixels, divided by `scale`.
struct TrainingData {
  torch::Tensor values;  // s x n x C
  torch::Tensor inputs;  // s x (n C): the encoder's input, the same values per pixel
  torch::Tensor lights;  // n x 2: (lx, ly) of the selected lights
  float scale = 1.0f;
};

TrainingData MakeTrainingData(const Observations& observations,
                              const std::vector<LightDirection>& lights,
                              std::span<const int> selected, std::span<const std::int64_t> sample,
                              float scale) {
  const auto n = static_cast<std::int64_t>(selected.size());
  TrainingData data;
  data.scale = scale;
  data.inputs = ProfilesOf(observations, selected, sample, scale);
  data.values =
      data.inputs.view({static_cast<std::int64_t>(sample.size()), n, observations.channels()});
  data.lights = torch::empty({n, 2}, torch::kFloat32);
  for (std::int64_t i = 0; i < n; ++i) {
    data.lights[i][0] = static_cast<float>(lights[selected[i]].x());
    data.lights[i][1] = static_cast<float>(lights[selected[i]].y());
  }
  return data;
}

// The first `count` pixels of a seeded partial Fisher-Yates shuffle of 0 .. m-1.
std::vector<std::int64_t> SamplePixels(std::int64_t m, std::int64_t count, Random& random) {
  std::vector<std::int64_t> order(static_cast<std::size_t>(m));
  std::iota(order.begin(), order.end(), std::int64_t{0});
  for (std::int64_t i = 0; i < count; ++i) {
    const auto j = i + static_cast<std::int64_t>(random.Index(static_cast<std::uint64_t>(m - i)));
    std::swap(order[i], order[j]);
  }
  order.resize(static_cast<std::size_t>(count));
  return order;
}

// Every pixel's coefficients by the trained encoder, in bands (the profiles of a band only are
// held as a tensor), written to `maps` at the pixels' image positions.
void EncodeEveryPixel(torch::nn::Sequential& encoder, const Observations& observations,
                      std::span<const int> selected, float scale, Image& maps) {
  torch::NoGradGuard no_grad;
  constexpr std::int64_t kBand = 8192;
  const std::int64_t m = observations.pixels();
  const int k = maps.channels();
  std::vector<std::int64_t> band;
  for (std::int64_t first = 0; first < m; first += kBand) {
    const std::int64_t count = std::min(kBand, m - first);
    band.resize(static_cast<std::size_t>(count));
    std::iota(band.begin(), band.end(), first);
    const torch::Tensor codes =
        encoder->forward(ProfilesOf(observations, selected, band, scale)).contiguous();
    const float* c = codes.data_ptr<float>();
    for (std::int64_t p = 0; p < count; ++p) {
      auto pixel = maps.pixel(observations.pixel_indices()[first + p]);
      for (int j = 0; j < k; ++j) pixel[j] = c[p * k + j];
    }
  }
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

// Pixels [first, first + count) of `pixels` as an index tensor.
torch::Tensor IndexTensor(const std::vector<std::int64_t>& pixels, std::size_t first,
                          std::size_t count) {
  const auto begin = pixels.begin() + static_cast<std::ptrdiff_t>(first);
  return torch::tensor(std::vector<std::int64_t>(begin, begin + static_cast<std::ptrdiff_t>(count)),
                       torch::kInt64);
}

std::vector<torch::Tensor> CopyParameters(const std::vector<torch::Tensor>& parameters) {
  std::vector<torch::Tensor> copies;
  for (const torch::Tensor& p : parameters) copies.push_back(p.detach().clone());
  return copies;
}

// The encoder and the decoder trained together (NeuralRTI), with their optimiser. The encoder
// maps a pixel's profile (n C values) to k coefficients; the decoder maps k coefficients and a
// light's (lx, ly) to the pixel's value under that light. The random draws (the minibatch order,
// the lights of each minibatch) come from the caller's Random in a fixed order, so a seed gives
// the same training bit for bit.
class NeuralTrainer {
 public:
  NeuralTrainer(const TrainingData& data, std::int64_t channels, const NeuralFitOptions& options)
      : data_(data),
        channels_(channels),
        lights_(data.lights.size(0)),
        // The encoder's weights are drawn first, then the decoder's (torch's seeded generator).
        encoder_(MakePerceptron(static_cast<int>(lights_ * channels), options.encoder_width,
                                options.encoder_layers, options.coefficients)),
        decoder_(MakePerceptron(options.coefficients + 2, options.decoder_width,
                                options.decoder_layers, static_cast<int>(channels))),
        parameters_(AllParameters(encoder_, decoder_)),
        learning_rate_(options.learning_rate),
        optimiser_(parameters_, torch::optim::AdamOptions(learning_rate_)),
        batch_(static_cast<std::size_t>(options.batch_pixels)),
        lights_per_batch_(options.lights_per_batch > 0
                              ? std::min<std::int64_t>(options.lights_per_batch, lights_)
                              : lights_),
        light_order_(static_cast<std::size_t>(lights_)) {
    std::iota(light_order_.begin(), light_order_.end(), std::int64_t{0});
  }

  std::size_t Batches(std::size_t pixels) const { return (pixels + batch_ - 1) / batch_; }

  // One epoch: `training` shuffled, then one Adam step per minibatch of its pixels, each decoded
  // under lights_per_batch of the lights (drawn per minibatch) or all of them. Returns the mean
  // training loss; advances `bar` once per minibatch.
  double Epoch(std::vector<std::int64_t>& training, Random& random, Progress& bar) {
    Shuffle(training, random);
    double sum = 0.0;
    for (std::size_t first = 0; first < training.size(); first += batch_) {
      const std::size_t count = std::min(batch_, training.size() - first);
      const torch::Tensor index = IndexTensor(training, first, count);
      optimiser_.zero_grad();
      torch::Tensor loss;
      if (lights_per_batch_ < lights_) {
        Shuffle(light_order_, random);
        std::vector<std::int64_t> chosen(light_order_.begin(),
                                         light_order_.begin() + lights_per_batch_);
        std::sort(chosen.begin(), chosen.end());
        const torch::Tensor light_index = torch::tensor(chosen, torch::kInt64);
        loss = Loss(index, &light_index);
      } else {
        loss = Loss(index);
      }
      loss.backward();
      optimiser_.step();
      sum += loss.item<double>() * static_cast<double>(count);
      bar.Advance();
    }
    return sum / static_cast<double>(training.size());
  }

  // Mean squared error over `pixels` under every light, without gradients, in batches.
  double MeanLoss(const std::vector<std::int64_t>& pixels) {
    torch::NoGradGuard no_grad;
    constexpr std::size_t kBatch = 1024;
    double sum = 0.0;
    for (std::size_t first = 0; first < pixels.size(); first += kBatch) {
      const std::size_t count = std::min(kBatch, pixels.size() - first);
      const torch::Tensor index = IndexTensor(pixels, first, count);
      sum += Loss(index).item<double>() * static_cast<double>(count);
    }
    return sum / static_cast<double>(pixels.size());
  }

  std::vector<torch::Tensor> Snapshot() const { return CopyParameters(parameters_); }
  void Restore(const std::vector<torch::Tensor>& snapshot) {
    torch::NoGradGuard no_grad;
    for (std::size_t i = 0; i < parameters_.size(); ++i) parameters_[i].copy_(snapshot[i]);
  }
  void ScaleLearningRate(double factor) {
    learning_rate_ *= factor;
    for (auto& group : optimiser_.param_groups()) {
      static_cast<torch::optim::AdamOptions&>(group.options()).lr(learning_rate_);
    }
  }

  torch::nn::Sequential& encoder() { return encoder_; }
  torch::nn::Sequential& decoder() { return decoder_; }

 private:
  static std::vector<torch::Tensor> AllParameters(torch::nn::Sequential& encoder,
                                                  torch::nn::Sequential& decoder) {
    std::vector<torch::Tensor> parameters = encoder->parameters();
    for (const torch::Tensor& p : decoder->parameters()) parameters.push_back(p);
    return parameters;
  }
  // The minibatch `index`'s mean squared error under every light, or under `light_index` only
  // (ascending).
  torch::Tensor Loss(const torch::Tensor& index, const torch::Tensor* light_index = nullptr) {
    const torch::Tensor codes = encoder_->forward(data_.inputs.index_select(0, index));
    const torch::Tensor values = data_.values.index_select(0, index);
    if (!light_index) {
      return torch::mse_loss(DecodeAllLights(decoder_, codes, data_.lights, channels_), values);
    }
    return torch::mse_loss(
        DecodeAllLights(decoder_, codes, data_.lights.index_select(0, *light_index), channels_),
        values.index_select(1, *light_index));
  }

  const TrainingData& data_;
  std::int64_t channels_;
  std::int64_t lights_;
  torch::nn::Sequential encoder_;
  torch::nn::Sequential decoder_;
  std::vector<torch::Tensor> parameters_;
  double learning_rate_;
  torch::optim::Adam optimiser_;
  std::size_t batch_;
  std::int64_t lights_per_batch_;
  std::vector<std::int64_t> light_order_;
};

// Trains epoch after epoch until the validation pixels' loss has not fallen below (1 -
// min_improvement) times its best for `patience` epochs, or for max_epochs; the best epoch's
// weights are kept. Fills the report's epochs and losses.
void TrainWithEarlyStopping(NeuralTrainer& trainer, std::vector<std::int64_t>& training,
                            const std::vector<std::int64_t>& validation, Random& random,
                            const NeuralFitOptions& options, Progress& bar,
                            NeuralFitReport& report) {
  double best = std::numeric_limits<double>::infinity();
  std::vector<torch::Tensor> best_parameters = trainer.Snapshot();
  int stale = 0;
  for (int epoch = 1; epoch <= options.max_epochs; ++epoch) {
    bar.Start(std::isfinite(best) ? fmt::format("neural: epoch {}/{} (validation loss {:.4g})",
                                                epoch, options.max_epochs, best)
                                  : fmt::format("neural: epoch {}/{}", epoch, options.max_epochs),
              trainer.Batches(training.size()));
    const double training_loss = trainer.Epoch(training, random, bar);
    bar.Finish();
    const double validation_loss = trainer.MeanLoss(validation);
    report.epochs = epoch;
    if (validation_loss < best * (1.0 - options.min_improvement)) {
      best = validation_loss;
      best_parameters = trainer.Snapshot();
      report.best_epoch = epoch;
      report.training_loss = training_loss;
      report.validation_loss = validation_loss;
      stale = 0;
    } else if (++stale >= options.patience) {
      break;
    } else if (options.plateau_decay < 1.0) {
      trainer.ScaleLearningRate(options.plateau_decay);
    }
  }
  trainer.Restore(best_parameters);
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
          {"plateau_decay", plateau_decay},
          {"optimiser", "adam"},
          {"sample_pixels", sample_pixels},
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
          {"encoded_pixels", encoded_pixels},
          {"threads", threads},
          {"seconds", seconds},
          {"cpu_seconds", cpu_seconds}};
}

Representation FitNeural(const Observations& observations,
                         const std::vector<LightDirection>& lights, std::span<const int> selected,
                         const NeuralFitOptions& options, const fs::path& source,
                         Progress* progress, NeuralFitReport* report_out) {
  const auto start_time = std::chrono::steady_clock::now();
  const std::clock_t start_cpu = std::clock();
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
  const int threads = options.threads > 0
                          ? options.threads
                          : std::max(1, static_cast<int>(std::thread::hardware_concurrency()));
  torch::set_num_threads(threads);
  torch::manual_seed(options.seed);
  const std::int64_t channels = observations.channels();

  // The sample: a seeded draw of the pixels; its first validation_count are the early-stopping
  // set, the rest train.
  Random random(options.seed);
  const std::int64_t sample_count = std::min<std::int64_t>(options.sample_pixels, m);
  const std::vector<std::int64_t> sample = SamplePixels(m, sample_count, random);
  const TrainingData data = MakeTrainingData(observations, lights, selected, sample,
                                             ObservationScale(observations, selected, source));
  const auto validation_count = std::clamp<std::int64_t>(
      static_cast<std::int64_t>(std::llround(options.validation_fraction * sample_count)), 1,
      sample_count - 1);
  std::vector<std::int64_t> validation(static_cast<std::size_t>(validation_count));
  std::iota(validation.begin(), validation.end(), std::int64_t{0});
  std::vector<std::int64_t> training(static_cast<std::size_t>(sample_count - validation_count));
  std::iota(training.begin(), training.end(), validation_count);

  NeuralTrainer trainer(data, channels, options);
  NeuralFitReport report;
  report.training_pixels = static_cast<int>(training.size());
  report.validation_pixels = static_cast<int>(validation.size());
  TrainWithEarlyStopping(trainer, training, validation, random, options, bar, report);

  // The coefficient maps: every pixel encoded by the kept encoder.
  Image maps(observations.width(), observations.height(), NeuralMapNames(options.coefficients));
  EncodeEveryPixel(trainer.encoder(), observations, selected, data.scale, maps);
  report.encoded_pixels = static_cast<int>(m);
  report.threads = threads;
  report.seconds =
      std::chrono::duration<double>(std::chrono::steady_clock::now() - start_time).count();
  report.cpu_seconds = static_cast<double>(std::clock() - start_cpu) / CLOCKS_PER_SEC;
  if (report_out) *report_out = report;
  auto shading = std::make_shared<NeuralShading>(ToNeuralDecoder(trainer.decoder(), data.scale));
  nlohmann::json details = {{"neural", options.ToJson()}, {"neural_training", report.ToJson()}};
  return Representation("neural", std::move(maps), std::move(shading), std::move(details));
}

}  // namespace photomat
