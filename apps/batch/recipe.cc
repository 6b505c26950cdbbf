#include "apps/batch/recipe.h"

#include <fmt/format.h>
#include <glob.h>

#include <algorithm>
#include <map>
#include <set>

#include "core/error.h"
#include "core/image_io.h"
#include "core/json_file.h"
#include "represent/model/method.h"

namespace photomat::batch {
namespace {

namespace fs = std::filesystem;

// Every key of the object `reader` holds must be one of `allowed`: a misspelt key would otherwise
// be silently ignored and the collection processed without what it asked for.
void CheckKeys(const JsonReader& reader, const std::vector<std::string>& allowed) {
  if (!reader.value().is_object()) reader.Fail("expected an object");
  for (const auto& [key, value] : reader.value().items()) {
    if (std::find(allowed.begin(), allowed.end(), key) == allowed.end()) {
      reader[key].Fail(fmt::format("unknown key (expected one of: {})", fmt::join(allowed, ", ")));
    }
  }
}

bool OptionalBoolean(const JsonReader& reader, const std::string& key, bool fallback) {
  return reader.Has(key) ? reader[key].Boolean() : fallback;
}

std::string OneOf(const JsonReader& reader, const std::vector<std::string>& choices) {
  const std::string value = reader.String();
  if (std::find(choices.begin(), choices.end(), value) == choices.end()) {
    reader.Fail(fmt::format("\"{}\": expected one of {}", value, fmt::join(choices, ", ")));
  }
  return value;
}

// A path of the recipe, relative to its folder.
fs::path RecipePath(const JsonReader& reader, const fs::path& base) {
  const std::string text = reader.String();
  if (text.empty()) reader.Fail("expected a path, got an empty string");
  const fs::path path(text);
  return (path.is_absolute() ? path : base / path).lexically_normal();
}

fs::path ExistingPath(const JsonReader& reader, const fs::path& base, bool folder) {
  const fs::path path = RecipePath(reader, base);
  std::error_code ec;
  if (!fs::exists(path, ec)) reader.Fail(fmt::format("\"{}\" does not exist", path.string()));
  if (folder && !fs::is_directory(path, ec)) {
    reader.Fail(fmt::format("\"{}\" is not a folder", path.string()));
  }
  if (!folder && fs::is_directory(path, ec)) {
    reader.Fail(fmt::format("\"{}\" is a folder, expected a file", path.string()));
  }
  return path;
}

// glob(3) treats these as pattern characters; the recipe's own folder must match literally.
std::string EscapeGlob(const std::string& text) {
  std::string escaped;
  for (char c : text) {
    if (c == '*' || c == '?' || c == '[' || c == ']' || c == '\\') escaped += '\\';
    escaped += c;
  }
  return escaped;
}

std::vector<fs::path> GlobFolders(const JsonReader& reader, const fs::path& base) {
  const std::string pattern = reader.String();
  if (pattern.empty()) reader.Fail("expected a pattern, got an empty string");
  const std::string full =
      fs::path(pattern).is_absolute() ? pattern : EscapeGlob(base.string()) + "/" + pattern;
  glob_t matches{};
  const int result = glob(full.c_str(), GLOB_ONLYDIR, nullptr, &matches);
  std::vector<fs::path> folders;
  if (result == 0) {
    for (std::size_t i = 0; i < matches.gl_pathc; ++i) {
      std::error_code ec;
      const fs::path path = fs::path(matches.gl_pathv[i]).lexically_normal();
      if (fs::is_directory(path, ec)) folders.push_back(path);
    }
  }
  globfree(&matches);
  if (result != 0 && result != GLOB_NOMATCH)
    reader.Fail(fmt::format("cannot expand \"{}\"", pattern));
  if (folders.empty()) reader.Fail(fmt::format("no folder matches \"{}\"", pattern));
  std::sort(folders.begin(), folders.end(), [](const fs::path& a, const fs::path& b) {
    return NaturalLess(a.string(), b.string());
  });
  return folders;
}

RecipeCapture MakeCapture(fs::path folder) {
  // "captures/coin/" normalises to "captures/coin/" with an empty file name: drop the slash.
  if (folder.filename().empty()) folder = folder.parent_path();
  RecipeCapture capture;
  capture.name = folder.filename().string();
  capture.parent = folder.parent_path().filename().string();
  capture.folder = std::move(folder);
  return capture;
}

std::vector<RecipeCapture> ParseCaptures(const JsonReader& captures, const fs::path& base) {
  if (captures.ArraySize() == 0) captures.Fail("expected at least one capture");
  std::vector<RecipeCapture> result;
  std::map<fs::path, std::string> listed;  // folder -> the entry that listed it
  for (std::size_t i = 0; i < captures.ArraySize(); ++i) {
    const JsonReader entry = captures[i];
    CheckKeys(entry, {"folder", "glob"});
    if (entry.Has("folder") == entry.Has("glob"))
      entry.Fail("expected one of \"folder\" or \"glob\"");
    const std::vector<fs::path> folders =
        entry.Has("folder") ? std::vector{ExistingPath(entry["folder"], base, true)}
                            : GlobFolders(entry["glob"], base);
    for (const fs::path& folder : folders) {
      RecipeCapture capture = MakeCapture(folder);
      const auto [it, added] = listed.emplace(capture.folder, entry.where());
      if (!added) {
        entry.Fail(
            fmt::format("\"{}\" is already listed by {}", capture.folder.string(), it->second));
      }
      result.push_back(std::move(capture));
    }
  }
  return result;
}

RecipeCalibration ParseCalibration(const JsonReader& reader, const fs::path& base) {
  CheckKeys(reader, {"response", "dark", "flat_field", "near_lights", "intensities",
                     "semi_calibrated", "ignore_intensities", "png16"});
  RecipeCalibration calibration;
  if (reader.Has("response")) calibration.response = ExistingPath(reader["response"], base, false);
  if (reader.Has("dark")) calibration.dark = RecipePath(reader["dark"], base);
  if (calibration.dark && !fs::exists(*calibration.dark)) {
    reader["dark"].Fail(fmt::format("\"{}\" does not exist", calibration.dark->string()));
  }
  if (reader.Has("flat_field")) {
    calibration.flat_field = ExistingPath(reader["flat_field"], base, true);
  }
  if (reader.Has("near_lights")) {
    calibration.near_lights = ExistingPath(reader["near_lights"], base, false);
  }
  if (reader.Has("intensities")) {
    calibration.intensities = ExistingPath(reader["intensities"], base, false);
  }
  calibration.semi_calibrated = OptionalBoolean(reader, "semi_calibrated", false);
  calibration.ignore_intensities = OptionalBoolean(reader, "ignore_intensities", false);
  calibration.png16 = OptionalBoolean(reader, "png16", false);
  if (calibration.flat_field && calibration.near_lights) {
    reader["near_lights"].Fail("give at most one of \"flat_field\" and \"near_lights\"");
  }
  if (calibration.intensities && calibration.semi_calibrated) {
    reader["semi_calibrated"].Fail("give at most one of \"intensities\" and \"semi_calibrated\"");
  }
  return calibration;
}

std::vector<std::string> MethodNames(const JsonReader& reader, const std::string& list) {
  try {
    std::vector<std::string> names;
    for (const Method& method : ParseMethodList(list)) names.push_back(method.Name());
    return names;
  } catch (const Error& error) {
    reader.Fail(error.fault());
  }
}

RecipeFit ParseFit(const JsonReader& reader) {
  CheckKeys(reader, {"methods", "robust", "loss"});
  RecipeFit fit;
  const JsonReader methods = reader["methods"];
  if (methods.value().is_array()) {
    if (methods.ArraySize() == 0) methods.Fail("expected at least one method");
    std::vector<std::string> names;
    for (std::size_t i = 0; i < methods.ArraySize(); ++i) {
      const std::string name = methods[i].String();
      MethodNames(methods[i], name);
      names.push_back(name);
    }
    fit.methods = fmt::format("{}", fmt::join(names, ","));
  } else {
    fit.methods = methods.String();
    MethodNames(methods, fit.methods);
  }
  fit.robust = OptionalBoolean(reader, "robust", false);
  if (reader.Has("loss")) {
    if (!fit.robust) reader["loss"].Fail("a loss needs \"robust\": true");
    fit.loss = OneOf(reader["loss"], {"huber", "cauchy", "tukey"});
  }
  return fit;
}

// `true`, `false` or an object of options: whether the export is wanted.
bool Wanted(const JsonReader& exports, const std::string& key) {
  if (!exports.Has(key)) return false;
  const JsonReader value = exports[key];
  if (value.value().is_boolean()) return value.Boolean();
  if (!value.value().is_object()) value.Fail("expected true, false or an object of options");
  return true;
}

RecipeExports ParseExports(const JsonReader& reader, const std::vector<std::string>& fitted) {
  CheckKeys(reader, {"stacks", "maps", "ptm", "rti", "viewer", "evaluation"});
  RecipeExports exports;
  exports.stacks = OptionalBoolean(reader, "stacks", true);
  if (Wanted(reader, "maps")) {
    RecipeMaps maps;
    if (reader["maps"].value().is_object()) {
      const JsonReader options = reader["maps"];
      CheckKeys(options, {"method", "normal_convention", "height", "gltf"});
      if (options.Has("method")) {
        maps.method = options["method"].String();
        const std::vector<std::string> one = MethodNames(options["method"], maps.method);
        if (one.size() != 1) options["method"].Fail("expected one method");
      }
      if (options.Has("normal_convention")) {
        maps.normal_convention = OneOf(options["normal_convention"], {"opengl", "directx"});
      }
      if (options.Has("height")) maps.height = OneOf(options["height"], {"poisson", "fc"});
      maps.gltf = OptionalBoolean(options, "gltf", true);
    }
    // The maps come from the fit's stack of that method, which must then be fitted.
    if (exports.stacks && std::find(fitted.begin(), fitted.end(), maps.method) == fitted.end()) {
      reader["maps"].Fail(fmt::format("method \"{}\" is not among fit.methods ({})", maps.method,
                                      fmt::join(fitted, ",")));
    }
    exports.maps = maps;
  }
  if (Wanted(reader, "ptm")) {
    exports.ptm = "";
    if (reader["ptm"].value().is_object()) {
      CheckKeys(reader["ptm"], {"format"});
      if (reader["ptm"].Has("format"))
        exports.ptm = OneOf(reader["ptm"]["format"], {"rgb", "lrgb"});
    }
  }
  if (Wanted(reader, "rti")) {
    exports.rti = 0;
    if (reader["rti"].value().is_object()) {
      CheckKeys(reader["rti"], {"terms"});
      if (reader["rti"].Has("terms")) {
        const int terms = reader["rti"]["terms"].Integer();
        if (terms != 4 && terms != 9 && terms != 16)
          reader["rti"]["terms"].Fail("expected 4, 9 or 16");
        exports.rti = terms;
      }
    }
  }
  exports.viewer = OptionalBoolean(reader, "viewer", false);
  if (Wanted(reader, "evaluation")) {
    RecipeEvaluation evaluation;
    if (reader["evaluation"].value().is_object()) {
      const JsonReader options = reader["evaluation"];
      CheckKeys(options, {"prediction", "report", "report_images"});
      evaluation.prediction = OptionalBoolean(options, "prediction", true);
      evaluation.report = OptionalBoolean(options, "report", true);
      if (options.Has("report_images")) {
        const JsonReader images = options["report_images"];
        for (std::size_t i = 0; i < images.ArraySize(); ++i) {
          const int index = images[i].Integer();
          if (index < 0) images[i].Fail("expected an image index (0 or more)");
          evaluation.report_images.push_back(index);
        }
      }
    }
    // photomat-neural evaluates the neural basis alone and only on held-out lights
    // (`evaluate --methods neural --hold-out-every K`), not the evaluation a batch asks.
    if (std::find(fitted.begin(), fitted.end(), "neural") != fitted.end()) {
      reader["evaluation"].Fail(
          "the neural basis is evaluated on its own (photomat evaluate CAPTURE --methods neural "
          "--hold-out-every K), not in a batch: leave it out of fit.methods or turn the "
          "evaluation off");
    }
    exports.evaluation = evaluation;
  }
  if (!exports.stacks && !exports.maps && !exports.ptm && !exports.rti && !exports.viewer &&
      !exports.evaluation) {
    reader.Fail("nothing to write: every export is off");
  }
  return exports;
}

// Checks the layout's placeholders; `{name}`, `{parent}` and `{index}` are known.
void CheckLayout(const JsonReader& reader, const std::string& layout) {
  if (layout.empty()) reader.Fail("expected a folder pattern such as \"{name}\"");
  if (fs::path(layout).is_absolute()) reader.Fail("expected a relative folder pattern");
  for (std::size_t open = layout.find('{'); open != std::string::npos;
       open = layout.find('{', open + 1)) {
    const std::size_t close = layout.find('}', open);
    if (close == std::string::npos) reader.Fail(fmt::format("\"{}\": unclosed '{{'", layout));
    const std::string key = layout.substr(open + 1, close - open - 1);
    if (key != "name" && key != "parent" && key != "index") {
      reader.Fail(
          fmt::format("unknown placeholder \"{{{}}}\" (expected {{name}}, {{parent}} or "
                      "{{index}})",
                      key));
    }
  }
  for (const fs::path& part : fs::path(layout)) {
    if (part == "..")
      reader.Fail(fmt::format("\"{}\": \"..\" would leave the output folder", layout));
  }
}

std::string Substitute(std::string text, const std::string& key, const std::string& value) {
  for (std::size_t at = text.find(key); at != std::string::npos;
       at = text.find(key, at + value.size())) {
    text.replace(at, key.size(), value);
  }
  return text;
}

}  // namespace

fs::path CaptureOutputFolder(const Recipe& recipe, std::size_t index) {
  const RecipeCapture& capture = recipe.captures.at(index);
  std::string folder = Substitute(recipe.layout, "{name}", capture.name);
  folder = Substitute(folder, "{parent}", capture.parent);
  folder = Substitute(folder, "{index}", fmt::format("{:04}", index));
  return (recipe.output_folder / folder).lexically_normal();
}

Recipe ParseRecipe(const nlohmann::json& document, const fs::path& file) {
  Recipe recipe;
  recipe.file = fs::absolute(file).lexically_normal();
  recipe.source = document;
  const fs::path base = recipe.file.parent_path();
  const JsonReader root(document, file);
  CheckKeys(root, {"description", "captures", "calibration", "fit", "exports", "output"});
  if (root.Has("description")) root["description"].String();
  recipe.captures = ParseCaptures(root["captures"], base);
  if (root.Has("calibration")) recipe.calibration = ParseCalibration(root["calibration"], base);
  recipe.fit = ParseFit(root["fit"]);
  recipe.exports =
      ParseExports(root["exports"], MethodNames(root["fit"]["methods"], recipe.fit.methods));

  const JsonReader output = root["output"];
  CheckKeys(output, {"folder", "layout"});
  recipe.output_folder = RecipePath(output["folder"], base);
  if (output.Has("layout")) recipe.layout = output["layout"].String();
  CheckLayout(output.Has("layout") ? output["layout"] : output, recipe.layout);
  std::map<fs::path, std::size_t> folders;
  for (std::size_t i = 0; i < recipe.captures.size(); ++i) {
    const fs::path folder = CaptureOutputFolder(recipe, i);
    if (folder == recipe.output_folder) {
      output.Fail(fmt::format("layout \"{}\" puts capture {} in the output folder itself",
                              recipe.layout, recipe.captures[i].folder.string()));
    }
    const auto [it, added] = folders.emplace(folder, i);
    if (!added) {
      (output.Has("layout") ? output["layout"] : output)
          .Fail(fmt::format("\"{}\" gives the same folder {} to captures {} and {}; add {{parent}} "
                            "or {{index}}",
                            recipe.layout, folder.string(),
                            recipe.captures[it->second].folder.string(),
                            recipe.captures[i].folder.string()));
    }
  }
  return recipe;
}

Recipe ReadRecipe(const fs::path& file) { return ParseRecipe(ReadJsonFile(file), file); }

}  // namespace photomat::batch
