#include "apps/batch/recipe.h"

#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include <functional>

#include "core/error.h"
#include "tests/support/test_support.h"

namespace photomat::batch {
namespace {

namespace fs = std::filesystem;
using photomat::testing::TempDir;
using ::testing::HasSubstr;

// A collection folder: captures/a/x, captures/a/y, captures/b/x (two captures named x), an empty
// calibration/flat folder and a recipe that uses them.
class RecipeTest : public ::testing::Test {
 protected:
  void SetUp() override {
    for (const char* folder : {"captures/a/x", "captures/a/y", "captures/a/z10", "captures/a/z9",
                               "captures/b/x", "calibration/flat"}) {
      fs::create_directories(dir_ / folder);
    }
    photomat::testing::WriteFile(dir_ / "captures/a/notes.txt", "not a capture");
    photomat::testing::WriteFile(dir_ / "calibration/dark.exr", "");
  }

  nlohmann::json Valid() const {
    return nlohmann::json::parse(R"({
      "captures": [{"glob": "captures/a/*"}, {"folder": "captures/b/x"}],
      "calibration": {"flat_field": "calibration/flat", "dark": "calibration/dark.exr"},
      "fit": {"methods": ["gradient", "ptm"], "robust": true, "loss": "huber"},
      "exports": {"maps": {"method": "gradient", "height": "fc"}, "ptm": {"format": "rgb"},
                  "rti": {"terms": 16}, "viewer": true,
                  "evaluation": {"prediction": false, "report_images": [0, 5]}},
      "output": {"folder": "processed", "layout": "{parent}/{name}"}
    })");
  }

  fs::path File() const { return dir_ / "recipe.json"; }

  // The error message ParseRecipe gives after `edit` changes the valid recipe.
  std::string ErrorAfter(const std::function<void(nlohmann::json&)>& edit) const {
    nlohmann::json json = Valid();
    edit(json);
    try {
      ParseRecipe(json, File());
    } catch (const Error& error) {
      return error.what();
    }
    return "(no error)";
  }

