#include "apps/neural_fit_command.h"

#include <fmt/format.h>

#include <numeric>

#include "apps/cli_main.h"
#include "apps/cli_support.h"
#include "apps/neural_training_options.h"
#include "capture/io/load_photometric_set.h"
#include "core/colour.h"
#include "core/error.h"
#include "core/image_io.h"
#include "represent/fitting/observations.h"
#include "represent/neural/neural_fit.h"
#include "represent/stack/map_stack.h"

namespace photomat::app {

void AddNeuralFitCommand(CLI::App& app) {
  struct Options {
    SetInputOptions set_input;
    std::string method;
    std::filesystem::path out;
    std::string exr_compression{ToString(kDefaultExrCompression)};
    NeuralFitOptions neural;
  };
  auto options = std::make_shared<Options>();
  CLI::App* command = AddListedCommand(app, "fit");
  AddSetInputOptions(*command, options->set_input);
  command
      ->add_option("--method", options->method,
                   "neural (this program trains the neural basis only; the other methods are "
                   "fitted by `photomat fit` without --method neural)")
      ->required();
  command->add_option("--out", options->out, "Output folder")->required();
  AddNeuralTrainingOptions(*command, options->neural);
  AddExrCompressionOption(*command, options->exr_compression);
  command->callback([options] {
    if (options->method != "neural") {
      throw Error(
          fmt::format("--method {}: this program trains neural only; fit the other "
                      "methods in a separate `photomat fit`",
                      options->method));
    }
    const ExrCompression compression = ParseExrCompression(options->exr_compression);
    const LoadOptions load = options->set_input.ToLoadOptions();
    const std::filesystem::path& input = options->set_input.input;
    // IMPLEMENTER CHOICE: not streamed (README "Streamed fitting"): every epoch visits every
    // pixel's whole profile, so the set is held in memory (DiLiGenT cat: 96 x 3 x 45k masked
    // values, 52 MB).
    const LoadedSet loaded = LoadSetForCommand(input, load);
    const PhotometricSet& set = loaded.set;
    const Observations observations(set);
    std::vector<int> all(set.size());
    std::iota(all.begin(), all.end(), 0);
    TerminalProgressBar bar;
    NeuralFitReport report;
    const Representation r =
        FitNeural(observations, set.lights(), all, options->neural, set.source(), &bar, &report);
    CreateFolder(options->out);
    const std::filesystem::path path = options->out / "neural.exr";
    SaveRepresentation(path, r, {set.lights(), "linear", input.string(), loaded.encodings},
                       compression);
    WriteFitManifest(options->out, input.string(), {{"neural", "neural.exr"}});
    fmt::print(
        "neural: {} epochs (best {}) on {} of {} pixels, validation loss {:.4g}, {:.1f} s wall, "
        "{:.1f} s CPU on {} threads\n",
        report.epochs, report.best_epoch, report.training_pixels, report.encoded_pixels,
        report.validation_loss, report.seconds, report.cpu_seconds, report.threads);
    fmt::print("{:<10} {} maps -> {}\n", "neural", r.maps().channels(), path.string());
  });
}

}  // namespace photomat::app
