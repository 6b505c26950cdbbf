#pragma once

#include <sys/types.h>

#include <cstdint>
#include <filesystem>
#include <string>
#include <vector>

namespace photomat::batch {

// Where a child's standard output and error go.
enum class ChildOutput {
  kInherit,       // the parent's
  kAppendToFile,  // appended to ChildCommand::log (created if missing)
  kCapture,       // collected into ChildOutcome::output
};

struct ChildCommand {
  std::filesystem::path executable;
  std::vector<std::string> arguments;       // argv[1...]
  std::filesystem::path working_directory;  // empty: the parent's
  ChildOutput output = ChildOutput::kInherit;
  std::filesystem::path log;  // for kAppendToFile
  // CPUs the child may run on (sched_setaffinity); empty: the parent's. TBB sizes its thread pool
  // from this mask, so it is how a worker gives each photomat child its share of the cores.
  std::vector<int> cpus;
};

struct ChildOutcome {
  int exit_code = -1;  // -1 when ended by a signal
  int signal = 0;      // the signal that ended it, or 0
  // Peak resident memory of the child and of the descendants it waited for (wait4's ru_maxrss).
  // It also counts the child's forked copy of the parent before exec, so it reads at least the
  // parent's resident size: for `batch run-task` (a photomat, about 150 MB at start) no more
  // than any photomat child uses before it reads a capture.
  std::int64_t peak_rss_bytes = 0;
  double wall_seconds = 0;
  std::string output;  // kCapture only

  bool Succeeded() const { return exit_code == 0; }
  // "exit status 1" or "killed by signal 9 (Killed)".
  std::string Describe() const;
};

// A started child process. It dies with the thread that started it (PR_SET_PDEATHSIG = SIGKILL),
// so a batch killed at any moment takes its whole process tree with it instead of leaving
// orphans that would go on writing. Start and Wait it on the same thread.
class ChildProcess {
 public:
  // Throws Error naming the executable when it cannot be started.
  explicit ChildProcess(const ChildCommand& command);
  ~ChildProcess();  // kills (SIGKILL) and reaps a child that was not waited for
  ChildProcess(const ChildProcess&) = delete;
  ChildProcess& operator=(const ChildProcess&) = delete;

  pid_t pid() const { return pid_; }
  ChildOutcome Wait();

 private:
  pid_t pid_ = -1;
  int capture_fd_ = -1;
  bool waited_ = false;
  double start_seconds_ = 0;
};

// Starts `command` and waits for it.
ChildOutcome RunChild(const ChildCommand& command);

// The path of the running executable (/proc/self/exe, resolved), so that a batch runs its tasks
// with exactly the photomat that planned them; for one of photomat's subcommand programs
// (libexec/photomat/photomat-batch), the `photomat` that started it (bin/photomat).
std::filesystem::path CurrentExecutable();

// `name` looked up in $PATH (as a shell would); Error when no executable of that name is there.
std::filesystem::path FindInPath(const std::string& name);

// The CPUs this process may run on (its affinity mask), in increasing order.
std::vector<int> AvailableCpus();

}  // namespace photomat::batch