  TempDir dir_;
};

TEST_F(RecipeTest, ValidRecipeExpandsGlobsInNaturalOrderAndResolvesPaths) {
  const Recipe recipe = ParseRecipe(Valid(), File());
  ASSERT_EQ(recipe.captures.size(), 5u);
  std::vector<std::string> names;
  for (const RecipeCapture& c : recipe.captures) names.push_back(c.parent + "/" + c.name);
  // Folders only (notes.txt is skipped), z9 before z10.
  EXPECT_EQ(names, (std::vector<std::string>{"a/x", "a/y", "a/z9", "a/z10", "b/x"}));
  EXPECT_EQ(recipe.captures[0].folder, (dir_.path() / "captures/a/x").lexically_normal());
  ASSERT_TRUE(recipe.calibration);
  EXPECT_EQ(*recipe.calibration->flat_field, (dir_.path() / "calibration/flat").lexically_normal());
  EXPECT_EQ(recipe.fit.methods, "gradient,ptm");
  EXPECT_TRUE(recipe.fit.robust);
  EXPECT_EQ(recipe.fit.loss, "huber");
  EXPECT_EQ(recipe.exports.maps->height, "fc");
  EXPECT_EQ(*recipe.exports.ptm, "rgb");
  EXPECT_EQ(*recipe.exports.rti, 16);
  EXPECT_FALSE(recipe.exports.evaluation->prediction);
  EXPECT_EQ(recipe.exports.evaluation->report_images, (std::vector<int>{0, 5}));
  EXPECT_EQ(CaptureOutputFolder(recipe, 4), (dir_.path() / "processed/b/x").lexically_normal());
}

TEST_F(RecipeTest, ReadRecipeNamesTheFileForSyntaxErrors) {
  photomat::testing::WriteFile(File(), "{\"captures\": [}");
  try {
    ReadRecipe(File());
    FAIL() << "no error";
  } catch (const Error& error) {
    EXPECT_THAT(error.what(), HasSubstr(File().string() + ": invalid JSON at line 1"));
  }
}

// Each fault is reported as "FILE: KEY PATH: fault".
TEST_F(RecipeTest, EveryErrorNamesTheFileAndTheKey) {
  const std::string file = File().string() + ": ";
  const struct Case {
    std::function<void(nlohmann::json&)> edit;
    std::string expected;
  } cases[] = {
      {[](auto& j) { j.erase("captures"); }, "missing \"captures\""},
      {[](auto& j) { j["captures"] = nlohmann::json::array(); },
       "captures: expected at least one capture"},
      {[](auto& j) { j["captures"][0]["folder"] = "captures/b/x"; },
       "captures[0]: expected one of \"folder\" or \"glob\""},
      {[](auto& j) { j["captures"][1]["folder"] = "nowhere"; },
       "captures[1].folder: \"" + (dir_.path() / "nowhere").string() + "\" does not exist"},
      {[](auto& j) {
         j["captures"].push_back({{"glob", "x/*"}});
       },
       "captures[2].glob: no folder matches \"x/*\""},
      {[](auto& j) {
         j["captures"].push_back({{"folder", "captures/a/y"}});
       },
       "captures[2]: \"" + (dir_.path() / "captures/a/y").string() +
           "\" is already listed by captures[0]"},
      {[](auto& j) { j["captures"][1]["path"] = "x"; }, "captures[1].path: unknown key"},
      {[](auto& j) { j["fitt"] = 1; }, "fitt: unknown key (expected one of: description, captures"},
      {[](auto& j) { j["fit"]["methods"] = "gradient,foo"; },
       "fit.methods: unknown method \"foo\""},
      {[](auto& j) { j["fit"]["methods"][1] = "hsh5"; }, "fit.methods[1]: unknown method \"hsh5\""},
      {[](auto& j) { j["fit"]["methods"] = nlohmann::json::array(); },
       "fit.methods: expected at least one method"},
      {[](auto& j) { j["fit"]["robust"] = false; }, "fit.loss: a loss needs \"robust\": true"},
      {[](auto& j) { j["fit"]["loss"] = "l2"; },
       "fit.loss: \"l2\": expected one of huber, cauchy, tukey"},
      {[](auto& j) { j["fit"]["robust"] = "yes"; }, "fit.robust: expected true or false"},
      {[](auto& j) { j["exports"]["maps"]["method"] = "eigen6"; },
       "exports.maps: method \"eigen6\" is not among fit.methods (gradient,ptm)"},
      {[](auto& j) { j["exports"]["maps"] = 3; },
       "exports.maps: expected true, false or an object"},
      {[](auto& j) { j["exports"]["maps"]["normal_convention"] = "up"; },
       "exports.maps.normal_convention: \"up\": expected one of opengl, directx"},
      {[](auto& j) { j["exports"]["ptm"]["format"] = "lum"; },
       "exports.ptm.format: \"lum\": expected one of rgb, lrgb"},
      {[](auto& j) { j["exports"]["rti"]["terms"] = 5; }, "exports.rti.terms: expected 4, 9 or 16"},
      {[](auto& j) { j["exports"]["evaluation"]["report_images"][1] = -1; },
       "exports.evaluation.report_images[1]: expected an image index"},
      {[](auto& j) { j["exports"]["evaluation"]["reports"] = true; },
       "exports.evaluation.reports: unknown key"},
      {[](auto& j) {
         j["fit"]["methods"] = "neural";
         j["exports"].erase("maps");
       },
       "exports.evaluation: the neural basis is evaluated on its own"},
      {[](auto& j) {
         j["exports"] = {{"stacks", false}, {"viewer", false}};
       },
       "exports: nothing to write"},
      {[](auto& j) { j["calibration"]["flat_field"] = "calibration/none"; },
       "calibration.flat_field: \"" + (dir_.path() / "calibration/none").string() +
           "\" does not exist"},
      {[](auto& j) { j["calibration"]["flat_field"] = "calibration/dark.exr"; },
       "calibration.flat_field: \"" + (dir_.path() / "calibration/dark.exr").string() +
           "\" is not a folder"},
      {[](auto& j) { j["calibration"]["near_lights"] = "calibration/dark.exr"; },
       "calibration.near_lights: give at most one of \"flat_field\" and \"near_lights\""},
      {[](auto& j) { j["output"]["layout"] = "{capture}"; },
       "output.layout: unknown placeholder \"{capture}\""},
      {[](auto& j) { j["output"]["layout"] = "../{name}"; },
       "output.layout: \"../{name}\": \"..\""},
      {[](auto& j) { j["output"]["layout"] = "{name"; }, "output.layout: \"{name\": unclosed"},
      {[](auto& j) { j["output"]["layout"] = "{name}"; },
       "output.layout: \"{name}\" gives the same folder"},
      {[](auto& j) { j["output"].erase("folder"); }, "missing \"folder\" in output"},
  };
  for (const Case& c : cases) {
    const std::string error = ErrorAfter(c.edit);
    EXPECT_THAT(error, HasSubstr(file + c.expected)) << "expected: " << c.expected;
  }
}

TEST_F(RecipeTest, LayoutPlaceholdersAndDefaults) {
  nlohmann::json json = Valid();
  json["output"] = {{"folder", "out"}, {"layout", "{index}-{name}"}};
  json["exports"] = {{"stacks", true}};
  json["fit"] = {{"methods", "all"}};
  json.erase("calibration");
  const Recipe recipe = ParseRecipe(json, File());
  EXPECT_FALSE(recipe.calibration);
  EXPECT_EQ(recipe.fit.methods, "all");
  EXPECT_FALSE(recipe.fit.robust);
  EXPECT_FALSE(recipe.exports.maps || recipe.exports.ptm || recipe.exports.rti ||
               recipe.exports.evaluation || recipe.exports.viewer);
  EXPECT_EQ(CaptureOutputFolder(recipe, 3), (dir_.path() / "out/0003-z10").lexically_normal());
}

}  // namespace
}  // namespace photomat::batch
