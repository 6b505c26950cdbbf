#include "apps/relight_command.h"

#include <fmt/format.h>

#include "apps/cli_main.h"
#include "apps/cli_support.h"
#include "core/error.h"
#include "relight/formats/stack_file.h"
#include "relight/render/relight.h"
#include "represent/stack/map_stack.h"

namespace photomat::app {

void AddRelightCommand(CLI::App& app) {
  struct Options {
    std::filesystem::path stack;
    std::string method;
    std::string light;
    std::filesystem::path lights;
    std::string sweep;
    std::filesystem::path out;
    std::string format;
    bool clamp = false;
  };
  auto options = std::make_shared<Options>();
  CLI::App* command = AddListedCommand(app, "relight");
  command
      ->add_option("stack", options->stack,
                   "A map stack (.exr), a folder written by `photomat fit`, a .ptm or .rti "
                   "file, or a relight web folder (info.json + plane_N.jpg)")
      ->required();
  command->add_option("--method", options->method, "Which stack of a fit folder");
  auto* light = command->add_option("--light", options->light, "One light: SLANT,TILT in degrees");
  auto* lights = command->add_option("--lights", options->lights,
                                     "Lights from a light file (.lp, manifest.json, DiLiGenT)");
  auto* sweep = command->add_option("--sweep", options->sweep,
                                    "COUNT[,SLANT]: COUNT lights circling at SLANT (default 60)");
  light->excludes(lights)->excludes(sweep);
  lights->excludes(sweep);
  command->add_option("--out", options->out, "Output image (--light) or folder")->required();
  command->add_option("--format", options->format,
                      "png8 (sRGB, default for .png), png16 (linear) or exr (default for .exr)");
  command->add_flag("--clamp", options->clamp, "Clamp negative values (attached shadows) to 0");
  command->callback([options] {
    if (options->light.empty() && options->lights.empty() && options->sweep.empty()) {
      throw Error("give the light(s): --light SLANT,TILT, --lights FILE or --sweep COUNT[,SLANT]");
    }
    const std::optional<std::string> method =
        options->method.empty() ? std::nullopt : std::optional(options->method);
    const LoadedStack stack = LoadStackFile(options->stack, method);
    RelitOutputOptions output;
    output.values = StackValueEncoding(stack.provenance);
    output.relight.clamp_negative = options->clamp;
    if (!options->format.empty()) {
      output.format = ParseRelitFormat(options->format);
    } else if (options->out.extension() == ".exr") {
      output.format = RelitFormat::kExr;
    }
    if (!options->light.empty()) {
      WriteRelitImage(options->out, stack.representation, ParseSlantTilt(options->light), output);
      fmt::print("wrote {}\n", options->out.string());
      return;
    }
    std::vector<LightDirection> directions;
    if (!options->lights.empty()) {
      directions = ReadLightDirections(options->lights);
    } else {
      directions = ParseSweep(options->sweep);
    }
    TerminalProgressBar bar;
    WriteRelitSet(options->out, stack.representation, directions, output, &bar);
    fmt::print("wrote {} images and manifest.json to {}\n", directions.size(),
               options->out.string());
  });
}

}  // namespace photomat::app
