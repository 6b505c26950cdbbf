#pragma once

#include <cstdint>
#include <filesystem>
#include <nlohmann/json.hpp>
#include <string>
#include <vector>

#include "apps/batch/recipe.h"

namespace photomat::batch {

// One photomat command line of a task: the arguments after `photomat`. Paths inside the task's
// own folder are relative (the step runs with that folder as its working directory), so a step
// writes the same bytes wherever the folder is (its temporary name, then its final one) and a
// person can repeat it by hand: `cd FOLDER && photomat ARGUMENTS`.
struct TaskStep {
  std::string name;  // "calibrate", "fit", "maps", "interchange", "viewer", "evaluate"
  std::vector<std::string> arguments;
};

// Everything one capture needs, independent of every other task.
struct Task {
  int index = 0;
  std::string name;               // the capture's folder name
  std::filesystem::path capture;  // absolute
  std::filesystem::path folder;   // the final output folder, absolute
  std::vector<TaskStep> steps;
  // Pixels (width x height) and pixels x images of the capture, read from its first image's header
  // and its light file at planning time; 0 when that failed (the task itself then reports why).
  std::uint64_t pixels = 0;
  std::uint64_t pixel_images = 0;
  // Over the plan's large-capture threshold with a step that holds every image in memory
  // (StepHoldsWholeSet): its memory grows with pixels x images (README "Large captures").
  bool large = false;
  // Hex digest of what the task does (capture, folder, steps): a done record with another hash
  // belongs to a different recipe, and the task runs again.
  std::string hash;
};

// Whether `step` holds every image of its capture in memory at once (or as much), so that its
// memory grows with pixels x images: the fit of the neural basis, and any step without --stream
// that reads the capture. The other steps stream in bands (README "Streamed fitting", "Streamed
// relighting and export", "Calibration"), among them every other fit, the evaluation and an
// export with --stream (the interchange files, fitted to the photographs in bands): their memory
// does not grow with the number of images.
bool StepHoldsWholeSet(const TaskStep& step);

struct PlanOptions {
  // Pixels x images above which a capture with a step that holds the whole set is large.
  // Default: 5e8, about 13.5 GB at the 27 bytes per pixel and image that an in-memory fit
  // measured, over half of a 24 GB machine.
  std::uint64_t large_capture_pixel_images = 500'000'000;
};

struct TaskPlan {
  std::filesystem::path recipe_file;
  nlohmann::json recipe;  // as read, for the record
  std::vector<Task> tasks;
};

inline constexpr const char* kTaskPlanName = "tasks.json";

// One task per capture, in recipe order; the same recipe always gives the same plan.
TaskPlan PlanTasks(const Recipe& recipe, const PlanOptions& options = {});

// The task's steps for `recipe`'s capture `index` (PlanTasks without reading the capture).
std::vector<TaskStep> TaskSteps(const Recipe& recipe, std::size_t index);

// The digest Task::hash holds for `task`.
std::string TaskHash(const Task& task);

// DIR/tasks.json, written atomically; ReadTaskPlan throws Error naming the file on any fault.
void WriteTaskPlan(const std::filesystem::path& batch_dir, const TaskPlan& plan);
TaskPlan ReadTaskPlan(const std::filesystem::path& batch_dir);

// A step as a person would type it (POSIX shell quoting where needed).
std::string ShellCommand(const std::string& program, const std::vector<std::string>& arguments);

}  // namespace photomat::batch
