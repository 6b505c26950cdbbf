#include "apps/batch/child_process.h"

#include <fmt/format.h>
#include <gmock/gmock.h>
#include <gtest/gtest.h>
#include <sys/wait.h>
#include <unistd.h>

#include <chrono>
#include <csignal>
#include <cstdio>
#include <fstream>
#include <thread>

#include "core/atomic_file.h"
#include "core/error.h"
#include "tests/support/test_support.h"

namespace photomat::batch {
namespace {

namespace fs = std::filesystem;
using photomat::testing::TempDir;
using ::testing::HasSubstr;

ChildCommand Shell(const std::string& script) {
  ChildCommand command;
  command.executable = "/bin/sh";
  command.arguments = {"-c", script};
  command.output = ChildOutput::kCapture;
  return command;
}

fs::path FakePhotomat() {
  return photomat::testing::PhotomatExecutable().parent_path().parent_path() / "tests" /
         "fake_photomat";
}

TEST(ChildProcessTest, ExitStatusSignalAndOutput) {
  const ChildOutcome ok = RunChild(Shell("echo out; echo err >&2"));
  EXPECT_TRUE(ok.Succeeded());
  EXPECT_EQ(ok.output, "out\nerr\n");
  EXPECT_GT(ok.wall_seconds, 0.0);
  const ChildOutcome failed = RunChild(Shell("exit 3"));
  EXPECT_EQ(failed.exit_code, 3);
  EXPECT_EQ(failed.Describe(), "exit status 3");
  const ChildOutcome killed = RunChild(Shell("kill -SEGV $$"));
  EXPECT_EQ(killed.exit_code, -1);
  EXPECT_EQ(killed.signal, SIGSEGV);
  EXPECT_THAT(killed.Describe(), HasSubstr("killed by signal 11"));
}

TEST(ChildProcessTest, WorkingDirectoryAndAppendedLog) {
  TempDir dir;
  ChildCommand command = Shell("pwd; echo second");
  command.working_directory = dir.path();
  command.output = ChildOutput::kAppendToFile;
  command.log = dir / "log.txt";
  photomat::testing::WriteFile(command.log, "first\n");
  ASSERT_TRUE(RunChild(command).Succeeded());
  EXPECT_EQ(ReadTextFile(command.log), "first\n" + dir.path().string() + "\nsecond\n");
}

TEST(ChildProcessTest, AnExecutableThatCannotRunIsAnErrorNamingIt) {
  ChildCommand command;
  command.executable = "/nonexistent/photomat";
  try {
    RunChild(command);
    FAIL() << "no error";
  } catch (const Error& error) {
    EXPECT_THAT(error.what(), HasSubstr("/nonexistent/photomat: cannot run: No such file"));
  }
}

TEST(ChildProcessTest, PeakMemoryFollowsWhatTheChildTouches) {
  ChildCommand command;
  command.executable = FakePhotomat();
  command.arguments = {"allocate", "300"};
  command.output = ChildOutput::kCapture;
  const ChildOutcome outcome = RunChild(command);
  ASSERT_TRUE(outcome.Succeeded()) << outcome.Describe();
  // The child reports the kernel's own account (/proc/self/status) after touching 300 MiB. Its
  // anonymous growth is the 300 MiB plus at most the allocator's bookkeeping (measured 307200 kB;
  // 1 MiB of room). The program's file-backed pages vary between runs, so the peak is compared
  // with the child's own high-water mark, not with a second run.
  long anon_growth_kb = 0, rss_kb = 0, hwm_kb = 0;
  ASSERT_EQ(std::sscanf(outcome.output.c_str(), "anon_growth_kb %ld rss_kb %ld hwm_kb %ld",
                        &anon_growth_kb, &rss_kb, &hwm_kb),
            3)
      << outcome.output;
  EXPECT_GE(anon_growth_kb, 300L << 10);
  EXPECT_LT(anon_growth_kb, 301L << 10);
  EXPECT_GE(hwm_kb, rss_kb);
  // ru_maxrss is the kernel's high-water mark at exit, the same counter as VmHWM; the two differ
  // by the pages still held in per-thread counter caches when /proc was read (measured 88 kB
  // below). 1 MiB of room either side: a second run of the program is not the reference.
  EXPECT_NEAR(static_cast<double>(outcome.peak_rss_bytes), hwm_kb * 1024.0, 1 << 20);
}

TEST(ChildProcessTest, CpusLimitTheChildsAffinity) {
  ChildCommand command;
  command.executable = FakePhotomat();
  command.arguments = {"cpus"};
  command.output = ChildOutput::kCapture;
  command.cpus = {AvailableCpus().front()};
  EXPECT_EQ(RunChild(command).output, "cpus 1\n");
  command.cpus = {};
  EXPECT_EQ(RunChild(command).output, fmt::format("cpus {}\n", AvailableCpus().size()));
}

// A child outlives neither the thread nor the process that started it: a killed batch leaves no
// orphan writing on.
TEST(ChildProcessTest, ChildDiesWithItsParent) {
  int pipe_fds[2];
  ASSERT_EQ(pipe(pipe_fds), 0);
  const pid_t parent = fork();
  if (parent == 0) {
    ChildProcess child(Shell("sleep 30"));
    const pid_t pid = child.pid();
    [[maybe_unused]] ssize_t n = write(pipe_fds[1], &pid, sizeof(pid));
    _exit(0);  // no destructor: only PR_SET_PDEATHSIG can end the child
  }
  pid_t grandchild = 0;
  ASSERT_EQ(read(pipe_fds[0], &grandchild, sizeof(grandchild)),
            static_cast<ssize_t>(sizeof(grandchild)));
  waitpid(parent, nullptr, 0);
  bool gone = false;
  for (int i = 0; i < 100 && !gone; ++i) {
    // Gone, or a zombie waiting for a pid 1 that does not reap.
    std::ifstream stat("/proc/" + std::to_string(grandchild) + "/stat");
    std::string pid, name, state;
    gone = !(stat >> pid >> name >> state) || state == "Z";
    if (!gone) std::this_thread::sleep_for(std::chrono::milliseconds(20));
  }
  EXPECT_TRUE(gone) << "child " << grandchild << " outlived its parent";
  close(pipe_fds[0]);
  close(pipe_fds[1]);
}

TEST(ChildProcessTest, FindInPathAndCurrentExecutable) {
  EXPECT_EQ(FindInPath("sh").filename(), "sh");
  EXPECT_THROW(FindInPath("no-such-program-photomat"), Error);
  EXPECT_EQ(CurrentExecutable().filename(), "batch_test");
}

}  // namespace
}  // namespace photomat::batch
