#pragma once

#include <cstdint>
#include <filesystem>
#include <optional>
#include <string>

#include "apps/batch/task_plan.h"

namespace photomat::batch {

// Where a batch keeps what it knows about its tasks (beside tasks.json in the batch folder):
//   records/NNNN.json  the last attempt of task NNNN: running, failed or done, with its error
//   logs/NNNN-NAME.log every attempt's command lines and photomat output, appended
// and, in each task's final folder, the done record .photomat-task.json, which arrives with the
// outputs in the one rename that publishes them: a task is done exactly when its final folder
// holds a done record with the task's hash.

enum class TaskState { kRunning, kFailed, kDone };
std::string ToString(TaskState state);

struct TaskRecord {
  TaskState state = TaskState::kRunning;
  int attempt = 0;  // 1 for the first run of the task
  std::string hash;
  std::string host;
  int pid = 0;
  std::string slurm_job;    // "JOB_INDEX" under Slurm, else empty
  std::string failed_step;  // the step that failed
  std::string error;        // its photomat error line (or how it ended)
  double elapsed_seconds = 0;
  std::int64_t peak_rss_bytes = 0;  // the largest step's, measured with wait4
};

inline constexpr const char* kDoneRecordName = ".photomat-task.json";

std::filesystem::path RecordPath(const std::filesystem::path& batch_dir, const Task& task);
std::filesystem::path LogPath(const std::filesystem::path& batch_dir, int index,
                              const std::string& name);
std::filesystem::path LogPath(const std::filesystem::path& batch_dir, const Task& task);
std::filesystem::path DoneRecordPath(const Task& task);

void WriteTaskRecord(const std::filesystem::path& path, const TaskRecord& record);
// nullopt when there is none; an unreadable record counts as none (it is only informative).
std::optional<TaskRecord> ReadTaskRecord(const std::filesystem::path& path);

// The done record of the task's final folder, if it is this task's (same hash).
std::optional<TaskRecord> DoneRecord(const Task& task);
bool IsTaskDone(const Task& task);

// The last attempt's record in the batch folder, if it is of this task (same hash).
std::optional<TaskRecord> LastAttempt(const std::filesystem::path& batch_dir, const Task& task);

}  // namespace photomat::batch
