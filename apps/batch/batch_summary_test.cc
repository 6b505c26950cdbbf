#include "apps/batch/batch_summary.h"

#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include <regex>

#include "apps/batch/task_record.h"
#include "core/atomic_file.h"
#include "core/json_file.h"
#include "tests/support/test_support.h"

namespace photomat::batch {
namespace {

namespace fs = std::filesystem;
using photomat::testing::TempDir;
using ::testing::HasSubstr;

// Three tasks: one done with an evaluation and a report, one failed, one not run; the done one's
// name needs escaping in HTML and encoding in a link.
class BatchSummaryTest : public ::testing::Test {
 protected:
  void SetUp() override {
    const char* names[] = {"coin <1> & co", "vase", "tile"};
    for (int i = 0; i < 3; ++i) {
      Task task;
      task.index = i;
      task.name = names[i];
      task.capture = dir_ / "captures" / task.name;
      task.folder = dir_ / "out" / task.name;
      task.steps = {
          {"fit", {"fit", task.capture.string(), "--method", "gradient,ptm", "--out", "stacks"}}};
      task.hash = TaskHash(task);
      plan_.tasks.push_back(task);
    }
    plan_.recipe_file = dir_ / "recipe.json";
    const Task& done = plan_.tasks[0];
    TaskRecord record;
    record.state = TaskState::kDone;
    record.hash = done.hash;
    record.elapsed_seconds = 2.5;
    record.peak_rss_bytes = 96LL << 20;
    fs::create_directories(done.folder / "report");
    photomat::testing::WriteFile(done.folder / "report/index.html", "<html></html>");
    WriteTaskRecord(DoneRecordPath(done), record);
    WriteJsonFile(done.folder / "evaluation.json",
                  {{"gradient",
                    {{"eta_reconstruction", 0.0125},
                     {"eta_prediction", 0.015},
                     {"normals", {{"mean_angular_error_deg", 1.25}}}}},
                   {"ptm", {{"eta_reconstruction", 0.04}}}});
    TaskRecord failed;
    failed.state = TaskState::kFailed;
    failed.hash = plan_.tasks[1].hash;
    failed.failed_step = "fit";
    failed.error = "/c/vase/img_007.png: image file not found";
    fs::create_directories(batch_ / "records");
    WriteTaskRecord(RecordPath(batch_, plan_.tasks[1]), failed);
    photomat::testing::WriteFile(LogPath(batch_, plan_.tasks[1]),
                                 "=== attempt 1 of task 1 (vase)\n");
  }

  TempDir dir_;
  fs::path batch_ = dir_ / "batch";
  TaskPlan plan_;
};

TEST_F(BatchSummaryTest, StatesAndNumbersPerCaptureAndMethod) {
  const BatchSummary summary = SummariseBatch(batch_, plan_);
  ASSERT_EQ(summary.tasks.size(), 3u);
  EXPECT_EQ(summary.tasks[0].state, "done");
  ASSERT_EQ(summary.tasks[0].methods.size(), 2u);
  EXPECT_EQ(summary.tasks[0].methods[0].method, "gradient");
  EXPECT_DOUBLE_EQ(*summary.tasks[0].methods[0].normal_mean_degrees, 1.25);
  EXPECT_DOUBLE_EQ(*summary.tasks[0].methods[1].eta_reconstruction, 0.04);
  EXPECT_FALSE(summary.tasks[0].methods[1].normal_mean_degrees);  // PTM has no ground-truth entry
  EXPECT_TRUE(summary.tasks[0].report);
  EXPECT_EQ(summary.tasks[1].state, "failed");
  EXPECT_EQ(summary.tasks[2].state, "not run");
  const std::string table = FormatSummaryTable(summary);
  EXPECT_THAT(table,
              HasSubstr("gradient       0.012500     0.015000       1.250      2.5       96\n"));
  EXPECT_THAT(
      table,
      HasSubstr("vase                 failed   fit: /c/vase/img_007.png: image file not found\n"));
  EXPECT_THAT(table, HasSubstr("1 done, 1 failed, 1 not run\n"));
}

TEST_F(BatchSummaryTest, IndexLinksRelativelyAndEscapes) {
  WriteBatchSummary(batch_, SummariseBatch(batch_, plan_));
  const nlohmann::json json = ReadJsonFile(batch_ / "summary.json");
  EXPECT_EQ(json["done"], 1);
  EXPECT_EQ(json["tasks"][1]["error"], "/c/vase/img_007.png: image file not found");
  EXPECT_TRUE(json["tasks"][0]["methods"][1]["normal_mean_angular_error_deg"].is_null());

  const std::string html = ReadTextFile(batch_ / "index.html");
  EXPECT_THAT(html, HasSubstr("coin &lt;1&gt; &amp; co"));
  EXPECT_EQ(html.find("coin <1>"), std::string::npos);
  const std::regex href("href=\"([^\"]*)\"");
  int links = 0;
  for (auto it = std::sregex_iterator(html.begin(), html.end(), href); it != std::sregex_iterator();
       ++it) {
    const std::string link = (*it)[1];
    EXPECT_FALSE(link.starts_with("/")) << link;
    EXPECT_EQ(link.find("://"), std::string::npos) << link;
    ++links;
  }
  EXPECT_THAT(html, HasSubstr("href=\"../out/coin%20%3C1%3E%20%26%20co/report/index.html\""));
  EXPECT_EQ(links, 2);  // the done task's report and the failed task's log (the others have none)
  EXPECT_THAT(html, HasSubstr("href=\"logs/0001-vase.log\""));
}

TEST(RelativeLinkTest, EncodesAndWalksUp) {
  EXPECT_EQ(RelativeLink("/a/batch", "/a/out/x y/report/index.html"),
            "../out/x%20y/report/index.html");
  EXPECT_EQ(RelativeLink("/a/batch", "/a/batch/logs/0001-x.log"), "logs/0001-x.log");
}

}  // namespace
}  // namespace photomat::batch
