#include "apps/batch/testing/collection.h"

#include <fmt/format.h>
#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include <algorithm>
#include <atomic>
#include <cstdint>
#include <cstring>
#include <fstream>
#include <sstream>
#include <thread>

#include "core/atomic_file.h"
#include "tests/support/test_support.h"

namespace photomat::batch::testing {

namespace fs = std::filesystem;

std::vector<TestCapture> EightCapturesTwoBroken() {
  std::vector<TestCapture> captures;
  for (int i = 0; i < 8; ++i) captures.push_back({fmt::format("capture-{}", i), "32x24", i + 1});
  captures[3].fault = CaptureFault::kMissingImage;
  captures[6].fault = CaptureFault::kMalformedLp;
  return captures;
}

ChildOutcome RunPhotomatIn(const fs::path& folder, const std::vector<std::string>& arguments) {
  fs::create_directories(folder);
  ChildCommand command;
  command.executable = fs::absolute(photomat::testing::PhotomatExecutable());
  command.arguments = arguments;
  command.working_directory = folder;
  command.output = ChildOutput::kCapture;
  return RunChild(command);
}

void WriteCaptures(const fs::path& dir, const std::vector<TestCapture>& captures) {
  for (const TestCapture& capture : captures) {
    const fs::path folder = dir / "captures" / capture.name;
    const ChildOutcome generate =
        RunPhotomatIn(dir, {"generate", "--out", folder.string(), "--size", capture.size, "--seed",
                            std::to_string(capture.seed)});
    ASSERT_TRUE(generate.Succeeded()) << generate.output;
    if (capture.fault == CaptureFault::kMissingImage) fs::remove(folder / "img_007.png");
    if (capture.fault == CaptureFault::kMalformedLp) {
      fs::remove(folder / "manifest.json");
      std::string lp;
      for (int i = 0; i < 36; ++i) {
        lp += i == 4 ? "img_004.png 0.1 abc 0.9\n" : fmt::format("img_{:03}.png 0.1 0.2 0.97\n", i);
      }
      photomat::testing::WriteFile(folder / "lights.lp", lp);
    }
  }
}

fs::path WriteTestRecipe(const fs::path& dir) {
  const fs::path recipe = dir / "recipe.json";
  photomat::testing::WriteFile(recipe, R"({
  "description": "batch test collection",
  "captures": [{"glob": "captures/*"}],
  "fit": {"methods": ["gradient", "ptm"]},
  "exports": {
    "maps": {"method": "gradient"},
    "ptm": true,
    "rti": true,
    "viewer": true,
    "evaluation": {"report": true}
  },
  "output": {"folder": "out", "layout": "{name}"}
}
)");
  return recipe;
}

fs::path PlanTestCollection(const fs::path& dir, const std::vector<TestCapture>& captures) {
  WriteCaptures(dir, captures);
  const fs::path recipe = WriteTestRecipe(dir);
  const fs::path batch = dir / "batch";
  const ChildOutcome plan =
      RunPhotomatIn(dir, {"batch", "plan", recipe.string(), "--out", batch.string()});
  EXPECT_TRUE(plan.Succeeded()) << plan.output;
  EXPECT_THAT(plan.output,
              ::testing::HasSubstr(fmt::format("{} tasks (0 already done)", captures.size())));
  return batch;
}

std::string RunByHand(const fs::path& capture, const std::string& name, const fs::path& folder) {
  const std::string c = capture.string();
  const std::vector<std::vector<std::string>> commands = {
      {"fit", c, "--method", "gradient,ptm", "--out", "stacks"},
      {"export", "stacks", "--method", "gradient", "--out", "maps", "--normal-convention", "opengl",
       "--height", "poisson"},
      {"export", c, "--ptm", name + ".ptm", "--rti", name + ".rti"},
      {"export", "stacks", "--viewer", "viewer"},
      {"evaluate", c, "--methods", "gradient,ptm", "--json", "evaluation.json", "--report",
       "report", "--stream"},
  };
  for (const auto& arguments : commands) {
    const ChildOutcome outcome = RunPhotomatIn(folder, arguments);
    if (!outcome.Succeeded())
      return fmt::format("{}: {}", fmt::join(arguments, " "), outcome.output);
  }
  return "";
}

std::vector<std::string> ListFiles(const fs::path& root) {
  std::vector<std::string> files;
  for (const auto& entry : fs::recursive_directory_iterator(root)) {
    if (!entry.is_regular_file()) continue;
    const std::string relative = entry.path().lexically_relative(root).generic_string();
    if (relative != ".photomat-task.json") files.push_back(relative);
  }
  std::sort(files.begin(), files.end());
  return files;
}

std::string ReadComparableBytes(const fs::path& file) {
  std::string bytes = ReadTextFile(file);
  // OpenImageIO's "DateTime" is OpenEXR's standard attribute capDate.
  static const std::string kKey("capDate\0string\0", 15);
  for (std::size_t at = bytes.find(kKey); at != std::string::npos; at = bytes.find(kKey, at + 1)) {
    const std::size_t size_at = at + kKey.size();
    if (size_at + 4 > bytes.size()) break;
    std::uint32_t size = 0;
    std::memcpy(&size, bytes.data() + size_at, 4);  // little-endian, as EXR headers are
    if (size_at + 4 + size > bytes.size()) break;
    std::fill_n(bytes.begin() + static_cast<long>(size_at + 4), size, '\0');
  }
  return bytes;
}

void ExpectSameOutputs(const fs::path& by_hand, const fs::path& batch) {
  const std::vector<std::string> expected = ListFiles(by_hand);
  ASSERT_EQ(ListFiles(batch), expected) << by_hand << " vs " << batch;
  ASSERT_GT(expected.size(), 10u);
  for (const std::string& file : expected) {
    EXPECT_TRUE(ReadComparableBytes(by_hand / file) == ReadComparableBytes(batch / file))
        << file << " differs between " << by_hand << " and " << batch;
  }
}

void ExpectSameAsByHand(const std::vector<ByHandRun>& runs) {
  std::vector<std::string> failures(runs.size());
  std::atomic<std::size_t> next{0};
  const auto work = [&] {
    for (std::size_t i = next++; i < runs.size(); i = next++) {
      failures[i] = RunByHand(runs[i].capture, runs[i].name, runs[i].by_hand);
    }
  };
  std::thread first(work), second(work);
  first.join();
  second.join();
  for (std::size_t i = 0; i < runs.size(); ++i) {
    ASSERT_EQ(failures[i], "") << runs[i].name;
    ExpectSameOutputs(runs[i].by_hand, runs[i].output);
  }
}

int CountAttempts(const fs::path& log) {
  std::ifstream in(log);
  int attempts = 0;
  for (std::string line; std::getline(in, line);)
    attempts += line.starts_with("=== attempt ") && line.find(" of task ") != std::string::npos;
  return attempts;
}

}  // namespace photomat::batch::testing
