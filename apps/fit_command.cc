#include "apps/fit_command.h"

#include <fmt/format.h>

#include <algorithm>
#include <numeric>
#include <optional>

#include "apps/cli_main.h"
#include "apps/cli_support.h"
#include "apps/light_profile_cli.h"
#include "apps/robust_support.h"
#include "capture/io/load_photometric_set.h"
#include "capture/io/streamed_set.h"
#include "core/colour.h"
#include "core/disk_space.h"
#include "core/error.h"
#include "core/image_io.h"
#include "represent/stack/map_stack.h"
#include "represent/streaming/streamed_fit.h"

namespace photomat::app {

void AddFitCommand(CLI::App& app) {
  struct Options {
    SetInputOptions set_input;
    std::string methods = "all";
    std::filesystem::path out;
    bool robust = false;
    std::string loss = "cauchy";
    std::string exr_compression{kAutoExrCompression};
    PbrFitOptions pbr;
    LightProfileCli profile;
    std::size_t memory_mb = 0;
  };
  auto options = std::make_shared<Options>();
  CLI::App* command = AddListedCommand(app, "fit");
  AddSetInputOptions(*command, options->set_input);
  command
      ->add_option("--method", options->methods,
                   "Method(s): 3i, gradient, ptm, ptm-lrgb, eigenK (eigen3, eigen6, ...), hsh4, "
                   "hsh9, hsh16, pbr (microfacet maps; implies --robust), rbf, bilinear, a "
                   "comma-separated list, "
                   "or all (the first six); `--method neural` alone trains the neural basis "
                   "(its own options: `photomat fit --method neural --help`)")
      ->capture_default_str();
  command->add_option("--out", options->out, "Output folder")->required();
  command->add_flag("--robust", options->robust,
                    "Robust fits: clipped samples, shadows and highlights get low or zero weight "
                    "(robust photometric stereo; PTM and Eigen-k share its outlier weights)");
  command->add_option("--loss", options->loss, "Robust loss: huber, cauchy or tukey")
      ->capture_default_str();
  AddPbrOptions(*command, options->pbr);
  AddLightProfileOptions(*command, options->profile);
  AddExrCompressionOption(*command, options->exr_compression, true);
  AddBandMemoryOption(*command, options->memory_mb,
                      "the bands of rows fitted at a time, beyond the decoders' buffers",
                      kMinimumFitMemory);
  command->callback([options] {
    std::vector<Method> methods = ParseMethodList(options->methods);
    ApplyLightProfileOptions(options->profile, methods);
    // pbr starts from the robust photometric stereo, and shares its measured masks.
    if (std::any_of(methods.begin(), methods.end(),
                    [](const Method& m) { return m.kind == Method::Kind::kPbr; })) {
      options->robust = true;
    }
    const LoadOptions load = options->set_input.ToLoadOptions();
    const std::filesystem::path& input = options->set_input.input;
    // Streamed (README, "Streamed fitting"): the images are read band by band and every stack
    // is written band by band, then all renamed into place.
    StreamedSet set = OpenStreamedSet(input, load);
    const std::size_t pixels = static_cast<std::size_t>(set.width()) * set.height();
    const ExrCompression compression = FittedStackCompression(
        options->exr_compression, set.SelectedPixels(0, set.height()) < pixels);
    StreamedFitOptions fit;
    fit.memory_bytes = options->memory_mb << 20;
    fit.robust = options->robust;
    if (options->robust) {
      fit.robust_options = RobustOptionsFromCommandLine(options->loss, {});
      fit.robust_options.measured = {};  // measured per band (StreamedFitOptions)
      fit.robust_options.pbr = options->pbr;
    }
    fit.compression = compression;
    fit.provenance = {set.lights(), "linear", input.string(), set.encodings()};
    TerminalProgressBar bar;
    fit.progress = &bar;
    // Before the folder is made, so that a fit refused for want of space leaves nothing behind.
    CheckDiskSpace(options->out, StreamedStackBytes(set, methods), "the map stacks");
    CreateFolder(options->out);
    std::vector<std::filesystem::path> paths;
    for (const Method& method : methods) paths.push_back(options->out / (method.Name() + ".exr"));
    const StreamedFitReport report = FitStreamed(set, methods, paths, fit);
    WarnAboutClippedPixels(report.saturated_pixels, set.image_names());
    fmt::print("streamed in bands of {} of {} rows, {} pass(es) over the images\n",
               report.band_rows, set.height(), report.passes);
    if (report.robust_summary) fmt::print("{}\n", DescribeRobustFit(*report.robust_summary));
    if (report.pbr_summary) fmt::print("pbr summary: {}\n", report.pbr_summary->ToJson().dump());
    std::map<std::string, std::string> stacks;
    for (std::size_t i = 0; i < methods.size(); ++i) {
      stacks[methods[i].Name()] = paths[i].filename().string();
      fmt::print("{:<10} {} maps -> {}\n", methods[i].Name(), report.map_counts[i],
                 paths[i].string());
    }
    WriteFitManifest(options->out, input.string(), stacks);
  });
}

}  // namespace photomat::app
