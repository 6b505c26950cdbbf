#include "apps/evaluate_command.h"

#include <fmt/format.h>
#include <fmt/ranges.h>

#include <algorithm>
#include <charconv>
#include <filesystem>
#include <functional>
#include <memory>
#include <optional>
#include <span>
#include <vector>

#include "apps/cli_main.h"
#include "apps/cli_support.h"
#include "apps/light_profile_cli.h"
#include "apps/robust_support.h"
#include "apps/streamed_capture.h"
#include "apps/synthesis_cli.h"
#include "capture/io/streamed_set.h"
#include "core/error.h"
#include "core/image_io.h"
#include "core/json_file.h"
#include "core/memory_limits.h"
#include "core/scratch_folder.h"
#include "relight/web/evaluation_report.h"
#include "relight/web/published_name.h"
#include "represent/evaluation/evaluation.h"
#include "represent/evaluation/method_comparison.h"
#include "represent/evaluation/streamed_evaluation.h"
#include "represent/fitting/prediction_folds.h"
#include "represent/stack/map_stack.h"
#include "represent/stack/stack_band_reader.h"
#include "represent/streaming/fitted_stack_writer.h"
#include "represent/streaming/streamed_fit.h"
#include "represent/streaming/streamed_folds.h"

namespace photomat::app {
namespace {

// "3,17,40": image indices for the report; empty: none given.
std::vector<int> ParseIndexList(const std::string& text) {
  std::vector<int> indices;
  std::size_t start = 0;
  while (start < text.size()) {
    const std::size_t comma = std::min(text.find(',', start), text.size());
    const std::string item = text.substr(start, comma - start);
    int index = -1;
    const auto [end, ec] = std::from_chars(item.data(), item.data() + item.size(), index);
    if (ec != std::errc() || end != item.data() + item.size() || index < 0) {
      throw Error(fmt::format("\"{}\": expected image indices, e.g. 0,12,30", text));
    }
    indices.push_back(index);
    start = comma + 1;
  }
  return indices;
}

// The ground-truth normals: --gt-normals, else the ones the input names.
std::optional<std::filesystem::path> TruthPath(const std::filesystem::path& given,
                                               const std::optional<std::filesystem::path>& named) {
  return given.empty() ? named : std::optional(given);
}

// The methods fitted alike (`members` their places in the evaluation's list): pbr with robust
// options of its own (`evaluate` fits it as `fit` does, robustly with its --pbr-* options, with
// or without --robust), the others least squares or with the evaluation's robust options.
struct FitGroup {
  std::vector<std::size_t> members;
  std::vector<Method> methods;
  std::optional<RobustFitOptions> robust;
};

std::vector<FitGroup> FitGroups(const std::vector<Method>& methods,
                                const std::optional<RobustFitOptions>& robust,
                                const RobustFitOptions& pbr_robust) {
  FitGroup others{{}, {}, robust}, pbr{{}, {}, pbr_robust};
  for (std::size_t m = 0; m < methods.size(); ++m) {
    FitGroup& group = methods[m].kind == Method::Kind::kPbr ? pbr : others;
    group.members.push_back(m);
    group.methods.push_back(methods[m]);
  }
  std::vector<FitGroup> groups;
  for (FitGroup* group : {&others, &pbr}) {
    if (!group->methods.empty()) groups.push_back(std::move(*group));
  }
  return groups;
}

// A group's prediction (PredictStreamed) and its fit of every image, made in the same passes
// over the photographs (StreamedPredictionOptions::whole_set_fit), written into scratch stacks in
// `folder` as FitIntoFolder writes them. The predictions go to `results` at the group's places.
// Returns the stacks in the group's order.
std::vector<std::filesystem::path> PredictAndFitIntoFolder(StreamedSet& set, const FitGroup& group,
                                                           StreamedPredictionOptions predict,
                                                           const std::filesystem::path& folder,
                                                           std::vector<MethodEvaluation>& results,
                                                           bool warn_clipped) {
  StreamedFitOptions fit;  // the stacks' compression and provenance, as FitIntoFolder's
  const std::vector<std::filesystem::path> stacks =
      PlanScratchStacks(set, group.methods, folder, set.source().string(), fit);
  std::vector<std::unique_ptr<FittedStackWriter>> writers;
  std::vector<std::string> names;
  for (std::size_t i = 0; i < stacks.size(); ++i) {
    writers.push_back(std::make_unique<FittedStackWriter>(stacks[i], set.width(), set.height(),
                                                          fit.compression, fit.provenance));
    names.push_back(group.methods[i].Name());
  }
  predict.robust = group.robust;
  predict.whole_set_fit = [&](std::size_t i, int first_row, const Representation& band) {
    writers[i]->Write(first_row, band);
  };
  std::vector<MethodEvaluation> predicted(group.methods.size());
  PredictStreamed(set, group.methods, predicted, predict);
  for (auto& writer : writers) writer->Commit();
  for (std::size_t i = 0; i < group.members.size(); ++i) {
    results[group.members[i]] = std::move(predicted[i]);
  }
  if (warn_clipped) WarnAboutClippedPixels(set.SaturatedPixels(), set.image_names());
  fmt::print("fitted {} to the {} photographs (linear) in the prediction's passes\n",
             fmt::join(names, ", "), set.size());
  return stacks;
}

// `evaluate INPUT --stream` (README "Streamed relighting and export"): `methods` fitted to `set`
// in bands into scratch stacks, then all evaluated against the set streamed in one pass
// (EvaluateStacksStreamed): the same eta of reconstruction as the in-memory evaluation to float
// rounding, and the same normal errors. With `prediction`, the folds are fitted band by band
// (PredictStreamed: the same eta and PSNR of prediction) and the fit of every image is made in
// the same passes (PredictAndFitIntoFolder); without, the stacks are a streamed fit's
// (FitIntoFolder). Each group of FitGroups is fitted in passes of its own. `use(results, stacks)`
// then gets the evaluations and the scratch stacks (a report is drawn from them).
// IMPLEMENTER CHOICE: the scratch folder is beside `output` (the JSON or report the user chose a
// place for), else in the current folder; its free space is checked first, and it is removed
// however the evaluation ends.
using UseStreamedEvaluations = std::function<void(const std::vector<MethodEvaluation>&,
                                                  std::span<const std::filesystem::path>)>;
void EvaluateSetStreamed(StreamedSet& set, const std::vector<Method>& methods,
                         StreamedEvaluationOptions options, const std::vector<FitGroup>& groups,
                         const std::optional<StreamedPredictionOptions>& prediction,
                         const std::filesystem::path& output, const UseStreamedEvaluations& use) {
  const std::filesystem::path beside = output.empty() || output.parent_path().empty()
                                           ? std::filesystem::path(".")
                                           : output.parent_path();
  CreateFolder(beside);
  TerminalProgressBar bar;
  std::vector<MethodEvaluation> results(methods.size());
  if (prediction) {
    // Every group's folds checked first: a fold too small for a method fails before any pass.
    const std::vector<PredictionFold> folds =
        PredictionFolds(set.size(), prediction->hold_out_every);
    for (const Method& method : methods) CheckFoldsFit(folds, method, set.source());
  }
  const ScratchFolder scratch(beside, "photomat-evaluate");
  std::vector<std::filesystem::path> stacks(methods.size());
  for (const FitGroup& group : groups) {
    const bool first = &group == &groups.front();
    std::vector<std::filesystem::path> fitted;
    if (prediction) {
      StreamedPredictionOptions predict = *prediction;
      predict.progress = &bar;
      fitted = PredictAndFitIntoFolder(set, group, predict, scratch.path(), results, first);
    } else {
      StreamedFitOptions fit;
      fit.memory_bytes = options.memory_bytes;
      fit.progress = &bar;
      fit.robust = group.robust.has_value();
      if (group.robust) fit.robust_options = *group.robust;
      fitted = FitIntoFolder(set, group.methods, scratch.path(), set.source().string(), fit,
                             /*warn_clipped=*/first);
    }
    for (std::size_t i = 0; i < group.members.size(); ++i) stacks[group.members[i]] = fitted[i];
  }
  options.progress = &bar;
  std::vector<StackBandReader> readers;
  std::vector<StackBandReader*> open;
  readers.reserve(stacks.size());
  for (const std::filesystem::path& stack : stacks) open.push_back(&readers.emplace_back(stack));
  std::vector<MethodEvaluation> reconstructions = EvaluateStacksStreamed(set, open, options);
  for (std::size_t i = 0; i < methods.size(); ++i) {
    MethodEvaluation& reconstruction = reconstructions[i];
    results[i].method = methods[i];
    results[i].eta_reconstruction = reconstruction.eta_reconstruction;
    results[i].reconstruction_per_image = std::move(reconstruction.reconstruction_per_image);
    results[i].normals = reconstruction.normals;
  }
  use(results, stacks);
}

// --report-images checked against the set before the evaluation, which can take minutes.
void CheckReportImages(const std::vector<int>& images, int set_size) {
  for (int index : images) {
    if (index >= set_size) {
      throw Error(fmt::format("--report-images: image {} is not in the set (0 to {})", index,
                              set_size - 1));
    }
  }
}

EvaluationReportOptions ReportOptions(const std::filesystem::path& input,
                                      const std::vector<int>& images,
                                      const std::optional<RobustFitOptions>& robust,
                                      const RobustFitOptions& pbr_robust,
                                      const std::optional<MethodComparison>& comparison,
                                      Progress& progress) {
  EvaluationReportOptions report;
  report.title = fmt::format("photomat evaluation of {}", PublishedName(input));
  report.images = images;
  report.robust = robust;
  report.pbr_robust = pbr_robust;
  report.comparison = comparison;
  report.progress = &progress;
  return report;
}

// Prints `heading` and the table of `results` (and, with `ranking`, the ranking of the methods
// over their predicted images by that measure), and writes them to `json` unless it is empty.
// Returns the ranking.
std::optional<MethodComparison> PrintAndSaveEvaluations(
    const std::string& heading, const std::vector<MethodEvaluation>& results,
    std::optional<RankingMeasure> ranking, const std::filesystem::path& json) {
  fmt::print("{}\n{}", heading, FormatEvaluationTable(results));
  std::optional<MethodComparison> comparison;
  if (ranking) {
    comparison = CompareMethods(results, *ranking);
    fmt::print("\n{}", FormatComparisonTable(*comparison));
  }
  if (!json.empty()) {
    nlohmann::json out = EvaluationsToJson(results);
    if (comparison) out["comparison"] = comparison->ToJson();
    WriteJsonFile(json, out);
  }
  return comparison;
}

struct EvaluateCommandOptions {
  std::filesystem::path input;
  std::string methods = "all";
  std::filesystem::path gt_normals;
  std::filesystem::path json;
  std::filesystem::path report;
  std::string report_images;
  bool no_prediction = false;
  bool compare = false;
  std::string rank_by = "eta";
  std::string appearance = "auto";
  int hold_out_every = 0;
  bool literal_rms = false;
  bool raw_intensities = false;
  bool robust = false;
  std::string loss = "cauchy";
  SynthesisEvaluationOptions synthesis;
  LightProfileCli profile;
  std::filesystem::path stack;
  std::size_t memory_mb = 0;
  bool stream = false;
  PbrFitOptions pbr;
};

void AddEvaluateOptions(CLI::App& command, EvaluateCommandOptions& options) {
  command.add_option("input", options.input, "Photometric set (folder, .lp, manifest, DiLiGenT)")
      ->required();
  command.add_option("--methods", options.methods, "Comma-separated methods, or all")
      ->capture_default_str();
  command.add_option("--gt-normals", options.gt_normals,
                     "Float EXR of unit normals (x right, y up, z to camera); default: the one "
                     "the input names (manifest ground_truth, DiLiGenT gt_normals.exr)");
  command.add_option("--json", options.json, "Also write the results as JSON");
  command.add_option("--report", options.report,
                     "Also write an HTML report (table, charts, normal error maps, captured "
                     "beside relit images) into this folder");
  command.add_option("--report-images", options.report_images,
                     "Comma-separated indices of the captured images the report shows beside "
                     "their relighting (default: three spread-out lights)");
  command.add_flag("--no-prediction", options.no_prediction,
                   "Skip leave-one-out prediction (one fit per image)");
  command
      .add_option("--hold-out-every", options.hold_out_every,
                  "Prediction from one fit without every K-th image (0, K, 2K, ...) instead of "
                  "leave-one-out")
      ->check(CLI::PositiveNumber);
  command.add_flag("--compare", options.compare,
                   "Rank the methods over the predicted images: Friedman test, Kendall's W and "
                   "Nemenyi pairwise p-values (printed, in --json as \"comparison\", and in the "
                   "--report)");
  command
      .add_option("--rank-by", options.rank_by,
                  "With --compare: rank by eta (e_k/sigma_k, the thesis's; PSNR ranks alike), "
                  "ssim or delta-e2000 (of the sRGB renderings; streamed, of held-out images only)")
      ->capture_default_str();
  command
      .add_option("--appearance", options.appearance,
                  "The SSIM and colour difference of the predictions: auto (of held-out images, "
                  "and when --rank-by needs them), always (leave-one-out too, in memory only; "
                  "it then takes about twice as long) or never")
      ->check(CLI::IsMember({"auto", "always", "never"}))
      ->capture_default_str();
  command.add_flag("--literal-rms", options.literal_rms,
                   "Use eq. 4.5.1 as printed, (1/NM) sqrt(sum), instead of the RMS");
  command.add_flag("--ignore-intensities", options.raw_intensities,
                   "Do not divide the images by the light intensities the input gives");
  command.add_flag("--robust", options.robust,
                   "Evaluate the robust fits (fit --robust) instead of the least-squares ones");
  command.add_option("--loss", options.loss, "Robust loss: huber, cauchy or tukey")
      ->capture_default_str();
  // Synthesis quality (issue 4): INPUT is then the sample the synthesis was grown from.
  command.add_option("--synthesised", options.synthesis.synthesised,
                     "Score this synthesised stack or image against INPUT, the sample it was "
                     "grown from (a map stack, fit folder or image): nearest-patch distance, "
                     "roughness, wrap and (with --source-map) seam scores");
  command.add_option("--source-map", options.synthesis.source_map,
                     "With --synthesised: the source map `synthesize --save-source-map` wrote");
  command
      .add_option("--patch", options.synthesis.patch_size,
                  "With --synthesised: side of the compared patches")
      ->capture_default_str()
      ->check(CLI::Range(1, 64));
  AddLightProfileOptions(command, options.profile);
  command.add_option("--stack", options.stack,
                     "Evaluate this fitted stack (.exr, or a fit folder with --methods naming one) "
                     "against INPUT, both streamed in bands: the eta of reconstruction only");
  AddBandMemoryOption(command, options.memory_mb,
                      "the bands (with --stack or --stream; a set held whole beyond it is "
                      "evaluated streamed when it can be)",
                      kMinimumEvaluationMemory);
  command.add_flag("--stream", options.stream,
                   "Fit the methods to INPUT in bands into scratch stacks beside --json or "
                   "--report (or in the current folder) and evaluate those streamed, and fit "
                   "the prediction's folds band by band: the same numbers in memory for a "
                   "band, whatever the set's size (the SSIM and colour difference of held-out "
                   "images only); a --report's pictures are drawn band by band");
  AddPbrOptions(command, options.pbr);
}

LoadOptions LoadOptionsOf(const EvaluateCommandOptions& options) {
  LoadOptions load;
  load.apply_intensities = !options.raw_intensities;
  return load;
}

// `evaluate INPUT --stack STACK`: a fitted stack against its set, streamed (README, "Streamed
// relighting and export").
void EvaluateStackCommand(const EvaluateCommandOptions& options) {
  StreamedSet set = OpenStreamedSet(options.input, LoadOptionsOf(options));
  const std::optional<std::string> method =
      options.methods == "all" ? std::nullopt : std::optional(options.methods);
  StackBandReader stack(ResolveStack(options.stack, method));
  TerminalProgressBar bar;
  StreamedEvaluationOptions streamed;
  streamed.memory_bytes = options.memory_mb << 20;
  streamed.literal_thesis_rms = options.literal_rms;
  streamed.ground_truth_normals = TruthPath(options.gt_normals, set.ground_truth_normals());
  streamed.progress = &bar;
  const std::vector<MethodEvaluation> results = {EvaluateStackStreamed(set, stack, streamed)};
  fmt::print("{} images, stack {} (streamed)\n{}", set.size(), stack.path().string(),
             FormatEvaluationTable(results));
  if (!options.json.empty()) WriteJsonFile(options.json, EvaluationsToJson(results));
}

// What the options ask of a fit-and-evaluate run, checked before it starts (it can take
// minutes; the checks that need the set come in RunEvaluate).
struct EvaluationRequest {
  std::vector<Method> methods;
  RankingMeasure measure = RankingMeasure::kEta;
  std::optional<RankingMeasure> ranking;  // with --compare
  bool appearance = false;                // the predictions' SSIM and colour difference
  std::vector<int> report_images;
  bool pbr_asked = false;
};

EvaluationRequest CheckedRequest(const EvaluateCommandOptions& options) {
  EvaluationRequest request;
  request.methods = ParseMethodList(options.methods);
  ApplyLightProfileOptions(options.profile, request.methods);
  request.pbr_asked = std::any_of(request.methods.begin(), request.methods.end(),
                                  [](const Method& m) { return m.kind == Method::Kind::kPbr; });
  if (options.hold_out_every > 0 && options.no_prediction) {
    throw Error(
        "--hold-out-every chooses the predicted images: it does not go with --no-prediction");
  }
  if (options.compare && (options.no_prediction || request.methods.size() < 2)) {
    throw Error(
        "--compare ranks two or more methods by their prediction errors: it needs --methods "
        "with at least two methods and does not go with --no-prediction");
  }
  request.measure = ParseRankingMeasure(options.rank_by);
  if (!options.compare && request.measure != RankingMeasure::kEta) {
    throw Error("--rank-by chooses the measure of --compare's ranking: add --compare");
  }
  if (options.compare) request.ranking = request.measure;
  // IMPLEMENTER CHOICE: by default the SSIM and colour difference where few images are
  // predicted (held out) and where the ranking needs them; they cost about as much as a cheap
  // method's folds (EvaluationOptions::appearance).
  if (options.appearance == "never" && request.measure != RankingMeasure::kEta) {
    throw Error(
        fmt::format("--rank-by {} needs the SSIM and colour difference: not with "
                    "--appearance never",
                    RankingMeasureName(request.measure)));
  }
  request.appearance = options.appearance == "always" ||
                       (options.appearance == "auto" &&
                        (options.hold_out_every > 0 || request.measure != RankingMeasure::kEta));
  request.report_images = ParseIndexList(options.report_images);
  return request;
}

// `evaluate --stream`, or a set too large to hold: fitted and evaluated band by band.
void EvaluateStreamedCommand(const EvaluateCommandOptions& options,
                             const EvaluationRequest& request, StreamedSet& set) {
  // Checked before the evaluation, which can take hours at this size: streamed, the SSIM and
  // colour difference are measured for held-out images only.
  if (options.hold_out_every == 0 && request.appearance) {
    throw Error(set.source(),
                fmt::format("{}: the streamed evaluation ({}) measures the SSIM and colour "
                            "difference of held-out images only (--hold-out-every K); "
                            "leave-one-out in memory (--memory MB) measures them for every "
                            "image",
                            request.measure != RankingMeasure::kEta
                                ? fmt::format("--rank-by {}", RankingMeasureName(request.measure))
                                : std::string("--appearance always"),
                            options.stream ? "--stream" : "the set exceeds the memory budget"));
  }
  StreamedEvaluationOptions streamed;
  streamed.memory_bytes = options.memory_mb << 20;
  streamed.literal_thesis_rms = options.literal_rms;
  streamed.ground_truth_normals = TruthPath(options.gt_normals, set.ground_truth_normals());
  // The measured masks are found per band (StreamedFitOptions, FoldFitOptions).
  const std::vector<Mask> found_per_band;
  std::optional<RobustFitOptions> robust;
  if (options.robust) robust = RobustOptionsFromCommandLine(options.loss, found_per_band);
  RobustFitOptions pbr_robust = RobustOptionsFromCommandLine(options.loss, found_per_band);
  pbr_robust.pbr = options.pbr;
  std::optional<StreamedPredictionOptions> prediction;
  if (!options.no_prediction) {
    prediction.emplace();
    prediction->memory_bytes = streamed.memory_bytes;
    prediction->hold_out_every = options.hold_out_every;
    prediction->literal_thesis_rms = options.literal_rms;
    prediction->robust = robust;
    prediction->appearance = request.appearance;
  }
  const auto print_and_report = [&](const std::vector<MethodEvaluation>& results,
                                    std::span<const std::filesystem::path> stacks) {
    const std::optional<MethodComparison> comparison = PrintAndSaveEvaluations(
        fmt::format("{} images (streamed){}", set.size(),
                    streamed.ground_truth_normals
                        ? fmt::format(", ground truth {}", streamed.ground_truth_normals->string())
                        : ""),
        results, request.ranking, options.json);
    if (options.report.empty()) return;
    TerminalProgressBar bar;
    StreamedReportOptions bands;
    bands.memory_bytes = streamed.memory_bytes;
    WriteEvaluationReportStreamed(
        options.report, set, stacks, results, streamed.ground_truth_normals,
        ReportOptions(options.input, request.report_images, robust, pbr_robust, comparison, bar),
        bands);
    fmt::print("report: {}\n", (options.report / "index.html").string());
  };
  EvaluateSetStreamed(set, request.methods, streamed,
                      FitGroups(request.methods, robust, pbr_robust), prediction,
                      options.json.empty() ? options.report : options.json, print_and_report);
}

// The evaluation of a set held in memory (EvaluateMethod per method).
void EvaluateInMemoryCommand(const EvaluateCommandOptions& options,
                             const EvaluationRequest& request) {
  // pbr is fitted as `fit --method pbr` fits it, robustly (its start, the measured masks and
  // the --pbr-* options), with or without --robust.
  const LoadOptions load = LoadOptionsOf(options);
  const RobustInput input = options.robust || request.pbr_asked
                                ? LoadSetForRobustFit(options.input, load)
                                : RobustInput{LoadSetForCommand(options.input, load), {}};
  const LoadedSet& loaded = input.loaded;
  std::optional<Image> truth;
  const auto truth_path = TruthPath(options.gt_normals, loaded.ground_truth_normals);
  if (truth_path) truth = ReadImage(*truth_path).image;
  if (truth && (truth->width() != loaded.set.width() || truth->height() != loaded.set.height())) {
    throw Error(*truth_path,
                fmt::format("normals are {}x{} but the images are {}x{}", truth->width(),
                            truth->height(), loaded.set.width(), loaded.set.height()));
  }
  const Observations observations(loaded.set);
  TerminalProgressBar bar;
  EvaluationOptions evaluation;
  evaluation.prediction = !options.no_prediction;
  evaluation.literal_thesis_rms = options.literal_rms;
  evaluation.hold_out_every = options.hold_out_every;
  evaluation.appearance = request.appearance;
  evaluation.progress = &bar;
  if (options.robust) {
    evaluation.robust = RobustOptionsFromCommandLine(options.loss, input.measured);
  }
  RobustFitOptions pbr_robust = RobustOptionsFromCommandLine(options.loss, input.measured);
  pbr_robust.pbr = options.pbr;
  std::vector<MethodEvaluation> results;
  for (const Method& method : request.methods) {
    EvaluationOptions method_evaluation = evaluation;
    if (method.kind == Method::Kind::kPbr) method_evaluation.robust = pbr_robust;
    results.push_back(EvaluateMethod(loaded.set, observations, method, truth ? &*truth : nullptr,
                                     method_evaluation));
  }
  const std::optional<MethodComparison> comparison = PrintAndSaveEvaluations(
      fmt::format("{} images, {} pixels{}", loaded.set.size(), observations.pixels(),
                  truth ? fmt::format(", ground truth {}", truth_path->string()) : ""),
      results, request.ranking, options.json);
  if (!options.report.empty()) {
    WriteEvaluationReport(options.report, loaded.set, results, truth ? &*truth : nullptr,
                          ReportOptions(options.input, request.report_images, evaluation.robust,
                                        pbr_robust, comparison, bar));
    fmt::print("report: {}\n", (options.report / "index.html").string());
  }
}

void RunEvaluate(EvaluateCommandOptions& options) {
  if (!options.stack.empty()) {
    EvaluateStackCommand(options);
    return;
  }
  if (!options.synthesis.synthesised.empty()) {
    options.synthesis.sample = options.input;
    options.synthesis.json = options.json;
    EvaluateSynthesis(options.synthesis);
    return;
  }
  const EvaluationRequest request = CheckedRequest(options);
  StreamedSet set = OpenStreamedSet(options.input, LoadOptionsOf(options));
  CheckReportImages(request.report_images, set.size());
  if (request.measure == RankingMeasure::kDeltaE2000 && set.channels() != 1 &&
      set.channels() != 3) {
    throw Error(set.source(), fmt::format("--rank-by delta-e2000 needs grey or RGB images, "
                                          "these have {} channels",
                                          set.channels()));
  }
  const std::size_t budget = options.memory_mb > 0 ? options.memory_mb << 20
                                                   : DefaultMemoryBudget(kMinimumEvaluationMemory);
  // IMPLEMENTER CHOICE: as `export` (StreamsCapture), streamed when asked or when the set held
  // whole would not fit the budget.
  if (options.stream || HoldingSetExceeds(set, budget)) {
    EvaluateStreamedCommand(options, request, set);
  } else {
    EvaluateInMemoryCommand(options, request);
  }
}

}  // namespace

void AddEvaluateCommand(CLI::App& app) {
  BindCommand(*AddListedCommand(app, "evaluate"), AddEvaluateOptions, RunEvaluate);
}

}  // namespace photomat::app
