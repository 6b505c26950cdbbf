#include "apps/fit_command.h"

#include <fmt/format.h>

#include <algorithm>
#include <numeric>
#include <optional>

#include "apps/cli_main.h"
#include "apps/cli_support.h"
#include "apps/light_profile_cli.h"
#include "apps/robust_support.h"
#include "core/colour.h"
#include "core/error.h"
#include "core/image_io.h"
#include "represent/fitting/fit.h"
#include "represent/stack/map_stack.h"

namespace photomat::app {

void AddFitCommand(CLI::App& app) {
  struct Options {
    std::filesystem::path input;
    std::string methods = "all";
    std::filesystem::path out;
    bool raw_intensities = false;
    std::string colour_space;
    bool robust = false;
    std::string loss = "cauchy";
    std::string exr_compression{ToString(kDefaultExrCompression)};
    PbrFitOptions pbr;
    LightProfileCli profile;
  };
  auto options = std::make_shared<Options>();
  CLI::App* command = AddListedCommand(app, "fit");
  command
      ->add_option("input", options->input,
                   "Photometric set: a folder, a .lp file, a manifest.json or a DiLiGenT folder")
      ->required();
  command
      ->add_option("--method", options->methods,
                   "Method(s): 3i, gradient, ptm, ptm-lrgb, eigenK (eigen3, eigen6, ...), hsh4, "
                   "hsh9, hsh16, pbr (microfacet maps; implies --robust), rbf, bilinear, a "
                   "comma-separated list, "
                   "or all (the first six)")
      ->capture_default_str();
  command->add_option("--out", options->out, "Output folder")->required();
  command->add_flag("--ignore-intensities", options->raw_intensities,
                    "Do not divide the images by the light intensities the input gives");
  command->add_option("--colour-space", options->colour_space,
                      "How untagged integer images encode light: linear or srgb (a file's own "
                      "colour tags come first; default: what the manifest says, else 8-bit "
                      "sRGB, 16-bit linear)");
  command->add_flag("--robust", options->robust,
                    "Robust fits: clipped samples, shadows and highlights get low or zero weight "
                    "(robust photometric stereo; PTM and Eigen-k share its outlier weights)");
  command->add_option("--loss", options->loss, "Robust loss: huber, cauchy or tukey")
      ->capture_default_str();
  AddPbrOptions(*command, options->pbr);
  AddLightProfileOptions(*command, options->profile);
  AddExrCompressionOption(*command, options->exr_compression);
  command->callback([options] {
    std::vector<Method> methods = ParseMethodList(options->methods);
    ApplyLightProfileOptions(options->profile, methods);
    // pbr starts from the robust photometric stereo, and shares its measured masks.
    if (std::any_of(methods.begin(), methods.end(),
                    [](const Method& m) { return m.kind == Method::Kind::kPbr; })) {
      options->robust = true;
    }
    const ExrCompression compression = ParseExrCompression(options->exr_compression);
    LoadOptions load;
    load.apply_intensities = !options->raw_intensities;
    if (!options->colour_space.empty()) {
      load.untagged_colour_space = ParseColourSpace(options->colour_space);
      if (!load.untagged_colour_space) throw Error("--colour-space: expected linear or srgb");
    }
    RobustInput input = options->robust ? LoadSetForRobustFit(options->input, load)
                                        : RobustInput{LoadSetForCommand(options->input, load), {}};
    const LoadedSet& loaded = input.loaded;
    // Robust: one robust fit, whose weights every method shares.
    std::optional<Observations> observations;
    std::optional<RobustFit> robust;
    TerminalProgressBar bar;  // the robust fit's, and the pbr fit's later: outlives both
    if (options->robust) {
      observations.emplace(loaded.set);
      std::vector<int> all(loaded.set.size());
      std::iota(all.begin(), all.end(), 0);
      RobustFitOptions robust_options = RobustOptionsFromCommandLine(options->loss, input.measured);
      robust_options.pbr = options->pbr;
      robust_options.progress = &bar;
      robust.emplace(*observations, loaded.set.lights(), all, robust_options, loaded.set.source());
      fmt::print("{}\n", DescribeRobustFit(robust->summary()));
    }
    CreateFolder(options->out);
    std::map<std::string, std::string> stacks;
    const StackProvenance provenance{loaded.set.lights(), "linear", options->input.string(),
                                     loaded.encodings};
    for (const Method& method : methods) {
      const Representation representation = robust ? robust->Fit(method) : Fit(loaded.set, method);
      const std::string file = method.Name() + ".exr";
      SaveRepresentation(options->out / file, representation, provenance, compression);
      stacks[method.Name()] = file;
      fmt::print("{:<10} {} maps -> {}\n", method.Name(), representation.maps().channels(),
                 (options->out / file).string());
    }
    WriteFitManifest(options->out, options->input.string(), stacks);
  });
}

}  // namespace photomat::app
