// The Slurm layer against a scripted client (the real cluster: apps/batch_slurm_test.cc).
#include "apps/batch/slurm.h"

#include <fmt/format.h>
#include <gmock/gmock.h>
#include <gtest/gtest.h>
#include <unistd.h>

#include <string>
#include <utility>
#include <vector>

#include "core/atomic_file.h"
#include "core/error.h"
#include "core/json_file.h"
#include "tests/support/test_support.h"

namespace photomat::batch {
namespace {

namespace fs = std::filesystem;
using photomat::testing::TempDir;
using ::testing::ElementsAre;
using ::testing::HasSubstr;

// Answers sbatch with increasing job ids and squeue/sacct with what the test sets; records every
// call.
struct FakeSlurm {
  int next_job = 41;
  std::string squeue;
  std::optional<std::string> sacct;  // nullopt: accounting disabled (exit 1)
  bool sbatch_fails = false;
  std::vector<std::vector<std::string>> calls;

  SlurmClient Client() {
    return [this](const std::vector<std::string>& argv) {
      calls.push_back(argv);
      ChildOutcome outcome;
      outcome.exit_code = 0;
      if (argv[0] == "sbatch") {
        if (sbatch_fails) {
          outcome.exit_code = 1;
          outcome.output = "sbatch: error: invalid partition specified: gpu\n";
        } else {
          outcome.output = fmt::format("{}\n", next_job++);
        }
      } else if (argv[0] == "squeue") {
        outcome.output = squeue;
      } else if (argv[0] == "sacct") {
        if (sacct) {
          outcome.output = *sacct;
        } else {
          outcome.exit_code = 1;
          outcome.output = "Slurm accounting storage is disabled\n";
        }
      }
      return outcome;
    };
  }
};

class SlurmTest : public ::testing::Test {
 protected:
  // Tasks 0..count-1 of `pixel_images` each; none run yet.
  TaskPlan Plan(int count, std::uint64_t pixel_images = 1'000'000) {
    TaskPlan plan;
    plan.recipe_file = dir_ / "recipe.json";
    for (int i = 0; i < count; ++i) {
      Task task;
      task.index = i;
      task.name = fmt::format("c{}", i);
      task.capture = dir_ / "captures" / task.name;
      task.folder = dir_ / "out" / task.name;
      task.steps = {{"fit", {"fit", task.capture.string(), "--out", "stacks"}}};
      task.pixel_images = pixel_images;
      task.hash = TaskHash(task);
      plan.tasks.push_back(task);
    }
    fs::create_directories(dir_.path());
    WriteTaskPlan(dir_.path(), plan);
    return plan;
  }

  void MarkDone(const Task& task, std::int64_t peak) {
    TaskRecord record;
    record.state = TaskState::kDone;
    record.hash = task.hash;
    record.peak_rss_bytes = peak;
    fs::create_directories(task.folder);
    WriteTaskRecord(DoneRecordPath(task), record);
  }

  void RecordAttempt(const Task& task, TaskState state, std::int64_t peak,
                     const std::string& error = "") {
    TaskRecord record;
    record.state = state;
    record.attempt = 1;
    record.hash = task.hash;
    record.peak_rss_bytes = peak;
    record.failed_step = "fit";
    record.error = error;
    fs::create_directories(dir_ / "records");
    WriteTaskRecord(RecordPath(dir_.path(), task), record);
  }

  SlurmOptions Options() const {
    SlurmOptions options;
    options.photomat = "/opt/photomat/bin/photomat";
    return options;
  }

