// `photomat batch` end to end on this machine: eight synthetic captures, two of them broken,
// against the same commands typed by hand; and a batch killed half-way, then resumed.
#include <fmt/format.h>
#include <gmock/gmock.h>
#include <gtest/gtest.h>
#include <unistd.h>

#include <chrono>
#include <csignal>
#include <map>
#include <thread>

#include "apps/batch/child_process.h"
#include "apps/batch/task_plan.h"
#include "apps/batch/task_record.h"
#include "apps/batch/testing/collection.h"
#include "core/atomic_file.h"
#include "core/json_file.h"
#include "tests/support/test_support.h"

namespace photomat::batch {
namespace {

namespace fs = std::filesystem;
using photomat::testing::TempDir;
using testing::CaptureFault;
using ::testing::HasSubstr;
using testing::RunPhotomatIn;
using testing::TestCapture;

TEST(BatchCliTest, EightCapturesTwoBrokenMatchTheCommandsByHand) {
  TempDir dir;
  const std::vector<TestCapture> captures = testing::EightCapturesTwoBroken();
  const fs::path batch = testing::PlanTestCollection(dir.path(), captures);

  const ChildOutcome run =
      RunPhotomatIn(dir.path(), {"batch", "run", batch.string(), "--workers", "2"});
  std::cout << run.output;
  EXPECT_EQ(run.exit_code, 1) << "two tasks failed, so the batch does";
  EXPECT_THAT(run.output, HasSubstr("8 tasks, 0 already done, 8 to run on 2 worker(s)"));
  // The broken ones, with the file and the fault; photomat's own error lines.
  const std::string captures_dir = (dir / "captures").string();
  EXPECT_THAT(run.output, HasSubstr("capture-3: FAILED at fit: " + captures_dir +
                                    "/capture-3/img_007.png: image file not found"));
  EXPECT_THAT(run.output, HasSubstr("capture-6: FAILED at fit: " + captures_dir +
                                    "/capture-6/lights.lp: line 5: \"abc\" is not a number"));
  EXPECT_THAT(run.output, HasSubstr("photomat: error: " + batch.string() +
                                    ": 2 of 8 tasks failed (tasks 3, 6)"));
  EXPECT_THAT(run.output, HasSubstr("6 done, 2 failed, 0 not run"));

  // The six good ones: byte for byte what the commands give by hand.
  std::vector<testing::ByHandRun> good;
  for (const TestCapture& capture : captures) {
    const fs::path output = dir / "out" / capture.name;
    if (capture.fault != CaptureFault::kNone) {
      EXPECT_FALSE(fs::exists(output)) << capture.name;
      continue;
    }
    good.push_back(
        {dir / "captures" / capture.name, capture.name, dir / "by-hand" / capture.name, output});
  }
  testing::ExpectSameAsByHand(good);
  // Nothing but the final folders in the output folder: no temporary ones left.
  EXPECT_EQ(std::distance(fs::directory_iterator(dir / "out"), fs::directory_iterator()), 6);

  const nlohmann::json summary = ReadJsonFile(batch / "summary.json");
  EXPECT_EQ(summary["done"], 6);
  EXPECT_EQ(summary["failed"], 2);
  const nlohmann::json& first = summary["tasks"][0];
  EXPECT_EQ(first["methods"][0]["method"], "gradient");
  // Lambertian, noiseless: the Gradient fit is exact (measured 3.6e-5 and 0.000 degrees).
  EXPECT_LT(first["methods"][0]["eta_reconstruction"].get<double>(), 1e-3);
  EXPECT_LT(first["methods"][0]["normal_mean_angular_error_deg"].get<double>(), 0.1);
  EXPECT_THAT(summary["tasks"][6]["error"].get<std::string>(), HasSubstr("lights.lp: line 5"));
  const std::string index = ReadTextFile(batch / "index.html");
  EXPECT_THAT(index, HasSubstr("href=\"../out/capture-0/report/index.html\""));
  EXPECT_THAT(index, HasSubstr("href=\"../out/capture-0/viewer/index.html\""));

  // Run again: the six done tasks are skipped, the two broken ones fail again, nothing else runs.
  const ChildOutcome again =
      RunPhotomatIn(dir.path(), {"batch", "run", batch.string(), "--workers", "2"});
  EXPECT_EQ(again.exit_code, 1);
  EXPECT_THAT(again.output, HasSubstr("8 tasks, 6 already done, 2 to run"));
  const TaskPlan tasks = ReadTaskPlan(batch);
  for (const Task& task : tasks.tasks) {
    const bool broken = captures[task.index].fault != CaptureFault::kNone;
    EXPECT_EQ(testing::CountAttempts(LogPath(batch, task)), broken ? 2 : 1) << task.name;
  }
  const ChildOutcome status = RunPhotomatIn(dir.path(), {"batch", "status", batch.string()});
  EXPECT_THAT(status.output, HasSubstr("6 done, 2 failed"));
}

// SIGKILL the whole `batch run` while tasks are running, then run again: every task is done
// exactly once, and what the kill interrupted left nothing half-written.
TEST(BatchCliTest, KilledHalfWayThenResumedRunsEveryTaskOnce) {
  TempDir dir;
  std::vector<TestCapture> captures;
  // Larger than the captures above, so that each task takes long enough to be caught running.
  for (int i = 0; i < 8; ++i) captures.push_back({fmt::format("capture-{}", i), "96x96", i + 1});
  const fs::path batch = testing::PlanTestCollection(dir.path(), captures);
  const TaskPlan plan = ReadTaskPlan(batch);

  int done_at_kill = 0;
  std::vector<int> running_at_kill;
  {
    ChildCommand command{fs::absolute(photomat::testing::PhotomatExecutable()),
                         {"batch", "run", batch.string(), "--workers", "2"},
                         dir.path(),
                         ChildOutput::kAppendToFile,
                         dir / "first-run.log",
                         {}};
    ChildProcess first(command);
    const auto deadline = std::chrono::steady_clock::now() + std::chrono::seconds(60);
    while (std::chrono::steady_clock::now() < deadline) {
      done_at_kill = 0;
      for (const Task& task : plan.tasks) done_at_kill += IsTaskDone(task);
      if (done_at_kill >= 3) break;
      std::this_thread::sleep_for(std::chrono::milliseconds(20));
    }
    ASSERT_EQ(::kill(first.pid(), SIGKILL), 0);
    EXPECT_EQ(first.Wait().signal, SIGKILL);
  }
  // Count again after the kill: a task may have finished between the last look and the kill.
  done_at_kill = 0;
  std::map<int, std::string> done_records;  // task -> its done record at the kill
  for (const Task& task : plan.tasks) {
    if (IsTaskDone(task)) {
      ++done_at_kill;
      done_records[task.index] = ReadTextFile(DoneRecordPath(task));
    } else if (std::optional<TaskRecord> record = LastAttempt(batch, task);
               record && record->state == TaskState::kRunning) {
      running_at_kill.push_back(task.index);
    }
    // Nothing half-written: a final folder exists only with the done record of its task.
    if (fs::exists(task.folder)) {
      EXPECT_TRUE(IsTaskDone(task)) << task.folder;
    }
  }
  std::cout << done_at_kill << " tasks done and " << running_at_kill.size()
            << " interrupted when batch run was killed\n";
  ASSERT_GE(done_at_kill, 3);
  ASSERT_LT(done_at_kill, 8) << "the run finished before the kill: make the tasks longer";
  EXPECT_LE(running_at_kill.size(), 2u);  // two workers

  const ChildOutcome second =
      RunPhotomatIn(dir.path(), {"batch", "run", batch.string(), "--workers", "2"});
  std::cout << second.output;
  ASSERT_TRUE(second.Succeeded()) << second.output;
  EXPECT_THAT(second.output, HasSubstr(fmt::format("8 tasks, {} already done, {} to run",
                                                   done_at_kill, 8 - done_at_kill)));
  // The runs are counted by the attempt numbers the task records hand out as each attempt starts
  // (the log's "=== attempt" line comes just after, so a kill in between leaves one line fewer).
  int attempts = 0;
  for (const Task& task : plan.tasks) {
    ASSERT_TRUE(IsTaskDone(task)) << task.name;
    const int task_attempts = DoneRecord(task)->attempt;
    attempts += task_attempts;
    const bool interrupted = std::find(running_at_kill.begin(), running_at_kill.end(),
                                       task.index) != running_at_kill.end();
    // Done once: a task done at the kill was not run again (its done record is the same bytes);
    // an interrupted one ran once more, every other once.
    if (done_records.contains(task.index)) {
      EXPECT_EQ(ReadTextFile(DoneRecordPath(task)), done_records[task.index]) << task.name;
    }
    EXPECT_EQ(task_attempts, interrupted ? 2 : 1) << task.name;
    EXPECT_LE(testing::CountAttempts(LogPath(batch, task)), task_attempts) << task.name;
  }
  std::cout << attempts << " attempts for 8 tasks\n";
  EXPECT_EQ(attempts, 8 + static_cast<int>(running_at_kill.size()));
  EXPECT_EQ(std::distance(fs::directory_iterator(dir / "out"), fs::directory_iterator()), 8);
  // And the resumed tasks wrote what a person would have.
  std::vector<testing::ByHandRun> resumed;
  for (int index : running_at_kill) {
    const Task& task = plan.tasks[static_cast<std::size_t>(index)];
    resumed.push_back({task.capture, task.name, dir / "by-hand" / task.name, task.folder});
  }
  testing::ExpectSameAsByHand(resumed);
}

TEST(BatchCliTest, EveryBatchCommandHasHelp) {
  for (const char* command : {"plan", "run", "slurm", "status", "summary", "run-task"}) {
    const ChildOutcome help =
        RunPhotomatIn(fs::temp_directory_path(), {"batch", command, "--help"});
    EXPECT_EQ(help.exit_code, 0) << command;
    EXPECT_THAT(help.output, HasSubstr(std::string("Usage: photomat batch ") + command)) << command;
  }
}

TEST(BatchCliTest, RecipeErrorsNameTheFileAndKey) {
  TempDir dir;
  photomat::testing::WriteFile(dir / "recipe.json",
                               R"({"captures": [{"glob": "x/*"}], "fit": {"methods": "gradient"},
                                   "exports": {}, "output": {"folder": "out"}})");
  const ChildOutcome plan =
      RunPhotomatIn(dir.path(), {"batch", "plan", "recipe.json", "--out", "b"});
  EXPECT_EQ(plan.exit_code, 1);
  EXPECT_EQ(plan.output,
            "photomat: error: recipe.json: captures[0].glob: no folder matches \"x/*\"\n");
  EXPECT_FALSE(fs::exists(dir / "b"));
}

}  // namespace
}  // namespace photomat::batch
