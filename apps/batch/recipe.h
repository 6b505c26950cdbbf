#pragma once

#include <filesystem>
#include <nlohmann/json.hpp>
#include <optional>
#include <string>
#include <vector>

namespace photomat::batch {

// A recipe says how to process every capture of a collection (README, "Collections (batch and
// Slurm)", has the schema and an example). Paths in it are relative to the recipe's folder;
// ReadRecipe resolves them, expands the globs and checks everything it can before any task runs,
// with errors naming the recipe file and the key path:
//   recipe.json: captures[2].glob: no folder matches "x/*".

struct RecipeCapture {
  std::filesystem::path folder;  // absolute, lexically normal
  std::string name;              // the folder's name: the {name} of the output layout
  std::string parent;            // its parent folder's name: {parent}
};

// What `photomat calibrate apply` takes; the paths are absolute.
struct RecipeCalibration {
  std::optional<std::filesystem::path> response, dark, flat_field, near_lights, intensities;
  bool semi_calibrated = false;
  bool ignore_intensities = false;
  bool png16 = false;
};

struct RecipeFit {
  std::string methods;  // a --method list, as photomat fit takes it ("gradient,ptm" or "all")
  bool robust = false;
  std::string loss = "cauchy";
};

struct RecipeMaps {
  std::string method = "gradient";
  std::string normal_convention = "opengl";
  std::string height = "poisson";
  bool gltf = true;
};

struct RecipeEvaluation {
  bool prediction = true;
  bool report = true;
  std::vector<int> report_images;  // empty: the report's default
};

struct RecipeExports {
  bool stacks = true;              // the fit's map stacks (every other export reads them)
  std::optional<RecipeMaps> maps;  // photomat export --out maps
  std::optional<std::string> ptm;  // --ptm-format ("" for the default)
  std::optional<int> rti;          // --hsh-terms (0 for the default)
  bool viewer = false;             // photomat export --viewer viewer
  std::optional<RecipeEvaluation> evaluation;  // photomat evaluate --json (and --report)
};

struct Recipe {
  std::filesystem::path file;  // absolute
  nlohmann::json source;       // the recipe as read
  std::vector<RecipeCapture> captures;
  std::optional<RecipeCalibration> calibration;
  RecipeFit fit;
  RecipeExports exports;
  std::filesystem::path output_folder;  // absolute
  std::string layout = "{name}";        // per-capture folder under output_folder
};

// Reads and validates a recipe; every fault is an Error naming the file and the key path.
Recipe ReadRecipe(const std::filesystem::path& file);
// The same for a parsed document (`file` names it in errors and anchors relative paths).
Recipe ParseRecipe(const nlohmann::json& document, const std::filesystem::path& file);

// The folder of one capture under the recipe's output layout ({name}, {parent}, {index}).
std::filesystem::path CaptureOutputFolder(const Recipe& recipe, std::size_t index);

}  // namespace photomat::batch
