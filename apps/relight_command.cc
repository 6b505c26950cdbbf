#include "apps/relight_command.h"

#include <fmt/format.h>

#include "apps/cli_main.h"
#include "apps/cli_support.h"
#include "core/disk_space.h"
#include "core/error.h"
#include "relight/formats/stack_file.h"
#include "relight/render/relight.h"
#include "relight/render/streamed_relight.h"
#include "represent/stack/map_stack.h"
#include "represent/stack/stack_band_reader.h"

namespace photomat::app {
namespace {

// The folder the outputs go to: `out` itself for a set, its parent for one image.
std::filesystem::path OutputFolder(const std::filesystem::path& out, bool one_image) {
  if (!one_image) return out;
  return out.has_parent_path() ? out.parent_path() : std::filesystem::path(".");
}

struct RelightCommandOptions {
  std::filesystem::path stack;
  std::string method;
  std::string light;
  std::filesystem::path lights;
  std::string sweep;
  std::filesystem::path out;
  std::string format;
  bool clamp = false;
  std::size_t memory_mb = 0;
};

void AddRelightOptions(CLI::App& command, RelightCommandOptions& options) {
  command
      .add_option("stack", options.stack,
                  "A map stack (.exr), a folder written by `photomat fit`, a compact stack "
                  "folder (export --compact), a .ptm or .rti file, or a relight web folder "
                  "(info.json + plane_N.jpg)")
      ->required();
  command.add_option("--method", options.method, "Which stack of a fit folder");
  auto* light = command.add_option("--light", options.light, "One light: SLANT,TILT in degrees");
  auto* lights = command.add_option("--lights", options.lights,
                                    "Lights from a light file (.lp, manifest.json, DiLiGenT)");
  auto* sweep = command.add_option("--sweep", options.sweep,
                                   "COUNT[,SLANT]: COUNT lights circling at SLANT (default 60)");
  light->excludes(lights)->excludes(sweep);
  lights->excludes(sweep);
  command.add_option("--out", options.out, "Output image (--light) or folder")->required();
  command.add_option("--format", options.format,
                     "png8 (sRGB, default for .png), png16 (linear) or exr (default for .exr)");
  command.add_flag("--clamp", options.clamp, "Clamp negative values (attached shadows) to 0");
  AddBandMemoryOption(command, options.memory_mb, "the bands of a streamed .exr stack",
                      kMinimumRelightMemory);
}

// The lights asked for: one (--light), a light file's, or a sweep.
std::vector<LightDirection> RelightDirections(const RelightCommandOptions& options) {
  if (!options.light.empty()) return {ParseSlantTilt(options.light)};
  if (!options.lights.empty()) return ReadLightDirections(options.lights);
  if (!options.sweep.empty()) return ParseSweep(options.sweep);
  throw Error("give the light(s): --light SLANT,TILT, --lights FILE or --sweep COUNT[,SLANT]");
}

// .ptm and .rti files, compact stack folders and relight's web folders are read whole (README,
// "Streamed relighting and export").
void RelightWholeStack(const RelightCommandOptions& options,
                       const std::optional<std::string>& method,
                       const std::vector<LightDirection>& directions, RelitOutputOptions output,
                       Progress& bar) {
  const bool one_image = !options.light.empty();
  const LoadedStack stack = LoadStackFile(options.stack, method);
  output.values = StackValueEncoding(stack.provenance);
  const Representation& r = stack.representation;
  CheckDiskSpace(OutputFolder(options.out, one_image),
                 RelitOutputBytes(r.width(), r.height(), r.output_channels(),
                                  static_cast<int>(directions.size()), output.format),
                 "relighting");
  if (one_image) {
    WriteRelitImage(options.out, r, directions.front(), output);
    fmt::print("wrote {}\n", options.out.string());
  } else {
    WriteRelitSet(options.out, r, directions, output, &bar);
    fmt::print("wrote {} images and manifest.json to {}\n", directions.size(),
               options.out.string());
  }
}

// A map stack: streamed band by band (README, "Streamed relighting and export").
void RelightStreamedStack(const RelightCommandOptions& options,
                          const std::filesystem::path& stack_path,
                          const std::vector<LightDirection>& directions,
                          const RelitOutputOptions& output, Progress& bar) {
  const bool one_image = !options.light.empty();
  StackBandReader stack(stack_path);
  StreamedRelightOptions streamed;
  streamed.output = output;
  streamed.output.values = StackValueEncoding(stack.header().provenance);
  CheckDiskSpace(OutputFolder(options.out, one_image),
                 RelitOutputBytes(stack.width(), stack.height(),
                                  stack.header().representation.output_channels(),
                                  static_cast<int>(directions.size()), output.format),
                 "relighting");
  streamed.memory_bytes = options.memory_mb << 20;
  streamed.progress = &bar;
  if (one_image) {
    const StreamedRelightReport report =
        WriteRelitImageStreamed(options.out, stack, directions.front(), streamed);
    fmt::print("wrote {} (bands of {} rows)\n", options.out.string(), report.band_rows);
  } else {
    const StreamedRelightReport report =
        WriteRelitSetStreamed(options.out, stack, directions, streamed);
    fmt::print("wrote {} images and manifest.json to {} (bands of {} rows, {} pass{})\n",
               directions.size(), options.out.string(), report.band_rows, report.passes,
               report.passes == 1 ? "" : "es");
  }
}

void RunRelight(const RelightCommandOptions& options) {
  const std::vector<LightDirection> directions = RelightDirections(options);
  const std::optional<std::string> method =
      options.method.empty() ? std::nullopt : std::optional(options.method);
  RelitOutputOptions output;
  output.relight.clamp_negative = options.clamp;
  if (!options.format.empty()) {
    output.format = ParseRelitFormat(options.format);
  } else if (options.out.extension() == ".exr") {
    output.format = RelitFormat::kExr;
  }
  TerminalProgressBar bar;
  const bool interchange = IsReadWholeStackInput(options.stack);
  const std::filesystem::path stack_path =
      interchange ? options.stack : ResolveStack(options.stack, method);
  if (interchange || !IsStreamableStack(stack_path)) {
    RelightWholeStack(options, method, directions, output, bar);
  } else {
    RelightStreamedStack(options, stack_path, directions, output, bar);
  }
}

}  // namespace

void AddRelightCommand(CLI::App& app) {
  BindCommand(*AddListedCommand(app, "relight"), AddRelightOptions, RunRelight);
}

}  // namespace photomat::app
