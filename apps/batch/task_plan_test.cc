#include "apps/batch/task_plan.h"

#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include "capture/synthetic/synthetic_capture.h"
#include "core/atomic_file.h"
#include "core/error.h"
#include "core/json_file.h"
#include "tests/support/synthetic_sets.h"
#include "tests/support/test_support.h"

namespace photomat::batch {
namespace {

namespace fs = std::filesystem;
using photomat::testing::TempDir;
using ::testing::ElementsAre;
using ::testing::HasSubstr;

using Arguments = std::vector<std::string>;

class TaskPlanTest : public ::testing::Test {
 protected:
  void SetUp() override {
    for (const char* name : {"c2", "c10", "c1"}) fs::create_directories(dir_ / "captures" / name);
    fs::create_directories(dir_ / "flat");
  }

  Recipe Parse(const nlohmann::json& json) const { return ParseRecipe(json, dir_ / "recipe.json"); }

  nlohmann::json Full() const {
    return {{"captures", {{{"glob", "captures/*"}}}},
            {"calibration", {{"flat_field", "flat"}, {"semi_calibrated", true}}},
            {"fit", {{"methods", {"gradient", "ptm"}}, {"robust", true}, {"loss", "tukey"}}},
            {"exports",
             {{"maps", {{"method", "ptm"}, {"normal_convention", "directx"}, {"gltf", false}}},
              {"ptm", true},
              {"rti", {{"terms", 4}}},
              {"viewer", true},
              {"evaluation", {{"prediction", false}, {"report_images", {1, 2}}}}}},
            {"output", {{"folder", "out"}}}};
  }

