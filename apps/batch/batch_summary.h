#pragma once

#include <cstdint>
#include <filesystem>
#include <optional>
#include <string>
#include <vector>

#include "apps/batch/task_plan.h"

namespace photomat::batch {

// What a batch produced, per capture: its state, and per method the numbers of its evaluation
// (evaluation.json in the task's folder) where the recipe asked for one.
struct MethodSummary {
  std::string method;
  std::optional<double> eta_reconstruction;
  std::optional<double> eta_prediction;
  std::optional<double> normal_mean_degrees;  // with ground truth only
};

struct TaskSummary {
  int index = 0;
  std::string name;
  std::filesystem::path capture;
  std::filesystem::path folder;
  std::string state;  // "done", "failed" or "not run"
  std::string failed_step;
  std::string error;
  double elapsed_seconds = 0;
  std::int64_t peak_rss_bytes = 0;
  std::vector<MethodSummary> methods;
  // Outputs present in the final folder, for the index's links.
  bool report = false, viewer = false, maps = false;
};

struct BatchSummary {
  std::filesystem::path recipe_file;
  std::vector<TaskSummary> tasks;
  int Count(const std::string& state) const;
};

// Reads the records and evaluations of every task of `plan`.
BatchSummary SummariseBatch(const std::filesystem::path& batch_dir, const TaskPlan& plan);

// The table `batch run` prints: one row per capture and method (capture, state, method, eta,
// normal error, time, peak memory), failed captures with their step and error.
std::string FormatSummaryTable(const BatchSummary& summary);

// DIR/summary.json (the same numbers) and DIR/index.html (the table with relative links to every
// task's report, viewer, maps and log), both written atomically.
void WriteBatchSummary(const std::filesystem::path& batch_dir, const BatchSummary& summary);

// `target` as a relative URL from the folder `from` (percent-encoded, '/' separated).
std::string RelativeLink(const std::filesystem::path& from, const std::filesystem::path& target);

}  // namespace photomat::batch
