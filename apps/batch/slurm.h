#pragma once

#include <cstdint>
#include <filesystem>
#include <functional>
#include <map>
#include <optional>
#include <string>
#include <vector>

#include "apps/batch/child_process.h"
#include "apps/batch/task_plan.h"
#include "apps/batch/task_record.h"

namespace photomat::batch {

// A batch on a Slurm cluster: the tasks not yet done become job arrays (one array index per
// task) that run `photomat batch run-task DIR INDEX`, and a job that depends on them
// (afterany) writes the summary. Nothing here schedules: sbatch, squeue, sacct and scancel do.
// The batch folder, the captures, the outputs and the photomat executable must be at the same
// paths on every node (a shared filesystem).

struct SlurmOptions {
  std::string partition, time, account, qos;
  std::string memory;        // --mem for every task (e.g. "8G"); empty: from each task's need
  std::string extra_sbatch;  // more sbatch options, e.g. "--gres=gpu:1 --constraint avx2"
  int cpus_per_task = 1;
  double memory_margin = 1.5;      // request = need x margin
  std::filesystem::path photomat;  // empty: this executable
};

// Memory one task needs: its own measured peak (an earlier attempt's record) when there is one,
// else the estimate of its largest step: from pixels x images for a step that holds the whole set
// (StepHoldsWholeSet), from the pixels alone for a streamed one (constants measured on photomat's
// steps; see .cc).
std::int64_t TaskMemoryNeedBytes(const Task& task, const std::optional<TaskRecord>& last_attempt);
// The --mem request in MiB for a need: need x margin, rounded up to 64 MiB, at least 256 MiB.
std::int64_t MemoryRequestMib(std::int64_t need_bytes, double margin);

struct SlurmArray {
  std::string job;         // the array's job id
  std::vector<int> tasks;  // array index i runs tasks[i]
  std::string memory;      // the --mem it asked for
  std::filesystem::path script;
};

struct SlurmSubmission {
  std::vector<SlurmArray> arrays;
  std::string summary_job;
};

// Runs a Slurm client (argv[0] looked up in PATH) and returns its outcome with the output;
// replaced in tests.
using SlurmClient = std::function<ChildOutcome(const std::vector<std::string>& argv)>;
SlurmClient SystemSlurmClient();

// Tasks of `plan` that are not done, grouped into arrays of equal memory request (at most 1000
// indices each: Slurm's default MaxArraySize is 1001).
std::vector<SlurmArray> PlanArrays(const std::filesystem::path& batch_dir, const TaskPlan& plan,
                                   const SlurmOptions& options);

// The sbatch script of one array (directives from `options`; --output and --chdir are given on
// the sbatch command line, so paths with spaces work).
std::string ArrayScript(const std::filesystem::path& batch_dir,
                        const std::filesystem::path& photomat, const SlurmArray& array,
                        const SlurmOptions& options);

// Writes the scripts into DIR/slurm, submits the arrays (`sbatch --parsable`) and the summary job
// (`--dependency=afterany:...`), and appends the job ids to DIR/slurm/jobs.json. Refuses while a
// job of the previous submission is still queued or running (its tasks would run twice).
SlurmSubmission SubmitBatch(const std::filesystem::path& batch_dir, const SlurmOptions& options,
                            const SlurmClient& slurm);

// The submissions recorded in DIR/slurm/jobs.json, oldest first.
std::vector<SlurmSubmission> ReadSubmissions(const std::filesystem::path& batch_dir);

struct TaskStatus {
  int index = 0;
  std::string name;
  std::string state;  // done, running, pending, failed, stopped, not run
  std::string detail;
};

// Every task's state from its records, the queue (squeue) and the accounting (sacct); when
// sacct is unavailable (JobAcctGatherType none, no slurmdbd) the records decide.
std::vector<TaskStatus> BatchStatus(const std::filesystem::path& batch_dir,
                                    const SlurmClient& slurm);
std::string FormatStatus(const std::vector<TaskStatus>& status);

// "JOB_INDEX|STATE" lines of `squeue -h -r -o %i|%T` or `sacct -n -P -X -o JobID,State`, as a
// map; "CANCELLED by 0" keeps its first word.
std::map<std::string, std::string> ParseJobStates(const std::string& output);

}  // namespace photomat::batch