  TempDir dir_;
};

TEST_F(TaskPlanTest, StepsAreThePhotomatCommandLinesOfTheRecipe) {
  const Recipe recipe = Parse(Full());
  const TaskPlan plan = PlanTasks(recipe);
  ASSERT_EQ(plan.tasks.size(), 3u);
  const Task& task = plan.tasks[0];
  EXPECT_EQ(task.name, "c1");
  EXPECT_EQ(task.folder, (dir_.path() / "out/c1").lexically_normal());
  const std::string capture = (dir_.path() / "captures/c1").lexically_normal().string();
  const std::string flat = (dir_.path() / "flat").lexically_normal().string();
  std::vector<std::string> names;
  for (const TaskStep& step : task.steps) names.push_back(step.name);
  EXPECT_THAT(names, ElementsAre("calibrate", "fit", "maps", "interchange", "viewer", "evaluate"));
  EXPECT_EQ(task.steps[0].arguments,
            (Arguments{"calibrate", "apply", capture, "--out", "calibrated", "--flat-field", flat,
                       "--semi-calibrated"}));
  EXPECT_EQ(task.steps[1].arguments, (Arguments{"fit", "calibrated", "--method", "gradient,ptm",
                                                "--out", "stacks", "--robust", "--loss", "tukey"}));
  EXPECT_EQ(task.steps[2].arguments,
            (Arguments{"export", "stacks", "--method", "ptm", "--out", "maps",
                       "--normal-convention", "directx", "--height", "poisson", "--no-gltf"}));
  EXPECT_EQ(task.steps[3].arguments, (Arguments{"export", "calibrated", "--stream", "--ptm",
                                                "c1.ptm", "--rti", "c1.rti", "--hsh-terms", "4"}));
  EXPECT_EQ(task.steps[4].arguments, (Arguments{"export", "stacks", "--viewer", "viewer"}));
  EXPECT_EQ(task.steps[5].arguments,
            (Arguments{"evaluate", "calibrated", "--methods", "gradient,ptm", "--json",
                       "evaluation.json", "--no-prediction", "--report", "report",
                       "--report-images", "1,2", "--robust", "--loss", "tukey", "--stream"}));
}

TEST_F(TaskPlanTest, WithoutStacksTheExportsReadTheCapture) {
  nlohmann::json json = Full();
  json.erase("calibration");
  json["exports"] = {{"stacks", false}, {"maps", true}, {"viewer", true}};
  const TaskPlan plan = PlanTasks(Parse(json));
  const std::string capture = (dir_.path() / "captures/c1").lexically_normal().string();
  ASSERT_EQ(plan.tasks[0].steps.size(), 2u);
  // Fitted in bands from the capture (export --stream).
  EXPECT_EQ(plan.tasks[0].steps[0].arguments,
            (Arguments{"export", capture, "--method", "gradient", "--out", "maps",
                       "--normal-convention", "opengl", "--height", "poisson", "--stream"}));
  EXPECT_EQ(plan.tasks[0].steps[1].arguments,
            (Arguments{"export", capture, "--viewer", "viewer", "--stream"}));
  // The whole-image FFT height streams too (only the gradient field is held whole).
  json["exports"]["maps"] = {{"height", "fc"}};
  const TaskPlan fc = PlanTasks(Parse(json));
  EXPECT_EQ(fc.tasks[0].steps[0].arguments.back(), "--stream");
  EXPECT_FALSE(StepHoldsWholeSet(fc.tasks[0].steps[0]));
  EXPECT_FALSE(StepHoldsWholeSet(fc.tasks[0].steps[1]));
}

TEST_F(TaskPlanTest, PlanIsDeterministicAndItsHashFollowsTheRecipe) {
  const fs::path a = dir_ / "a", b = dir_ / "b";
  fs::create_directories(a);
  fs::create_directories(b);
  WriteTaskPlan(a, PlanTasks(Parse(Full())));
  WriteTaskPlan(b, PlanTasks(Parse(Full())));
  EXPECT_EQ(ReadTextFile(a / kTaskPlanName), ReadTextFile(b / kTaskPlanName));

  const TaskPlan plan = ReadTaskPlan(a);
  nlohmann::json changed = Full();
  changed["fit"]["methods"] = {"gradient", "ptm", "eigen3"};
  const TaskPlan other = PlanTasks(Parse(changed));
  ASSERT_EQ(plan.tasks.size(), other.tasks.size());
  for (std::size_t i = 0; i < plan.tasks.size(); ++i) {
    EXPECT_EQ(plan.tasks[i].hash, TaskHash(plan.tasks[i]));
    EXPECT_NE(plan.tasks[i].hash, other.tasks[i].hash) << i;
    for (std::size_t j = 0; j < i; ++j) EXPECT_NE(plan.tasks[i].hash, plan.tasks[j].hash);
  }
}

TEST_F(TaskPlanTest, ReadTaskPlanRejectsAnEditedTask) {
  WriteTaskPlan(dir_.path(), PlanTasks(Parse(Full())));
  nlohmann::json json = ReadJsonFile(dir_ / kTaskPlanName);
  json["tasks"][1]["steps"][1]["arguments"][3] = "gradient";
  WriteJsonFile(dir_ / kTaskPlanName, json);
  try {
    ReadTaskPlan(dir_.path());
    FAIL() << "no error";
  } catch (const Error& error) {
    EXPECT_THAT(error.what(),
                HasSubstr(kTaskPlanName + std::string(": tasks[1].hash: does not match")));
  }
}

TEST_F(TaskPlanTest, PixelImagesComeFromTheLightFileAndTheFirstImage) {
  const photomat::testing::SyntheticSet synthetic =
      photomat::testing::LambertianSet(SurfacePattern::kBricks, 20);
  WriteSyntheticCapture(dir_ / "captures/c1", synthetic.material, synthetic.set, {});
  nlohmann::json json = Full();
  json.erase("calibration");
  // The neural basis's training holds the set (photomat-neural); it has no batch evaluation.
  json["fit"]["methods"] = {"neural"};
  json["exports"].erase("evaluation");
  json["exports"].erase("maps");
  PlanOptions options;
  options.large_capture_pixel_images = 20 * 20 * 36 - 1;
  const TaskPlan plan = PlanTasks(Parse(json), options);
  EXPECT_EQ(plan.tasks[0].pixels, 20u * 20u);
  EXPECT_EQ(plan.tasks[0].pixel_images, 20u * 20u * 36u);  // the thesis grid has 36 lights
  EXPECT_TRUE(plan.tasks[0].large);                        // its evaluation holds the whole set
  EXPECT_EQ(plan.tasks[1].pixel_images, 0u);  // an empty folder: unknown, its task will say why
  EXPECT_FALSE(plan.tasks[1].large);
  fs::create_directories(dir_ / "written");
  WriteTaskPlan(dir_ / "written", plan);
  EXPECT_EQ(ReadTaskPlan(dir_ / "written").tasks[0].pixels, 20u * 20u);

  // Only streamed steps (the fit, maps and viewer from the stacks, the .ptm and .rti fitted in
  // bands): not large at any size.
  json["fit"]["methods"] = {"ptm", "eigen6"};
  const TaskPlan streamed = PlanTasks(Parse(json), options);
  EXPECT_EQ(streamed.tasks[0].pixel_images, 20u * 20u * 36u);
  EXPECT_FALSE(streamed.tasks[0].large);
}

TEST_F(TaskPlanTest, StepHoldsWholeSetNamesTheStepsThatDoNotStream) {
  const auto whole_set_steps = [&](const nlohmann::json& json) {
    const TaskPlan plan = PlanTasks(Parse(json));
    std::vector<std::string> names;
    for (const TaskStep& step : plan.tasks[0].steps) {
      if (StepHoldsWholeSet(step)) names.push_back(step.name);
    }
    return names;
  };
  // calibrate apply streams (a target's flat-field and semi-calibrated intensities too), and the
  // interchange files are fitted to the photographs in bands (export --stream), and so is the
  // evaluation with its report.
  nlohmann::json json = Full();
  EXPECT_THAT(whole_set_steps(json), ElementsAre());
  // Without stacks, maps and viewer are made from the capture, streamed too.
  json["exports"]["stacks"] = false;
  EXPECT_THAT(whole_set_steps(json), ElementsAre());
  // The evaluation streams too, with or without prediction and report, robust fits and pbr
  // included (evaluate --stream).
  json = Full();
  json["fit"] = {{"methods", {"gradient", "ptm"}}};
  for (const bool prediction : {false, true}) {
    json["exports"]["evaluation"] = {{"prediction", prediction}, {"report", false}};
    const TaskPlan plan = PlanTasks(Parse(json));
    EXPECT_EQ(plan.tasks[0].steps.back().arguments.back(), "--stream");
    EXPECT_THAT(whole_set_steps(json), ElementsAre());
  }
  json["exports"]["evaluation"] = {{"prediction", true}, {"report", true}};
  EXPECT_THAT(whole_set_steps(json), ElementsAre());
  // Robust fits and robust prediction stream, Eigen-k's, rbf's and bilinear's (imputed over the
  // set, in passes of their own) too.
  json["exports"]["evaluation"] = {{"prediction", true}, {"report", false}};
  json["fit"]["robust"] = true;
  EXPECT_THAT(whole_set_steps(json), ElementsAre());
  json["fit"]["methods"] = {"ptm", "eigen6", "rbf", "bilinear"};
  EXPECT_THAT(whole_set_steps(json), ElementsAre());
  EXPECT_EQ(PlanTasks(Parse(json)).tasks[0].steps.back().arguments.back(), "--stream");
  // The neural basis's training visits every pixel's profile each epoch: the set is held.
  json["exports"].erase("evaluation");
  json["exports"].erase("maps");
  json["fit"] = {{"methods", {"neural"}}};
  EXPECT_THAT(whole_set_steps(json), ElementsAre("fit"));
  json["fit"] = {{"methods", {"gradient", "ptm"}}};
  json["exports"]["evaluation"] = {{"prediction", false}, {"report", false}};
  json["fit"]["methods"] = {"ptm", "pbr"};
  EXPECT_THAT(whole_set_steps(json), ElementsAre());
}

TEST(ShellCommandTest, QuotesWhatAShellWouldSplitOrExpand) {
  EXPECT_EQ(ShellCommand("photomat", {"fit", "/a/b-c_1.2", "--method", "gradient,ptm"}),
            "photomat fit /a/b-c_1.2 --method gradient,ptm");
  EXPECT_EQ(ShellCommand("photomat", {"fit", "my capture", "it's", "$HOME", ""}),
            "photomat fit 'my capture' 'it'\\''s' '$HOME' ''");
}

}  // namespace
}  // namespace photomat::batch
