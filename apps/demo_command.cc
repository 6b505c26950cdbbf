#include "apps/demo_command.h"

#include <fmt/format.h>

#include "apps/cli_main.h"
#include "apps/cli_support.h"
#include "capture/io/capture_manifest.h"
#include "core/image_io.h"
#include "core/json_file.h"
#include "relight/render/relight.h"
#include "relight/web/evaluation_report.h"
#include "relight/web/viewer_export.h"
#include "represent/evaluation/evaluation.h"
#include "represent/fitting/fit.h"
#include "represent/stack/map_stack.h"
#include "synthesize/texture/synthesis.h"

namespace photomat::app {

namespace {

struct DemoCommandOptions {
  std::filesystem::path out = "demo-out";
  int size = 128;
  int sweep = 24;
};

void AddDemoOptions(CLI::App& command, DemoCommandOptions& options) {
  command.add_option("--out", options.out, "Output folder")->capture_default_str();
  command.add_option("--size", options.size, "Sample width and height in pixels")
      ->capture_default_str()
      ->check(CLI::Range(16, 2048));
  command.add_option("--sweep", options.sweep, "Lights in the relit sweep (slant 60)")
      ->capture_default_str()
      ->check(CLI::Range(1, 3600));
}

// 1/4: the built-in bricks sample with shadows, highlights and a little noise.
void GenerateDemoCapture(const std::filesystem::path& capture, int size) {
  GenerateOptions generate;
  generate.material.width = generate.material.height = size;
  generate.material.max_slope_degrees = 45.0;
  generate.render.shadows = true;
  generate.render.specular = 0.25;
  generate.render.noise_sigma = 0.002;
  const int images = WriteSyntheticSet(capture, generate);
  fmt::print("1/4 generate: {} images of a {}x{} bricks sample -> {}\n", images, size, size,
             capture.string());
}

// 2/4: every method's stack, with the fit folder's stacks.json.
std::vector<Representation> FitDemoStacks(const LoadedSet& loaded,
                                          const std::filesystem::path& capture,
                                          const std::filesystem::path& stacks) {
  CreateFolder(stacks);
  std::map<std::string, std::string> files;
  std::vector<Representation> fitted;
  for (const Method& method : AllMethods()) {
    fitted.push_back(Fit(loaded.set, method));
    files[method.Name()] = method.Name() + ".exr";
    SaveRepresentation(stacks / files[method.Name()], fitted.back(),
                       {loaded.set.lights(), "linear", capture.string(), loaded.encodings});
  }
  WriteFitManifest(stacks, capture.string(), files);
  fmt::print("2/4 fit: {} map stacks -> {}\n", files.size(), stacks.string());
  return fitted;
}

// 3/4: every method against the truth, reconstruction and leave-one-out prediction.
std::vector<MethodEvaluation> EvaluateDemo(const LoadedSet& loaded, const Image& truth,
                                           const std::filesystem::path& out, Progress& bar) {
  const Observations observations(loaded.set);
  EvaluationOptions evaluation;
  evaluation.progress = &bar;
  std::vector<MethodEvaluation> results;
  for (const Method& method : AllMethods()) {
    results.push_back(EvaluateMethod(loaded.set, observations, method, &truth, evaluation));
  }
  WriteJsonFile(out / "evaluation.json", EvaluationsToJson(results));
  fmt::print("3/4 evaluate -> {}\n{}", (out / "evaluation.json").string(),
             FormatEvaluationTable(results));
  return results;
}

// Synthesis (issue 4): each stack grown to twice the sample's side (4x its area) by quilting its
// own maps (the thesis's five pipelines, table 6.2.1), tileable, then relit under the same sweep
// with the sample's light basis.
void GrowDemoStacks(const std::vector<Representation>& fitted, const LoadedSet& loaded,
                    const std::filesystem::path& capture, const std::vector<LightDirection>& sweep,
                    int size, const std::filesystem::path& out, Progress& bar) {
  const std::filesystem::path grown_folder = out / "synthesis";
  CreateFolder(grown_folder);
  SynthesisOptions synthesis;
  synthesis.target = {2 * size, 2 * size, true, 1};
  for (const Representation& representation : fitted) {
    const Representation grown = Synthesize(representation, synthesis, &bar);
    SaveRepresentation(grown_folder / (representation.method() + ".exr"), grown,
                       {loaded.set.lights(), "linear", "synthesised from " + capture.string()});
    WriteRelitSet(grown_folder / "relit" / representation.method(), grown, sweep, {}, &bar);
  }
  fmt::print(
      "+ synthesize: {} stacks grown from {}x{} to {}x{} (tileable quilting) and relit -> "
      "{}\n",
      fitted.size(), size, size, 2 * size, 2 * size, grown_folder.string());
}

// The evaluation report and the web viewer of every stack.
void WriteDemoPages(const LoadedSet& loaded, const std::vector<MethodEvaluation>& results,
                    const Image& truth, const std::vector<Representation>& fitted,
                    const std::filesystem::path& out, Progress& bar) {
  EvaluationReportOptions report;
  report.title = "photomat demo: evaluation of the built-in bricks sample";
  report.progress = &bar;
  WriteEvaluationReport(out / "report", loaded.set, results, &truth, report);
  ViewerExportOptions viewer;
  viewer.title = "photomat demo: bricks sample";
  viewer.capture_lights = loaded.set.lights();
  viewer.progress = &bar;
  ExportViewer(out / "viewer", fitted, viewer);
  fmt::print(
      "report: open {} in a browser\n"
      "viewer: serve {} with any static file server and open it, e.g.\n"
      "        python3 -m http.server --directory {} 8000   then   http://localhost:8000/\n",
      (out / "report" / "index.html").string(), (out / "viewer").string(),
      (out / "viewer").string());
}

void RunDemo(const DemoCommandOptions& options) {
  const std::filesystem::path& out = options.out;
  const std::filesystem::path capture = out / "capture";
  GenerateDemoCapture(capture, options.size);
  const LoadedSet loaded = LoadSetForCommand(capture, {});
  const Image truth = ReadImage(*loaded.ground_truth_normals).image;
  const std::vector<Representation> fitted = FitDemoStacks(loaded, capture, out / "stacks");
  TerminalProgressBar bar;
  const std::vector<MethodEvaluation> results = EvaluateDemo(loaded, truth, out, bar);
  const auto sweep = LightSweep(options.sweep, 60.0);
  for (const Representation& representation : fitted) {
    WriteRelitSet(out / "relit" / representation.method(), representation, sweep, {}, &bar);
  }
  fmt::print("4/4 relight: {} lights at slant 60 per method -> {}\n", sweep.size(),
             (out / "relit").string());
  GrowDemoStacks(fitted, loaded, capture, sweep, options.size, out, bar);
  WriteDemoPages(loaded, results, truth, fitted, out, bar);
}

}  // namespace

// The main job on the built-in sample: generate a capture with shadows and highlights, fit every
// method, evaluate them against the truth, and relight each under a light circling the sample.
void AddDemoCommand(CLI::App& app) {
  BindCommand(*AddListedCommand(app, "demo"), AddDemoOptions, RunDemo);
}

}  // namespace photomat::app
