#include "apps/batch/task_plan.h"

#include <OpenImageIO/imageio.h>
#include <fmt/format.h>

#include <algorithm>

#include "capture/io/load_photometric_set.h"
#include "core/digest.h"
#include "core/error.h"
#include "core/image_io.h"
#include "core/json_file.h"
#include "represent/model/method.h"

namespace photomat::batch {
namespace {

namespace fs = std::filesystem;

// The folder of a task's map stacks, which the exports after the fit read.
constexpr char kStacksFolder[] = "stacks";

void Append(std::vector<std::string>& arguments, std::initializer_list<std::string> more) {
  arguments.insert(arguments.end(), more.begin(), more.end());
}

std::vector<std::string> CalibrationArguments(const RecipeCalibration& c, const fs::path& capture) {
  std::vector<std::string> arguments{"calibrate", "apply", capture.string(), "--out", "calibrated"};
  if (c.response) Append(arguments, {"--response", c.response->string()});
  if (c.dark) Append(arguments, {"--dark", c.dark->string()});
  if (c.flat_field) Append(arguments, {"--flat-field", c.flat_field->string()});
  if (c.near_lights) Append(arguments, {"--near-lights", c.near_lights->string()});
  if (c.intensities) Append(arguments, {"--intensities", c.intensities->string()});
  if (c.semi_calibrated) arguments.push_back("--semi-calibrated");
  if (c.ignore_intensities) arguments.push_back("--ignore-intensities");
  if (c.png16) arguments.push_back("--png16");
  return arguments;
}

void AppendRobust(std::vector<std::string>& arguments, const RecipeFit& fit) {
  if (fit.robust) Append(arguments, {"--robust", "--loss", fit.loss});
}

struct CaptureSize {
  std::uint64_t pixels = 0, pixel_images = 0;
};

// Without decoding any image: the light file's count and the first image's header (every layout
// photomat reads keeps one size per capture). Zeros for a broken capture: its task fails with
// photomat's own error.
CaptureSize MeasureCapture(const fs::path& capture) {
  try {
    const std::size_t images = ReadLightDirections(capture).size();
    const std::vector<fs::path> files = ListImageFiles(capture);
    if (files.empty()) return {};
    auto input = OIIO::ImageInput::open(files.front().string());
    if (!input) return {};
    const OIIO::ImageSpec& spec = input->spec();
    const auto pixels = static_cast<std::uint64_t>(spec.width) * spec.height;
    return {pixels, pixels * images};
  } catch (const Error&) {
    return {};
  }
}

std::string Digest(const nlohmann::json& value) {
  const std::string text = value.dump();
  return fmt::format("{:016x}", Digest64(text));
}

nlohmann::json StepsToJson(const std::vector<TaskStep>& steps) {
  nlohmann::json json = nlohmann::json::array();
  for (const TaskStep& step : steps)
    json.push_back({{"name", step.name}, {"arguments", step.arguments}});
  return json;
}

}  // namespace

std::string TaskHash(const Task& task) {
  return Digest({{"capture", task.capture.string()},
                 {"folder", task.folder.string()},
                 {"steps", StepsToJson(task.steps)}});
}

bool StepHoldsWholeSet(const TaskStep& step) {
  // calibrate apply streams whatever it corrects (a target's gain maps band by band, the
  // semi-calibrated intensities from sampled pixels gathered in a first pass).
  if (step.name == "calibrate") return false;
  // Every method is fitted in bands but the neural basis, whose training visits every pixel's
  // profile each epoch (photomat-neural holds the set).
  if (step.name == "fit") {
    const auto methods = std::find(step.arguments.begin(), step.arguments.end(), "--method");
    if (methods == step.arguments.end() || methods + 1 == step.arguments.end()) return false;
    const std::vector<Method> fitted = ParseMethodList(*(methods + 1));
    return std::any_of(fitted.begin(), fitted.end(),
                       [](const Method& m) { return m.kind == Method::Kind::kNeural; });
  }
  // Exports of the stacks read them in bands; from the capture, export --stream fits the
  // photographs in bands first (the interchange files, and maps and viewer without stacks).
  if ((step.name == "maps" || step.name == "viewer") && step.arguments.size() >= 2 &&
      step.arguments[1] == kStacksFolder) {
    return false;
  }
  return std::find(step.arguments.begin(), step.arguments.end(), "--stream") ==
         step.arguments.end();
}

std::vector<TaskStep> TaskSteps(const Recipe& recipe, std::size_t index) {
  const RecipeCapture& capture = recipe.captures.at(index);
  const RecipeExports& exports = recipe.exports;
  std::vector<TaskStep> steps;
  // The photometric set every step reads: the calibrated copy when there is a calibration.
  std::string input = capture.folder.string();
  if (recipe.calibration) {
    steps.push_back({"calibrate", CalibrationArguments(*recipe.calibration, capture.folder)});
    input = "calibrated";
  }
  if (exports.stacks) {
    std::vector<std::string> fit{"fit",   input,        "--method", recipe.fit.methods,
                                 "--out", kStacksFolder};
    AppendRobust(fit, recipe.fit);
    steps.push_back({"fit", fit});
  }
  if (exports.maps) {
    const RecipeMaps& maps = *exports.maps;
    std::vector<std::string> arguments{
        "export", exports.stacks ? kStacksFolder : input, "--method", maps.method, "--out", "maps"};
    Append(arguments, {"--normal-convention", maps.normal_convention, "--height", maps.height});
    // From the capture: fitted in bands (export --stream); the whole-image FFT height then loads
    // the fitted stack, not the set.
    if (!exports.stacks) arguments.push_back("--stream");
    if (!maps.gltf) arguments.push_back("--no-gltf");
    steps.push_back({"maps", arguments});
  }
  if (exports.ptm || exports.rti) {
    // From the photographs, not the stack: .ptm/.rti are fitted to the encoded values as
    // PTMfitter and RTIBuilder do (README, "Interchange files and exports"); streamed, so that
    // the task's memory does not grow with the capture.
    std::vector<std::string> arguments{"export", input, "--stream"};
    if (exports.ptm) {
      Append(arguments, {"--ptm", capture.name + ".ptm"});
      if (!exports.ptm->empty()) Append(arguments, {"--ptm-format", *exports.ptm});
    }
    if (exports.rti) {
      Append(arguments, {"--rti", capture.name + ".rti"});
      if (*exports.rti != 0) Append(arguments, {"--hsh-terms", std::to_string(*exports.rti)});
    }
    steps.push_back({"interchange", arguments});
  }
  if (exports.viewer) {
    std::vector<std::string> arguments{"export", exports.stacks ? kStacksFolder : input, "--viewer",
                                       "viewer"};
    if (!exports.stacks) arguments.push_back("--stream");  // fitted in bands from the capture
    steps.push_back({"viewer", arguments});
  }
  if (exports.evaluation) {
    const RecipeEvaluation& evaluation = *exports.evaluation;
    std::vector<std::string> arguments{"evaluate",         input,    "--methods",
                                       recipe.fit.methods, "--json", "evaluation.json"};
    if (!evaluation.prediction) arguments.push_back("--no-prediction");
    if (evaluation.report) Append(arguments, {"--report", "report"});
    if (evaluation.report && !evaluation.report_images.empty()) {
      Append(arguments,
             {"--report-images", fmt::format("{}", fmt::join(evaluation.report_images, ","))});
    }
    AppendRobust(arguments, recipe.fit);
    // Evaluated streamed, prediction, robust fits and report too (evaluate --stream).
    arguments.push_back("--stream");
    steps.push_back({"evaluate", arguments});
  }
  return steps;
}

TaskPlan PlanTasks(const Recipe& recipe, const PlanOptions& options) {
  TaskPlan plan;
  plan.recipe_file = recipe.file;
  plan.recipe = recipe.source;
  for (std::size_t i = 0; i < recipe.captures.size(); ++i) {
    Task task;
    task.index = static_cast<int>(i);
    task.name = recipe.captures[i].name;
    task.capture = recipe.captures[i].folder;
    task.folder = CaptureOutputFolder(recipe, i);
    task.steps = TaskSteps(recipe, i);
    const CaptureSize size = MeasureCapture(task.capture);
    task.pixels = size.pixels;
    task.pixel_images = size.pixel_images;
    task.large = task.pixel_images > options.large_capture_pixel_images &&
                 std::any_of(task.steps.begin(), task.steps.end(), StepHoldsWholeSet);
    task.hash = TaskHash(task);
    plan.tasks.push_back(std::move(task));
  }
  return plan;
}

void WriteTaskPlan(const fs::path& batch_dir, const TaskPlan& plan) {
  nlohmann::json tasks = nlohmann::json::array();
  for (const Task& task : plan.tasks) {
    tasks.push_back({{"index", task.index},
                     {"name", task.name},
                     {"capture", task.capture.string()},
                     {"folder", task.folder.string()},
                     {"pixels", task.pixels},
                     {"pixel_images", task.pixel_images},
                     {"large", task.large},
                     {"hash", task.hash},
                     {"steps", StepsToJson(task.steps)}});
  }
  WriteJsonFile(batch_dir / kTaskPlanName, {{"format", "photomat-batch-plan"},
                                            {"version", 1},
                                            {"recipe_file", plan.recipe_file.string()},
                                            {"recipe", plan.recipe},
                                            {"tasks", tasks}});
}

TaskPlan ReadTaskPlan(const fs::path& batch_dir) {
  const fs::path file = batch_dir / kTaskPlanName;
  const nlohmann::json document = ReadJsonFile(file);
  const JsonReader root(document, file);
  if (root["format"].String() != "photomat-batch-plan") root["format"].Fail("not a batch plan");
  TaskPlan plan;
  plan.recipe_file = root["recipe_file"].String();
  plan.recipe = root["recipe"].value();
  const JsonReader tasks = root["tasks"];
  for (std::size_t i = 0; i < tasks.ArraySize(); ++i) {
    const JsonReader entry = tasks[i];
    Task task;
    task.index = entry["index"].Integer();
    if (task.index != static_cast<int>(i)) entry["index"].Fail(fmt::format("expected {}", i));
    task.name = entry["name"].String();
    task.capture = entry["capture"].String();
    task.folder = entry["folder"].String();
    // Plans written before "pixels" existed leave it 0 (unknown).
    if (entry.Has("pixels")) task.pixels = static_cast<std::uint64_t>(entry["pixels"].Number());
    task.pixel_images = static_cast<std::uint64_t>(entry["pixel_images"].Number());
    task.large = entry["large"].Boolean();
    task.hash = entry["hash"].String();
    const JsonReader steps = entry["steps"];
    for (std::size_t s = 0; s < steps.ArraySize(); ++s) {
      TaskStep step;
      step.name = steps[s]["name"].String();
      const JsonReader arguments = steps[s]["arguments"];
      for (std::size_t a = 0; a < arguments.ArraySize(); ++a) {
        step.arguments.push_back(arguments[a].String());
      }
      task.steps.push_back(std::move(step));
    }
    if (TaskHash(task) != task.hash)
      entry["hash"].Fail("does not match the task (edited by hand?)");
    plan.tasks.push_back(std::move(task));
  }
  return plan;
}

std::string ShellCommand(const std::string& program, const std::vector<std::string>& arguments) {
  std::string command = program;
  for (const std::string& argument : arguments) {
    const bool plain = !argument.empty() && argument.find_first_not_of(
                                                "abcdefghijklmnopqrstuvwxyzABCDEFGHIJKLMNOPQRSTUVW"
                                                "XYZ0123456789_-+=/.,:@%") == std::string::npos;
    if (plain) {
      command += " " + argument;
      continue;
    }
    std::string quoted = "'";
    for (char c : argument) quoted += c == '\'' ? std::string("'\\''") : std::string(1, c);
    command += " " + quoted + "'";
  }
  return command;
}

}  // namespace photomat::batch
