#pragma once

#include <filesystem>
#include <string>
#include <vector>

#include "apps/batch/task_plan.h"
#include "apps/batch/task_record.h"

namespace photomat::batch {

// Runs one task: each step is a child process of `photomat` (the same executable), with the
// task's temporary folder (a hidden sibling of its final folder) as working directory. When every
// step succeeded the done record is written into that folder and the folder is renamed to the
// final name (swapped atomically with an earlier result of another recipe), so that the outputs
// and the record appear together or not at all: SIGKILL at any moment leaves either the previous
// state or the finished task, and a leftover temporary folder is removed by the next attempt.
// A task already done is not run again. Throws Error only when the task cannot be attempted at
// all (e.g. it is already running elsewhere); a failing step is a failed record.
struct TaskRunResult {
  TaskRecord record;
  bool skipped = false;  // was already done
};
// `cpus`: the CPUs the steps may run on (empty: this process's).
TaskRunResult RunTask(const std::filesystem::path& batch_dir, const Task& task,
                      const std::filesystem::path& photomat, const std::vector<int>& cpus = {});

struct BatchRunOptions {
  int threads_per_task = 1;
  int workers = 0;                 // 0: the available cores / threads_per_task (at least 1)
  std::filesystem::path photomat;  // empty: this executable
  // Pin each worker's steps to its own threads_per_task cores (TBB then sizes its pool to them).
  // Off by default: on a machine that also runs other work a pinned worker waits for its busy
  // core while another one is free (bench/batch_table: 12.7 s pinned against 8.8 s unpinned for
  // the same batch at load 3).
  bool pin_cpus = false;
};

struct BatchRunResult {
  int tasks = 0;
  int already_done = 0;
  int done = 0;
  std::vector<int> failed;  // task indices
};

// Runs every task of the batch folder that is not done, `workers` at once (threads, each running
// its task's steps as child processes, so a crash takes only its task down; what one Slurm array
// index does with `batch run-task`), printing a line as each task ends; then writes the summary
// (batch_summary.h). One `batch run` at a time per folder (a lock file says so).
BatchRunResult RunBatch(const std::filesystem::path& batch_dir, const BatchRunOptions& options);

// The workers RunBatch uses for `options`.
int DefaultWorkers(int threads_per_task);

// "/abs/cap/img_003.png: file not found" out of a photomat child's output: the fault of its last
// "photomat: error: " line, or "" when it printed none.
std::string PhotomatErrorLine(const std::string& output);

}  // namespace photomat::batch
