#include "core/progress.h"

#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include <thread>
#include <vector>

namespace photomat {
namespace {

using ::testing::HasSubstr;

TEST(ProgressTest, BarCountsStepsFromManyThreads) {
  std::FILE* sink = std::tmpfile();
  TerminalProgressBar bar(sink, /*force=*/true);
  bar.Start("fit", 4000);
  std::vector<std::thread> threads;
  for (int t = 0; t < 4; ++t) {
    threads.emplace_back([&] {
      for (int i = 0; i < 1000; ++i) bar.Advance();
    });
  }
  for (auto& thread : threads) thread.join();
  EXPECT_THAT(bar.Render(), HasSubstr("100% 4000/4000"));
  bar.Finish();
  std::rewind(sink);
  char buffer[4096] = {};
  const std::size_t n = std::fread(buffer, 1, sizeof(buffer) - 1, sink);
  EXPECT_THAT(std::string(buffer, n), HasSubstr("fit ["));
  std::fclose(sink);
}

TEST(ProgressTest, BarIsSilentWhenNotATerminal) {
  std::FILE* sink = std::tmpfile();
  TerminalProgressBar bar(sink);
  EXPECT_FALSE(bar.enabled());
  bar.Start("x", 10);
  bar.Advance(10);
  bar.Finish();
  EXPECT_EQ(std::ftell(sink), 0);
  std::fclose(sink);
}

}  // namespace
}  // namespace photomat
