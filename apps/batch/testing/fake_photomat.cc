// A photomat-like child for the batch runner's tests: each command line is one small action, so
// the tests choose exactly how a step behaves (writes, fails with photomat's error line, crashes,
// holds memory, sleeps), and `batch run-task` runs a task as the real photomat does.
#include <fmt/format.h>
#include <unistd.h>

#include <chrono>
#include <csignal>
#include <cstring>
#include <fstream>
#include <string>
#include <thread>
#include <vector>

#include "apps/batch/child_process.h"
#include "apps/batch/task_plan.h"
#include "apps/batch/task_runner.h"
#include "core/error.h"

namespace {

// One field of /proc/self/status in kB (VmRSS, VmHWM, RssAnon): the kernel's own account of this
// process, so the test can compare RunChild's measurement with what the child had.
long StatusKilobytes(const std::string& field) {
  std::ifstream status("/proc/self/status");
  std::string name;
  long value = 0;
  while (status >> name) {
    if (name == field + ":") {
      status >> value;
      return value;
    }
    status.ignore(1 << 20, '\n');
  }
  return -1;
}

int Run(const std::vector<std::string>& a) {
  using namespace photomat::batch;
  if (a.size() == 3 && a[0] == "write") {  // write FILE TEXT (relative to the working directory)
    std::ofstream(a[1]) << a[2];
    fmt::print("wrote {}\n", a[1]);
    return 0;
  }
  if (a.size() == 2 && a[0] == "fail") {  // fail FAULT: photomat's one error line
    fmt::print(stderr, "photomat: error: {}\n", a[1]);
    return 1;
  }
  if (a.size() == 1 && a[0] == "crash") {
    std::raise(SIGSEGV);
  }
  if (a.size() == 2 && a[0] == "allocate") {  // allocate MB: touch that much memory
    const long anon_before = StatusKilobytes("RssAnon");
    std::vector<char> block(std::stoul(a[1]) << 20);
    for (std::size_t i = 0; i < block.size(); i += 4096) block[i] = 1;
    // Anonymous pages stay resident (no swap in the test), file-backed ones may not: the anon
    // growth is exactly what was touched, the high-water mark is what RunChild must report.
    fmt::print("anon_growth_kb {}\nrss_kb {}\nhwm_kb {}\n",
               StatusKilobytes("RssAnon") - anon_before, StatusKilobytes("VmRSS"),
               StatusKilobytes("VmHWM"));
    return block[block.size() / 2] == 1 ? 0 : 2;
  }
  if (a.size() == 2 && a[0] == "sleep") {  // sleep SECONDS
    std::this_thread::sleep_for(std::chrono::duration<double>(std::stod(a[1])));
    return 0;
  }
  if (a.size() == 2 && a[0] == "count") {  // count FILE: one line per run, outside the task
    std::ofstream(a[1], std::ios::app) << getpid() << "\n";
    return 0;
  }
  if (a.size() == 1 && a[0] == "cpus") {  // how many CPUs this process may use
    fmt::print("cpus {}\n", AvailableCpus().size());
    return 0;
  }
  if (a.size() == 4 && a[0] == "batch" && a[1] == "run-task") {
    const TaskPlan plan = ReadTaskPlan(a[2]);
    const Task& task = plan.tasks.at(std::stoul(a[3]));
    const TaskRunResult result = RunTask(a[2], task, CurrentExecutable());
    return result.record.state == TaskState::kDone ? 0 : 1;
  }
  fmt::print(stderr, "photomat: error: fake_photomat: unknown command\n");
  return 2;
}

}  // namespace

int main(int argc, char** argv) {
  try {
    return Run(std::vector<std::string>(argv + 1, argv + argc));
  } catch (const std::exception& error) {
    fmt::print(stderr, "photomat: error: {}\n", error.what());
    return 1;
  }
}
