#include "apps/neural_evaluate_command.h"

#include <fmt/format.h>

#include "apps/cli_main.h"
#include "apps/cli_support.h"
#include "apps/neural_training_options.h"
#include "capture/io/load_photometric_set.h"
#include "core/error.h"
#include "core/json_file.h"
#include "represent/evaluation/evaluation.h"
#include "represent/fitting/prediction_folds.h"
#include "represent/neural/neural_fit.h"

namespace photomat::app {

void AddNeuralEvaluateCommand(CLI::App& app) {
  struct Options {
    SetInputOptions set_input;
    std::string methods;
    std::filesystem::path json;
    int hold_out_every = 0;
    NeuralFitOptions neural;
  };
  auto options = std::make_shared<Options>();
  CLI::App* command = AddListedCommand(app, "evaluate");
  AddSetInputOptions(*command, options->set_input);
  command->add_option("--methods", options->methods, "neural (this program evaluates it alone)")
      ->required();
  command
      ->add_option("--hold-out-every", options->hold_out_every,
                   "One training without the images 0, K, 2K, ..., which it predicts (required: "
                   "a training per image, as leave-one-out needs, would take hours)")
      ->required();
  command->add_option("--json", options->json, "Write the evaluation as JSON");
  AddNeuralTrainingOptions(*command, options->neural);
  command->callback([options] {
    if (options->methods != "neural") {
      throw Error(
          fmt::format("--methods {}: this program evaluates neural only", options->methods));
    }
    if (options->hold_out_every < 2) throw Error("--hold-out-every: expected 2 or more");
    const LoadedSet loaded =
        LoadSetForCommand(options->set_input.input, options->set_input.ToLoadOptions());
    const PhotometricSet& set = loaded.set;
    const Observations observations(set);
    MethodEvaluation evaluation;
    evaluation.method = Method::Parse("neural");
    const PredictionFold fold = PredictionFolds(set.size(), options->hold_out_every).front();
    evaluation.prediction_images = fold.predicted;
    const std::vector<int>& kept = fold.fitted;
    TerminalProgressBar bar;
    NeuralFitReport report;
    const Representation r =
        FitNeural(observations, set.lights(), kept, options->neural, set.source(), &bar, &report);
    // IMPLEMENTER CHOICE: the reconstruction error is that of the same training at the images it
    // saw (a second training on every image would double the time).
    for (int i : kept) {
      evaluation.reconstruction_per_image.push_back(NormalisedRmsError(
          observations, i, RelightObservedPixels(r, observations, set.lights()[i])));
    }
    std::vector<PredictionScores> scores;
    for (int i : evaluation.prediction_images) {
      scores.push_back(ScorePrediction(observations, i,
                                       RelightObservedPixels(r, observations, set.lights()[i])));
    }
    SetPredictionScores(evaluation, scores);
    double reconstruction = 0.0;
    for (double eta : evaluation.reconstruction_per_image) reconstruction += eta;
    evaluation.eta_reconstruction =
        reconstruction / static_cast<double>(evaluation.reconstruction_per_image.size());
    fmt::print("{}", FormatEvaluationTable({evaluation}));
    fmt::print(
        "neural: held out every {} ({} images), PSNR {:.2f} dB; trained {} epochs (best {}) "
        "in {:.1f} s\n",
        options->hold_out_every, evaluation.prediction_images.size(), *evaluation.psnr_prediction,
        report.epochs, report.best_epoch, report.seconds);
    if (!options->json.empty()) {
      // The training's options and summary (the fit's details, as a neural stack holds them), so
      // that a held-out score can be read beside the epochs and time it took.
      nlohmann::json json = EvaluationsToJson({evaluation});
      json["neural"].update(r.details());
      WriteJsonFile(options->json, json);
    }
  });
}

}  // namespace photomat::app
