#include "apps/batch_command.h"

// photomat batch plan|run|slurm|status|summary (and run-task, what one worker or Slurm array
// index runs): a collection of captures processed by one recipe (apps/batch/).

#include <fmt/format.h>

#include <algorithm>
#include <cstdio>
#include <optional>
#include <string>
#include <vector>

#include "apps/batch/batch_summary.h"
#include "apps/batch/recipe.h"
#include "apps/batch/slurm.h"
#include "apps/batch/task_plan.h"
#include "apps/batch/task_runner.h"
#include "apps/cli_main.h"
#include "apps/cli_support.h"
#include "core/error.h"

namespace photomat::app {
namespace {

namespace fs = std::filesystem;
using namespace photomat::batch;

void AddPlan(CLI::App& batch) {
  struct Options {
    fs::path recipe;
    fs::path out;
    double large = 5e8;
  };
  auto options = std::make_shared<Options>();
  CLI::App* command = batch.add_subcommand(
      "plan", "Expand a recipe into one independent task per capture and write DIR/tasks.json.");
  command->add_option("recipe", options->recipe, "The recipe (JSON; README has the schema)")
      ->required();
  command->add_option("--out", options->out, "The batch folder")->required();
  command
      ->add_option("--large-capture", options->large,
                   "Pixels x images above which a capture is flagged large when a step of the "
                   "recipe holds every image in memory (the neural basis's fit)")
      ->capture_default_str();
  command->callback([options] {
    const Recipe recipe = ReadRecipe(options->recipe);
    PlanOptions plan_options;
    plan_options.large_capture_pixel_images = static_cast<std::uint64_t>(options->large);
    const TaskPlan plan = PlanTasks(recipe, plan_options);
    CreateFolder(options->out);
    WriteTaskPlan(options->out, plan);
    int done = 0, large = 0;
    std::int64_t largest_need = 0;
    std::vector<std::string> whole_set_steps;
    for (const Task& task : plan.tasks) {
      const bool is_done = IsTaskDone(task);
      done += is_done;
      large += task.large;
      if (task.large) {
        largest_need = std::max(largest_need, TaskMemoryNeedBytes(task, std::nullopt));
        whole_set_steps.clear();
        for (const TaskStep& step : task.steps) {
          if (StepHoldsWholeSet(step)) whole_set_steps.push_back(step.name);
        }
      }
      fmt::print("{:>5}  {:<20} {:>2} steps  {:>9.3g} Mpx*img{}  -> {}\n", task.index, task.name,
                 task.steps.size(), static_cast<double>(task.pixel_images) / 1e6,
                 is_done ? "  done" : (task.large ? "  large" : ""), task.folder.string());
    }
    fmt::print("{} tasks ({} already done) -> {}\n", plan.tasks.size(), done,
               (options->out / kTaskPlanName).string());
    if (large > 0) {
      // The steps come from the recipe, so every large task has the same ones.
      fmt::print(
          "{} large capture(s) over {:.3g} pixels x images: the step(s) {} hold every image in "
          "memory, or as much (about {:.1f} GB for the largest); the other steps stream in bands "
          "(README \"Large captures\")\n",
          large, options->large, fmt::join(whole_set_steps, ", "),
          static_cast<double>(largest_need) / 1e9);
    }
  });
}

void AddRun(CLI::App& batch) {
  struct Options {
    fs::path dir;
    BatchRunOptions run;
  };
  auto options = std::make_shared<Options>();
  CLI::App* command = batch.add_subcommand(
      "run",
      "Run the batch's tasks that are not done on this machine; a failed task is reported and "
      "the others go on. Ends with a summary table, DIR/summary.json and DIR/index.html.");
  command->add_option("dir", options->dir, "The batch folder (batch plan --out)")->required();
  command->add_option("--workers", options->run.workers,
                      "Tasks at once (default: the available cores / --threads-per-task)");
  command
      ->add_option("--threads-per-task", options->run.threads_per_task,
                   "Cores each task uses: --workers defaults to the cores over this")
      ->capture_default_str()
      ->check(CLI::PositiveNumber);
  command->add_flag("--pin-cpus", options->run.pin_cpus,
                    "Pin each worker's steps to its own --threads-per-task cores (for machines "
                    "that run nothing else)");
  command->callback([options] {
    const BatchRunResult result = RunBatch(options->dir, options->run);
    fmt::print("summary: {}, index: {}\n", (options->dir / "summary.json").string(),
               (options->dir / "index.html").string());
    if (!result.failed.empty()) {
      throw Error(options->dir,
                  fmt::format("{} of {} tasks failed (tasks {})", result.failed.size(),
                              result.tasks, fmt::join(result.failed, ", ")));
    }
  });
}

void AddRunTask(CLI::App& batch) {
  struct Options {
    fs::path dir;
    int index = -1;
  };
  auto options = std::make_shared<Options>();
  CLI::App* command = batch.add_subcommand(
      "run-task", "Run one task of the batch (what each worker and each Slurm array index runs).");
  command->add_option("dir", options->dir, "The batch folder")->required();
  command->add_option("index", options->index, "The task's index in tasks.json")->required();
  command->callback([options] {
    const TaskPlan plan = ReadTaskPlan(options->dir);
    if (options->index < 0 || options->index >= static_cast<int>(plan.tasks.size())) {
      throw Error(options->dir / kTaskPlanName,
                  fmt::format("no task {} (the plan has {})", options->index, plan.tasks.size()));
    }
    const Task& task = plan.tasks[static_cast<std::size_t>(options->index)];
    const TaskRunResult result = RunTask(options->dir, task, batch::CurrentExecutable());
    if (result.skipped) {
      fmt::print("task {} ({}): already done\n", task.index, task.name);
    } else if (result.record.state == TaskState::kDone) {
      fmt::print("task {} ({}): done in {:.2f} s\n", task.index, task.name,
                 result.record.elapsed_seconds);
    } else {
      throw Error(fmt::format("task {} ({}) failed at {}: {}", task.index, task.name,
                              result.record.failed_step, result.record.error));
    }
  });
}

void AddSummary(CLI::App& batch) {
  auto dir = std::make_shared<fs::path>();
  CLI::App* command = batch.add_subcommand(
      "summary",
      "Write DIR/summary.json and DIR/index.html from the task records, and print the table.");
  command->add_option("dir", *dir, "The batch folder")->required();
  command->callback([dir] {
    const BatchSummary summary = SummariseBatch(*dir, ReadTaskPlan(*dir));
    WriteBatchSummary(*dir, summary);
    fmt::print("{}", FormatSummaryTable(summary));
  });
}

void AddSlurm(CLI::App& batch) {
  struct Options {
    fs::path dir;
    SlurmOptions slurm;
  };
  auto options = std::make_shared<Options>();
  CLI::App* command = batch.add_subcommand(
      "slurm",
      "Submit the tasks that are not done as Slurm job arrays (memory per task from its measured "
      "need), and the summary as a job that depends on them; job ids go to DIR/slurm/jobs.json.");
  command->add_option("dir", options->dir, "The batch folder (on a filesystem every node sees)")
      ->required();
  command->add_option("--partition", options->slurm.partition, "sbatch --partition");
  command->add_option("--time", options->slurm.time, "sbatch --time, per task (e.g. 2:00:00)");
  command->add_option("--mem", options->slurm.memory,
                      "sbatch --mem for every task (default: each task's measured need x "
                      "--mem-margin, or an estimate from its size)");
  command->add_option("--mem-margin", options->slurm.memory_margin, "Factor on the measured need")
      ->capture_default_str();
  command->add_option("--account", options->slurm.account, "sbatch --account");
  command->add_option("--qos", options->slurm.qos, "sbatch --qos");
  command->add_option("--cpus-per-task", options->slurm.cpus_per_task, "sbatch --cpus-per-task")
      ->capture_default_str()
      ->check(CLI::PositiveNumber);
  command->add_option("--extra-sbatch", options->slurm.extra_sbatch,
                      "More sbatch options, one string (e.g. \"--gres=gpu:1 --constraint=avx2\")");
  command->callback([options] {
    const SlurmSubmission submission =
        SubmitBatch(options->dir, options->slurm, SystemSlurmClient());
    if (submission.arrays.empty()) {
      fmt::print("every task of {} is done: nothing to submit\n", options->dir.string());
      return;
    }
    for (const SlurmArray& array : submission.arrays) {
      fmt::print("job {}: array of {} task(s) ({}), --mem={}, script {}\n", array.job,
                 array.tasks.size(), fmt::join(array.tasks, ","), array.memory,
                 array.script.string());
    }
    fmt::print("job {}: summary, after the arrays end (afterany)\n", submission.summary_job);
    fmt::print("follow with: photomat batch status {}\n", options->dir.string());
  });
}

void AddStatus(CLI::App& batch) {
  auto dir = std::make_shared<fs::path>();
  CLI::App* command = batch.add_subcommand(
      "status",
      "Show each task's state: done, running, pending (Slurm), failed, stopped, not run.");
  command->add_option("dir", *dir, "The batch folder")->required();
  command->callback(
      [dir] { fmt::print("{}", FormatStatus(BatchStatus(*dir, SystemSlurmClient()))); });
}

}  // namespace

void AddBatchCommand(CLI::App& app) {
  CLI::App* batch = AddListedCommand(app, "batch");
  batch->require_subcommand(1);
  AddPlan(*batch);
  AddRun(*batch);
  AddSlurm(*batch);
  AddStatus(*batch);
  AddSummary(*batch);
  AddRunTask(*batch);
}

}  // namespace photomat::app
