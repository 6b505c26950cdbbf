#include "apps/synthesize_command.h"

#include <fmt/format.h>

#include <functional>
#include <optional>

#include "apps/cli_main.h"
#include "apps/cli_support.h"
#include "apps/synthesis_cli.h"
#include "core/error.h"
#include "core/image_io.h"
#include "core/text_parsing.h"
#include "represent/stack/map_stack.h"
#include "synthesize/texture/integrable_projection.h"
#include "synthesize/texture/synthesis.h"

namespace photomat::app {
namespace {

std::vector<double> ParseWeights(const std::string& text) {
  std::vector<double> weights;
  std::size_t start = 0;
  while (start <= text.size()) {
    const std::size_t comma = std::min(text.find(',', start), text.size());
    const auto value = ParseNumber(text.substr(start, comma - start));
    if (!value) throw Error(fmt::format("\"{}\": expected comma-separated weights", text));
    weights.push_back(*value);
    start = comma + 1;
  }
  return weights;
}

struct SynthesizeCommandOptions {
  std::filesystem::path input;
  std::string stack;
  std::string size;
  std::filesystem::path out;
  std::string method = "quilt";
  bool tileable = false;
  std::uint64_t seed = 1;
  std::string metric;
  std::string scaling = "minmax";
  std::string weights;
  QuiltOptions quilt;
  std::string search = "fast";
  bool no_coherence = false;
  bool variety = false;
  PixelSynthesisOptions pixel;
  std::optional<double> force_search;
  std::filesystem::path guide;
  std::filesystem::path source_map;
  std::filesystem::path save_source_map;
  bool integrable = false;
  std::filesystem::path height;
};

void AddSynthesizeOptions(CLI::App& command, SynthesizeCommandOptions& options) {
  command
      .add_option("input", options.input,
                  "A map stack (.exr), a folder written by `photomat fit`, or an image")
      ->required();
  command.add_option("--stack", options.stack, "Which stack of a fit folder (method name)");
  command.add_option("--size", options.size, "Output size WIDTHxHEIGHT")->required();
  command
      .add_option("--out", options.out,
                  "Output: a map stack .exr for stacks; any image format for images")
      ->required();
  command.add_option("--method", options.method, "quilt (default) or pixel")
      ->check(CLI::IsMember({"quilt", "pixel"}));
  command.add_flag("--tileable", options.tileable, "Make the output wrap seamlessly");
  command.add_option("--seed", options.seed, "Random seed")->capture_default_str();
  command.add_option("--metric", options.metric,
                     "Matching error: ssd or sad (default: ssd for quilt, sad for pixel)");
  command
      .add_option("--scaling", options.scaling,
                  "Per-channel normalisation before matching: minmax or zscore")
      ->capture_default_str();
  command.add_option("--weights", options.weights,
                     "Comma-separated weight per map in the matching error (default all 1)");
  command.add_option("--block", options.quilt.block_size,
                     "quilt: block size B (default: a third of the sample, 8..64)");
  command.add_option("--overlap", options.quilt.overlap, "quilt: overlap (default B/4)");
  command
      .add_option("--tolerance", options.quilt.tolerance,
                  "quilt: pick among blocks within (1 + T) of the best error")
      ->capture_default_str();
  command
      .add_option("--error-floor", options.quilt.error_floor,
                  "quilt: the best error counts as at least this many times the sample's "
                  "mean neighbour difference per overlap pixel")
      ->capture_default_str();
  command
      .add_option("--stride", options.quilt.candidate_stride,
                  "quilt: candidate blocks every STRIDE pixels (1 = every offset)")
      ->capture_default_str();
  command
      .add_option("--search", options.search,
                  "fast (exact: FFT correlation or vectorised sums for quilting, pruned sums "
                  "for pixels) or brute (every candidate summed in full); both choose the "
                  "same")
      ->capture_default_str();
  command.add_flag("--variety", options.variety,
                   "quilt: more different pieces of the sample at the cost of more, rougher "
                   "seams (the defaults before issue 18): blocks a quarter of the sample "
                   "(8..64), tolerance 0.1, error floor 1 (--block, --tolerance and "
                   "--error-floor still override)");
  command.add_flag("--no-coherence", options.no_coherence,
                   "quilt: search every block (no neighbour-block reuse)");
  command.add_option("--force-search", options.force_search,
                     "Share of blocks (quilt) or pixels (pixel) searched even when the "
                     "continuation of their neighbours is available (default 0.5)");
  command
      .add_option("--levels", options.pixel.levels,
                  "pixel: pyramid levels above the finest (-1: automatic)")
      ->capture_default_str();
  command
      .add_option("--neighbourhood", options.pixel.neighbourhood,
                  "pixel: odd side of the causal neighbourhood")
      ->capture_default_str();
  command
      .add_option("--parent-neighbourhood", options.pixel.parent_neighbourhood,
                  "pixel: odd side of the parent-level neighbourhood")
      ->capture_default_str();
  command.add_option("--guide", options.guide,
                     "Plan on these maps (a stack or image of the same sample size) and apply "
                     "the plan to the input");
  command.add_option("--source-map", options.source_map,
                     "Apply a saved source map instead of synthesising");
  command.add_option("--save-source-map", options.save_source_map,
                     "Also write the source map (where each output pixel came from)");
  command.add_flag("--integrable", options.integrable,
                   "Gradient stacks: project the grown normals onto the nearest integrable "
                   "field");
  command.add_option("--height", options.height,
                     "Also write the height (Frankot-Chellappa) of the grown normals (EXR)");
}

// What needs normals is checked before the work.
void CheckNormalsNeeded(const SynthesizeCommandOptions& options, const MapsInput& input) {
  if (options.integrable && (!input.stack || !HasNormalMaps(input.stack->representation))) {
    throw Error(input.path,
                "--integrable needs normal maps (normal.X, normal.Y, normal.Z: a "
                "gradient stack)");
  }
  if (!options.height.empty() &&
      (!input.stack || (!HasNormalMaps(input.stack->representation) &&
                        !EstimateNormals(input.stack->representation)))) {
    throw Error(input.path, "--height needs a map stack that gives normals (gradient, 3i, ptm)");
  }
}

// The synthesis the options ask for; `given(name)` says whether the user set an option (the
// --variety preset leaves those alone).
SynthesisOptions SynthesisOptionsFrom(const SynthesizeCommandOptions& options, int width,
                                      int height, const Image& sample,
                                      const std::function<bool(const char*)>& given) {
  SynthesisOptions synthesis;
  synthesis.method = ParseSynthesisMethod(options.method);
  synthesis.target = {width, height, options.tileable, options.seed};
  synthesis.quilt = options.quilt;
  if (options.variety) {
    const QuiltOptions preset = VarietyQuiltOptions(sample.width(), sample.height());
    if (!given("--block")) synthesis.quilt.block_size = preset.block_size;
    if (!given("--tolerance")) synthesis.quilt.tolerance = preset.tolerance;
    if (!given("--error-floor")) synthesis.quilt.error_floor = preset.error_floor;
  }
  synthesis.pixel = options.pixel;
  synthesis.quilt.search = synthesis.pixel.search = ParseSearchMode(options.search);
  synthesis.quilt.coherence = !options.no_coherence;
  MatchingOptions& matching = synthesis.method == SynthesisMethod::kQuilt
                                  ? synthesis.quilt.matching
                                  : synthesis.pixel.matching;
  if (!options.metric.empty()) matching.metric = ParseErrorMetric(options.metric);
  matching.scaling = ParseChannelScaling(options.scaling);
  if (!options.weights.empty()) matching.weights = ParseWeights(options.weights);
  if (options.force_search) {
    synthesis.quilt.forced_search_rate = synthesis.pixel.forced_search_rate = *options.force_search;
  }
  return synthesis;
}

// Where each output pixel comes from: the saved --source-map, or a plan made on the input (or on
// the --guide's maps); checked against the sample's size.
SourceMap SourceMapFor(const SynthesizeCommandOptions& options, const MapsInput& input, int width,
                       int height, const SynthesisOptions& synthesis, nlohmann::json& description) {
  SourceMap map;
  if (!options.source_map.empty()) {
    map = LoadSourceMap(options.source_map);
    description = {{"source_map", options.source_map.string()}};
    if (map.width() != width || map.height() != height) {
      throw Error(options.source_map,
                  fmt::format("the source map is {}x{} but --size asks for {}x{}", map.width(),
                              map.height(), width, height));
    }
  } else {
    std::optional<MapsInput> guide;
    if (!options.guide.empty()) guide = LoadMapsInput(options.guide);
    const Image& planned_on = guide ? guide->image : input.image;
    if (planned_on.width() != input.image.width() || planned_on.height() != input.image.height()) {
      throw Error(options.guide,
                  fmt::format("the guide is {}x{} but the input is {}x{}", planned_on.width(),
                              planned_on.height(), input.image.width(), input.image.height()));
    }
    TerminalProgressBar bar;
    SynthesisPlan plan = PlanSynthesis(planned_on, synthesis, &bar);
    map = std::move(plan.source_map);
    description = std::move(plan.description);
    if (guide) description["guide"] = guide->path.string();
  }
  if (map.sample_width() != input.image.width() || map.sample_height() != input.image.height()) {
    throw Error(options.source_map,
                fmt::format("the source map was made for a {}x{} sample, but {} is {}x{}",
                            map.sample_width(), map.sample_height(), input.path.string(),
                            input.image.width(), input.image.height()));
  }
  return map;
}

// The grown maps written: a plain image, or a stack (with its height and integrable normals
// when asked).
void WriteSynthesised(const SynthesizeCommandOptions& options, const MapsInput& input,
                      const SourceMap& map, const nlohmann::json& description) {
  if (!input.stack) {
    WritePlainMaps(options.out, map.Apply(input.image), input.info);
    fmt::print("wrote {} ({}x{}, {} channels)\n", options.out.string(), map.width(), map.height(),
               input.image.channels());
    return;
  }
  Representation grown = ApplySourceMap(input.stack->representation, map, description);
  if (options.integrable) grown = ProjectNormalsToIntegrable(grown);
  StackProvenance provenance = input.stack->provenance;
  provenance.source = fmt::format("synthesised from {}", input.path.string());
  SaveRepresentation(options.out, grown, provenance);
  fmt::print("wrote {} ({} stack, {}x{}, {} maps)\n", options.out.string(), grown.method(),
             map.width(), map.height(), grown.maps().channels());
  if (!options.height.empty()) {
    WriteImage(options.height, HeightFromRepresentation(grown));
    fmt::print("wrote {}\n", options.height.string());
  }
}

void RunSynthesize(const SynthesizeCommandOptions& options,
                   const std::function<bool(const char*)>& given) {
  const auto [width, height] = ParseSize(options.size);
  const std::optional<std::string> stack_name =
      options.stack.empty() ? std::nullopt : std::optional(options.stack);
  const MapsInput input = LoadMapsInput(options.input, stack_name);
  CheckNormalsNeeded(options, input);
  const SynthesisOptions synthesis =
      SynthesisOptionsFrom(options, width, height, input.image, given);
  nlohmann::json description;
  const SourceMap map = SourceMapFor(options, input, width, height, synthesis, description);
  if (!options.save_source_map.empty()) SaveSourceMap(options.save_source_map, map);
  WriteSynthesised(options, input, map, description);
}

}  // namespace

void AddSynthesizeCommand(CLI::App& app) {
  CLI::App* command = AddListedCommand(app, "synthesize");
  BindCommand(*command, AddSynthesizeOptions, [command](const SynthesizeCommandOptions& options) {
    RunSynthesize(options,
                  [command](const char* name) { return command->get_option(name)->count() > 0; });
  });
}

}  // namespace photomat::app