  TempDir dir_;
};

TEST(SlurmMemoryTest, RequestIsTheNeedTimesTheMarginInWholeSteps) {
  EXPECT_EQ(MemoryRequestMib(100LL << 20, 1.5), 256);    // 150 MiB: the floor
  EXPECT_EQ(MemoryRequestMib(1000LL << 20, 1.5), 1536);  // 1500 MiB, up to 64 MiB steps
  EXPECT_EQ(MemoryRequestMib(1024LL << 20, 2.0), 2048);
  Task task;
  task.steps = {{"evaluate", {"evaluate", "capture", "--methods", "ptm"}}};
  task.pixel_images = 0;
  const std::int64_t base = TaskMemoryNeedBytes(task, std::nullopt);
  task.pixel_images = 100'000'000;
  EXPECT_GT(TaskMemoryNeedBytes(task, std::nullopt), base + (2000LL << 20));  // grows with size
  TaskRecord measured;
  measured.peak_rss_bytes = 123LL << 20;
  EXPECT_EQ(TaskMemoryNeedBytes(task, measured), 123LL << 20);  // a measurement wins
}

// Streamed steps need memory for their bands and for what grows with the image, not with the
// number of images: a 48 MP x 50 task of fit, maps and viewer from the stacks asks for about what
// its steps were measured to take there (at most 977 MB peak RSS, README "Streamed fitting"),
// where one step that holds the whole set asks for tens of GB.
TEST(SlurmMemoryTest, StreamedStepsNeedWhatTheirBandsAndPixelsNeed) {
  Task task;
  task.steps = {{"fit", {"fit", "capture", "--method", "ptm", "--out", "stacks"}},
                {"maps", {"export", "stacks", "--method", "ptm", "--out", "maps"}},
                {"viewer", {"export", "stacks", "--viewer", "viewer"}}};
  task.pixels = 8688ULL * 5792ULL;
  task.pixel_images = task.pixels * 50;
  const std::int64_t streamed = TaskMemoryNeedBytes(task, std::nullopt);
  EXPECT_GT(streamed, 977LL * 1000 * 1000);
  EXPECT_LT(streamed, 2100LL * 1000 * 1000);
  task.pixel_images = task.pixels * 80;  // more lights: the same bands
  EXPECT_EQ(TaskMemoryNeedBytes(task, std::nullopt), streamed);
  // calibrate apply streams too, with a target's flat-field (its gain maps read band by band)
  // and semi-calibrated intensities (from sampled pixels gathered in a first pass); so do the
  // .ptm and .rti fitted to the photographs (export --stream).
  task.steps.push_back({"calibrate",
                        {"calibrate", "apply", "capture", "--out", "calibrated", "--dark", "d.exr",
                         "--flat-field", "flat", "--semi-calibrated"}});
  task.steps.push_back({"interchange", {"export", "calibrated", "--stream", "--ptm", "c.ptm"}});
  EXPECT_EQ(TaskMemoryNeedBytes(task, std::nullopt), streamed);
  // An evaluation holds the whole set.
  task.steps.push_back({"evaluate", {"evaluate", "calibrated", "--methods", "ptm"}});
  EXPECT_GT(TaskMemoryNeedBytes(task, std::nullopt),
            40 * static_cast<std::int64_t>(task.pixel_images));
}

// A streamed evaluation with a report holds its pictures at display size: the estimate covers what
// `evaluate --stream --methods gradient,ptm --hold-out-every 8 --report` took at 4096 x 3072 x 50
// (601 MiB peak RSS), and grows with the methods (their relit and predicted pictures).
TEST(SlurmMemoryTest, AStreamedReportAddsItsPicturesAtDisplaySize) {
  Task task;
  task.pixels = 4096ULL * 3072ULL;
  task.pixel_images = task.pixels * 50;
  const auto need = [&](const std::string& methods, bool report) {
    task.steps = {
        {"evaluate",
         {"evaluate", "capture", "--methods", methods, "--hold-out-every", "8", "--stream"}}};
    if (report) task.steps[0].arguments.insert(task.steps[0].arguments.end(), {"--report", "r"});
    return TaskMemoryNeedBytes(task, std::nullopt);
  };
  EXPECT_GT(need("gradient,ptm", true), 601LL << 20);
  // 1024 x 1024 display values (the most), 8 bytes each: 3 x 3 x 5 RGB pictures, 2 heat maps and
  // the mask for two methods; 2 x 3 x 3 more RGB pictures and a heat map per further method.
  const double display = 8.0 * 1024 * 1024;
  EXPECT_NEAR(static_cast<double>(need("gradient,ptm", true) - need("gradient,ptm", false)),
              display * (45 + 3), display);
  EXPECT_NEAR(static_cast<double>(need("gradient,ptm,hsh9", true) - need("gradient,ptm", true)),
              display * (18 + 1), display);
}

// Maps with the whole-map FFT height stream, but hold the gradient field and its spectra whole:
// the estimate covers what `export CAPTURE --stream --out maps --height fc` was measured to take
// at 4096 x 3072 x 50 (peak RSS 2026-12-06: Gradient 742 MiB, PTM 754 MiB; the method no longer
// matters, its albedo being made band by band), by at most 30 %.
TEST(SlurmMemoryTest, FrankotChellappaMapsNeedTheGradientFieldsTransform) {
  Task task;
  task.pixels = 4096ULL * 3072ULL;
  task.pixel_images = task.pixels * 50;
  for (const auto& [method, measured] :
       std::vector<std::pair<std::string, std::int64_t>>{{"gradient", 742}, {"ptm", 754}}) {
    task.steps = {
        {"maps",
         {"export", "capture", "--method", method, "--out", "maps", "--height", "fc", "--stream"}}};
    const std::int64_t need = TaskMemoryNeedBytes(task, std::nullopt);
    EXPECT_GT(need, measured << 20) << method;
    EXPECT_LT(need, static_cast<std::int64_t>(1.3 * static_cast<double>(measured << 20))) << method;
  }
}

// The viewer of a stack up to 4096 x 4096 pixels is made in memory, whatever the limit: the same
// task of a 4096 x 3072 x 50 capture (PTM) was measured at 2823 MB peak RSS by `batch run`, its
// viewer step; one pixel above the tiling threshold the viewer is tiled and streamed.
TEST(SlurmMemoryTest, ViewersBelowTheTilingThresholdAreMadeInMemory) {
  Task task;
  task.steps = {{"fit", {"fit", "capture", "--method", "ptm", "--out", "stacks"}},
                {"viewer", {"export", "stacks", "--viewer", "viewer"}}};
  task.pixels = 4096ULL * 3072ULL;
  task.pixel_images = task.pixels * 50;
  EXPECT_GT(TaskMemoryNeedBytes(task, std::nullopt), 2823LL << 20);
  task.pixels = 4096ULL * 4096ULL + 1;
  task.pixel_images = task.pixels * 50;
  EXPECT_LT(TaskMemoryNeedBytes(task, std::nullopt), 1000LL << 20);
}

TEST_F(SlurmTest, ArraysGroupTasksByMemoryAndLeaveDoneTasksOut) {
  const TaskPlan plan = Plan(5);
  MarkDone(plan.tasks[1], 100LL << 20);
  RecordAttempt(plan.tasks[2], TaskState::kFailed, 1000LL << 20);  // measured: 1536M
  RecordAttempt(plan.tasks[4], TaskState::kFailed, 1010LL << 20);  // measured: 1536M
  const std::vector<SlurmArray> arrays = PlanArrays(dir_.path(), plan, Options());
  ASSERT_EQ(arrays.size(), 2u);
  EXPECT_EQ(arrays[0].memory, "1536M");
  EXPECT_THAT(arrays[0].tasks, ElementsAre(2, 4));
  EXPECT_THAT(arrays[1].tasks, ElementsAre(0, 3));  // estimated from their size

  SlurmOptions fixed = Options();
  fixed.memory = "8G";
  const std::vector<SlurmArray> one = PlanArrays(dir_.path(), plan, fixed);
  ASSERT_EQ(one.size(), 1u);
  EXPECT_EQ(one[0].memory, "8G");
  EXPECT_THAT(one[0].tasks, ElementsAre(0, 2, 3, 4));
}

TEST_F(SlurmTest, ArraysHoldAtMostAThousandIndices) {
  const TaskPlan plan = Plan(1001);
  const std::vector<SlurmArray> arrays = PlanArrays(dir_.path(), plan, Options());
  ASSERT_EQ(arrays.size(), 2u);
  EXPECT_EQ(arrays[0].tasks.size(), 1000u);
  EXPECT_THAT(arrays[1].tasks, ElementsAre(1000));
}

TEST_F(SlurmTest, ScriptMapsArrayIndicesToTasksWithTheGivenDirectives) {
  SlurmOptions options = Options();
  options.partition = "main";
  options.time = "1:00:00";
  options.account = "lab";
  options.qos = "low";
  options.cpus_per_task = 2;
  options.extra_sbatch = "--gres gpu:1  --hold";
  const SlurmArray array{"", {0, 3, 5}, "768M", {}};
  EXPECT_EQ(
      ArrayScript("/shared/batch one", options.photomat, array, options),
      "#!/bin/bash\n"
      "# photomat batch: 3 task(s) of /shared/batch one not done at submission; array index i "
      "runs task tasks[i].\n"
      "#SBATCH --job-name=photomat-batch\n"
      "#SBATCH --array=0-2\n"
      "#SBATCH --cpus-per-task=2\n"
      "#SBATCH --mem=768M\n"
      "#SBATCH --partition=main\n"
      "#SBATCH --time=1:00:00\n"
      "#SBATCH --account=lab\n"
      "#SBATCH --qos=low\n"
      "#SBATCH --gres gpu:1\n"
      "#SBATCH --hold\n"
      "tasks=(0 3 5)\n"
      "exec /opt/photomat/bin/photomat batch run-task '/shared/batch one' "
      "\"${tasks[$SLURM_ARRAY_TASK_ID]}\"\n");
}

TEST_F(SlurmTest, SubmitsArraysThenTheSummaryAfterThemAndRecordsTheJobs) {
  const TaskPlan plan = Plan(3);
  MarkDone(plan.tasks[0], 100LL << 20);
  FakeSlurm slurm;
  const SlurmSubmission submission = SubmitBatch(dir_.path(), Options(), slurm.Client());
  ASSERT_EQ(submission.arrays.size(), 1u);
  EXPECT_EQ(submission.arrays[0].job, "41");
  EXPECT_THAT(submission.arrays[0].tasks, ElementsAre(1, 2));
  EXPECT_EQ(submission.summary_job, "42");
  ASSERT_EQ(slurm.calls.size(), 2u);  // no earlier submission: no squeue
  const auto& array_call = slurm.calls[0];
  EXPECT_EQ(array_call[0], "sbatch");
  EXPECT_THAT(array_call, ::testing::Contains("--parsable"));
  EXPECT_THAT(array_call,
              ::testing::Contains("--output=" + (dir_.path() / "logs/slurm-%A_%a.out").string()));
  EXPECT_EQ(array_call.back(), submission.arrays[0].script.string());
  EXPECT_THAT(ReadTextFile(submission.arrays[0].script), HasSubstr("tasks=(1 2)\n"));
  EXPECT_THAT(slurm.calls[1], ::testing::Contains("--dependency=afterany:41"));
  EXPECT_THAT(ReadTextFile(slurm.calls[1].back()),
              HasSubstr("batch summary " + dir_.path().string()));
  const std::vector<SlurmSubmission> recorded = ReadSubmissions(dir_.path());
  ASSERT_EQ(recorded.size(), 1u);
  EXPECT_EQ(recorded[0].arrays[0].job, "41");
  EXPECT_EQ(recorded[0].summary_job, "42");

  // While its jobs are queued, a second submission is refused (the tasks would run twice).
  slurm.squeue = "41_1|RUNNING\n42|PENDING\n";
  try {
    SubmitBatch(dir_.path(), Options(), slurm.Client());
    FAIL() << "no error";
  } catch (const Error& error) {
    EXPECT_THAT(
        error.what(),
        HasSubstr("the previous submission is still in the queue (41_1 running, 42 pending)"));
  }
  // Once they have left, only what is not done goes again.
  slurm.squeue = "";
  MarkDone(plan.tasks[2], 100LL << 20);
  const SlurmSubmission again = SubmitBatch(dir_.path(), Options(), slurm.Client());
  ASSERT_EQ(again.arrays.size(), 1u);
  EXPECT_THAT(again.arrays[0].tasks, ElementsAre(1));
  EXPECT_EQ(ReadSubmissions(dir_.path()).size(), 2u);
  EXPECT_TRUE(fs::exists(dir_ / "slurm/submission-2-array-0.sh"));
}

TEST_F(SlurmTest, NothingToSubmitWhenEveryTaskIsDone) {
  const TaskPlan plan = Plan(2);
  for (const Task& task : plan.tasks) MarkDone(task, 1);
  FakeSlurm slurm;
  EXPECT_TRUE(SubmitBatch(dir_.path(), Options(), slurm.Client()).arrays.empty());
  EXPECT_TRUE(slurm.calls.empty());
}

TEST_F(SlurmTest, SbatchFailureNamesTheScriptAndSlurmsMessage) {
  Plan(1);
  FakeSlurm slurm;
  slurm.sbatch_fails = true;
  try {
    SubmitBatch(dir_.path(), Options(), slurm.Client());
    FAIL() << "no error";
  } catch (const Error& error) {
    EXPECT_THAT(error.what(), HasSubstr("submission-1-array-0.sh: sbatch failed (exit status 1): "
                                        "sbatch: error: invalid partition specified: gpu"));
  }
  EXPECT_TRUE(ReadSubmissions(dir_.path()).empty());
}

TEST(ParseJobStatesTest, SqueueAndSacctLines) {
  EXPECT_EQ(ParseJobStates("12_3|RUNNING\n12_4|CANCELLED by 0\n13|PENDING\nbad line\n"),
            (std::map<std::string, std::string>{
                {"12_3", "RUNNING"}, {"12_4", "CANCELLED"}, {"13", "PENDING"}}));
}

TEST_F(SlurmTest, StatusCombinesRecordsQueueAndAccounting) {
  const TaskPlan plan = Plan(6);
  FakeSlurm slurm;
  SubmitBatch(dir_.path(), Options(), slurm.Client());  // job 41: tasks 0..5, summary 42
  MarkDone(plan.tasks[0], 90LL << 20);
  slurm.squeue = "41_1|RUNNING\n41_2|PENDING\n42|PENDING\n";
  RecordAttempt(plan.tasks[3], TaskState::kFailed, 1,
                "/c/c3/lights.lp: line 5: \"abc\" is not a number");
  RecordAttempt(plan.tasks[4], TaskState::kRunning, 1);  // killed: no outcome recorded

  const std::vector<TaskStatus> without = BatchStatus(dir_.path(), slurm.Client());
  std::vector<std::string> states;
  for (const TaskStatus& s : without) states.push_back(s.state);
  EXPECT_THAT(states, ElementsAre("done", "running", "pending", "failed", "stopped", "stopped"));
  EXPECT_EQ(without[1].detail, "Slurm job 41_1");
  EXPECT_EQ(without[3].detail, "fit: /c/c3/lights.lp: line 5: \"abc\" is not a number");
  EXPECT_THAT(without[5].detail, HasSubstr("Slurm job 41_5 left the queue without a done record"));
  EXPECT_THAT(without[5].detail, HasSubstr("sacct unavailable"));

  slurm.sacct = "41_4|CANCELLED by 0\n41_5|OUT_OF_MEMORY\n";
  const std::vector<TaskStatus> with = BatchStatus(dir_.path(), slurm.Client());
  EXPECT_EQ(with[4].detail, "Slurm job 41_4: CANCELLED");
  EXPECT_EQ(with[5].detail, "Slurm job 41_5: OUT_OF_MEMORY");
  const std::string text = FormatStatus(with);
  EXPECT_THAT(text, HasSubstr("1 done, 1 running, 1 pending, 1 failed, 2 stopped\n"));
}

TEST_F(SlurmTest, StatusWithoutSlurmIsTheRecords) {
  const TaskPlan plan = Plan(4);
  MarkDone(plan.tasks[0], 1);
  // Task 2 is being run by a live process of this host (this test's), task 3's process is gone.
  char host[256] = {};
  gethostname(host, sizeof(host) - 1);
  for (int i : {2, 3}) {
    TaskRecord record;
    record.hash = plan.tasks[i].hash;
    record.host = host;
    record.pid = i == 2 ? static_cast<int>(getpid()) : 0;
    fs::create_directories(dir_ / "records");
    WriteTaskRecord(RecordPath(dir_.path(), plan.tasks[i]), record);
  }
  FakeSlurm slurm;
  const std::vector<TaskStatus> status = BatchStatus(dir_.path(), slurm.Client());
  EXPECT_EQ(status[0].state, "done");
  EXPECT_EQ(status[1].state, "not run");
  EXPECT_EQ(status[2].state, "running");
  EXPECT_EQ(status[3].state, "stopped");
  EXPECT_TRUE(slurm.calls.empty());  // never submitted: no Slurm client is asked
}

}  // namespace
}  // namespace photomat::batch
