#include "apps/command_table.h"

#include <array>
#include <stdexcept>
#include <string>

namespace photomat::app {
namespace {

constexpr Component kLiveCapture = Component::kLiveCapture;
constexpr Component kSolids = Component::kSolids;
constexpr Component kSurfacePatterns = Component::kSurfacePatterns;
constexpr Component kNeural = Component::kNeural;

constexpr std::string_view kEvaluateDescription =
    "Measure how well each method relights the captured images: Dong's normalised RMS error for "
    "reconstruction (fit all, relight each) and leave-one-out prediction, and the normal angular "
    "error against ground truth.";
constexpr std::string_view kFitDescription =
    "Fit relightable representations to a photometric set; writes one multi-layer EXR map stack "
    "per method and stacks.json into --out.";

// The programs (apps/CMakeLists.txt): photomat-pipeline holds every command of the core, the
// others one optional component each (or, for calibrate, Ceres).
constexpr std::array kCommands{
    CommandInfo{"generate",
                "Render a synthetic capture with ground truth: a procedural material (height field "
                "and RGB albedo) under known lights. Writes images, manifest.json and "
                "gt_normals/albedo/height.exr.",
                "photomat-pipeline"},
    CommandInfo{"fit", kFitDescription, "photomat-pipeline"},
    CommandInfo{"relight",
                "Render a map stack under new lights. One light (--light) writes one image to "
                "--out; several (--lights, --sweep) write a folder of images with a manifest.json.",
                "photomat-pipeline"},
    CommandInfo{"evaluate", kEvaluateDescription, "photomat-pipeline"},
    CommandInfo{"demo",
                "Run the whole pipeline on the built-in synthetic sample: generate, fit all "
                "methods, evaluate, relight a light sweep, then grow every stack to 4x its area "
                "and relight it.",
                "photomat-pipeline"},
    CommandInfo{"capture",
                "Record a photometric set from a camera while a light controller switches the "
                "lights of a plan. Images and the manifest are written as they come; --resume "
                "continues an interrupted session.",
                "photomat-capture", &kLiveCapture},
    CommandInfo{"devices",
                "List the cameras photomat can capture from: V4L2 devices (/dev/video*) and "
                "libcamera cameras, with their formats and controls.",
                "photomat-capture", &kLiveCapture},
    CommandInfo{"solid",
                "Solid (3D) textures: from 2D views, grown from a solid exemplar, procedural, and "
                "objects carved out of them.",
                "photomat-solid", &kSolids},
    CommandInfo{"rd",
                "Grow a reaction-diffusion pattern on a surface mesh (finite elements; writes a "
                "coloured PLY and glTF, previews, the fields) or on a periodic grid (a tileable "
                "material written as a relightable map stack).",
                "photomat-rd", &kSurfacePatterns},
    CommandInfo{"calibrate",
                "Calibrate a capture: light directions from a mirror sphere, flat-fields from a "
                "matte target, light intensities, camera response; and apply them.",
                "photomat-calibrate"},
    CommandInfo{"export",
                "Write a representation for other tools: with --out, a 16-bit tangent-space normal "
                "map, an sRGB albedo, a height map (EXR and 16-bit PNG), a glTF 2.0 tile and the "
                "stack with its height layer; with --ptm / --rti, a PTM (PTM_1.2) or HSH RTI file.",
                "photomat-pipeline"},
    CommandInfo{"synthesize",
                "Grow a map stack (any method) or a plain image to a new size by image quilting in "
                "R^n (the thesis's modified Efros-Freeman) or pixel-based multiresolution "
                "synthesis (modified Wei-Levoy). Every output pixel copies a whole sample pixel "
                "(all maps together), so the grown stack relights with the sample's light basis.",
                "photomat-pipeline"},
    CommandInfo{"batch",
                "Process a collection: plan a recipe into tasks, run them here or on a Slurm "
                "cluster, follow them, summarise.",
                "photomat-batch"},
};

// `fit --method neural` and `evaluate --methods neural`: the neural basis's training
// (represent/neural, libtorch).
constexpr CommandInfo kNeuralFit{"fit", kFitDescription, "photomat-neural", &kNeural};
constexpr CommandInfo kNeuralEvaluate{"evaluate", kEvaluateDescription, "photomat-neural",
                                      &kNeural};

// Whether `arguments` hold `OPTION neural` or `OPTION=neural`.
bool NamesNeural(std::span<char* const> arguments, std::string_view option) {
  const std::string joined = std::string(option) + "=neural";
  for (std::size_t i = 0; i < arguments.size(); ++i) {
    const std::string_view argument = arguments[i];
    if (argument == joined) return true;
    if (argument == option && i + 1 < arguments.size() &&
        std::string_view(arguments[i + 1]) == "neural") {
      return true;
    }
  }
  return false;
}

}  // namespace

std::span<const CommandInfo> Commands() { return kCommands; }

const CommandInfo* FindCommand(std::string_view name) {
  for (const CommandInfo& command : kCommands) {
    if (command.name == name) return &command;
  }
  return nullptr;
}

const CommandInfo* FindCommandFor(std::span<char* const> arguments) {
  if (arguments.empty()) return nullptr;
  const CommandInfo* command = FindCommand(arguments[0]);
  if (command && command->name == "fit" && NamesNeural(arguments.subspan(1), "--method")) {
    return &kNeuralFit;
  }
  if (command && command->name == "evaluate" && NamesNeural(arguments.subspan(1), "--methods")) {
    return &kNeuralEvaluate;
  }
  return command;
}

std::string_view CommandDescription(std::string_view name) {
  const CommandInfo* command = FindCommand(name);
  if (!command) throw std::out_of_range("no photomat command " + std::string(name));
  return command->description;
}

// PHOTOMAT_WITHOUT_<COMPONENT> (apps/CMakeLists.txt): what was left out and why, as the configure
// summary says it; "" when the component is built.
std::string_view ComponentAbsence(Component component) {
  switch (component) {
    case Component::kLiveCapture:
      return PHOTOMAT_WITHOUT_LIVE_CAPTURE;
    case Component::kSolids:
      return PHOTOMAT_WITHOUT_SOLIDS;
    case Component::kSurfacePatterns:
      return PHOTOMAT_WITHOUT_SURFACE_PATTERNS;
    case Component::kCarving:
      return PHOTOMAT_WITHOUT_CARVING;
    case Component::kNeural:
      return PHOTOMAT_WITHOUT_TORCH;
  }
  return {};
}

std::string BuiltWithout(Component component) {
  return "this photomat was built without " + std::string(ComponentAbsence(component));
}

std::string DescribeInThisBuild(std::string_view description, const Component* component) {
  std::string text(description);
  if (component && !ComponentAbsence(*component).empty()) {
    text += " (not in this build: " + std::string(ComponentAbsence(*component)) + ")";
  }
  return text;
}

std::string_view ProgramDescription() {
  return "photomat: turns photographs of a material sample under many known lights into "
         "relightable material maps.";
}

std::string_view ProgramVersion() { return "photomat 0.1.0"; }

}  // namespace photomat::app
