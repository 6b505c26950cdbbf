#include "apps/batch/child_process.h"

#include <fcntl.h>
#include <fmt/format.h>
#include <sched.h>
#include <sys/prctl.h>
#include <sys/resource.h>
#include <sys/wait.h>
#include <unistd.h>

#include <cerrno>
#include <chrono>
#include <csignal>
#include <cstdlib>
#include <cstring>
#include <string_view>

#include "core/error.h"

namespace photomat::batch {
namespace {

double NowSeconds() {
  return std::chrono::duration<double>(std::chrono::steady_clock::now().time_since_epoch()).count();
}

// Only async-signal-safe calls between fork and exec: the parent may have other threads.
[[noreturn]] void ExecChild(char* const* argv, const char* working_directory, int output_fd,
                            const cpu_set_t* cpus, pid_t parent, int error_fd) {
  int err = 0;
  if (prctl(PR_SET_PDEATHSIG, SIGKILL) != 0) err = errno;
  // The parent may have died before prctl: then nobody would kill us.
  if (err == 0 && getppid() != parent) _exit(127);
  if (err == 0 && output_fd >= 0) {
    if (dup2(output_fd, STDOUT_FILENO) < 0 || dup2(output_fd, STDERR_FILENO) < 0) err = errno;
  }
  if (err == 0 && working_directory != nullptr && chdir(working_directory) != 0) err = errno;
  if (err == 0 && cpus != nullptr && sched_setaffinity(0, sizeof(cpu_set_t), cpus) != 0) {
    err = errno;
  }
  if (err == 0) {
    execv(argv[0], argv);
    err = errno;
  }
  // Tell the parent why, through the close-on-exec pipe.
  [[maybe_unused]] const ssize_t written = write(error_fd, &err, sizeof(err));
  _exit(127);
}

}  // namespace

std::string ChildOutcome::Describe() const {
  if (signal != 0) return fmt::format("killed by signal {} ({})", signal, strsignal(signal));
  return fmt::format("exit status {}", exit_code);
}

ChildProcess::ChildProcess(const ChildCommand& command) {
  std::vector<std::string> strings{command.executable.string()};
  strings.insert(strings.end(), command.arguments.begin(), command.arguments.end());
  std::vector<char*> argv;
  for (std::string& s : strings) argv.push_back(s.data());
  argv.push_back(nullptr);
  const std::string working_directory = command.working_directory.string();

  int output_fd = -1;
  int capture[2] = {-1, -1};
  if (command.output == ChildOutput::kAppendToFile) {
    output_fd = ::open(command.log.c_str(), O_WRONLY | O_CREAT | O_APPEND | O_CLOEXEC, 0644);
    if (output_fd < 0) {
      throw Error(command.log, fmt::format("cannot open log: {}", std::strerror(errno)));
    }
  } else if (command.output == ChildOutput::kCapture) {
    if (pipe2(capture, O_CLOEXEC) != 0) {
      throw Error(fmt::format("cannot create a pipe: {}", std::strerror(errno)));
    }
    output_fd = capture[1];
  }
  cpu_set_t cpus;
  CPU_ZERO(&cpus);
  for (int cpu : command.cpus) CPU_SET(cpu, &cpus);
  int error_pipe[2];
  if (pipe2(error_pipe, O_CLOEXEC) != 0) {
    if (output_fd >= 0) ::close(output_fd);
    if (capture[0] >= 0) ::close(capture[0]);
    throw Error(fmt::format("cannot create a pipe: {}", std::strerror(errno)));
  }
  const pid_t parent = getpid();
  start_seconds_ = NowSeconds();
  pid_ = fork();
  if (pid_ == 0) {
    ExecChild(argv.data(), working_directory.empty() ? nullptr : working_directory.c_str(),
              output_fd, command.cpus.empty() ? nullptr : &cpus, parent, error_pipe[1]);
  }
  const int fork_errno = errno;
  ::close(error_pipe[1]);
  if (output_fd >= 0) ::close(output_fd);
  capture_fd_ = capture[0];
  if (pid_ < 0) {
    ::close(error_pipe[0]);
    if (capture_fd_ >= 0) ::close(capture_fd_);
    throw Error(command.executable,
                fmt::format("cannot start a process: {}", std::strerror(fork_errno)));
  }
  int exec_errno = 0;
  const ssize_t got = read(error_pipe[0], &exec_errno, sizeof(exec_errno));
  ::close(error_pipe[0]);
  if (got == sizeof(exec_errno)) {
    Wait();
    throw Error(command.executable, fmt::format("cannot run: {}", std::strerror(exec_errno)));
  }
}

ChildProcess::~ChildProcess() {
  if (!waited_ && pid_ > 0) {
    ::kill(pid_, SIGKILL);
    Wait();
  }
  if (capture_fd_ >= 0) ::close(capture_fd_);
}

ChildOutcome ChildProcess::Wait() {
  ChildOutcome outcome;
  if (capture_fd_ >= 0) {
    char buffer[4096];
    while (true) {
      const ssize_t n = read(capture_fd_, buffer, sizeof(buffer));
      if (n > 0) {
        outcome.output.append(buffer, static_cast<std::size_t>(n));
      } else if (n == 0 || errno != EINTR) {
        break;
      }
    }
    ::close(capture_fd_);
    capture_fd_ = -1;
  }
  int status = 0;
  rusage usage{};
  while (wait4(pid_, &status, 0, &usage) < 0) {
    if (errno != EINTR) throw Error(fmt::format("wait4: {}", std::strerror(errno)));
  }
  waited_ = true;
  outcome.wall_seconds = NowSeconds() - start_seconds_;
  outcome.peak_rss_bytes = static_cast<std::int64_t>(usage.ru_maxrss) * 1024;  // kB on Linux
  if (WIFEXITED(status)) outcome.exit_code = WEXITSTATUS(status);
  if (WIFSIGNALED(status)) outcome.signal = WTERMSIG(status);
  return outcome;
}

ChildOutcome RunChild(const ChildCommand& command) { return ChildProcess(command).Wait(); }

std::filesystem::path CurrentExecutable() {
  std::error_code ec;
  const std::filesystem::path path = std::filesystem::read_symlink("/proc/self/exe", ec);
  if (ec) throw Error("/proc/self/exe", fmt::format("cannot resolve: {}", ec.message()));
  // photomat's subcommand programs live in PREFIX/libexec/photomat/ and are started by
  // PREFIX/bin/photomat: a task's command lines are photomat's, so they run the dispatcher.
  const std::filesystem::path folder = path.parent_path();
  if (folder.filename() == "photomat" && folder.parent_path().filename() == "libexec") {
    const std::filesystem::path dispatcher =
        folder.parent_path().parent_path() / "bin" / "photomat";
    if (std::filesystem::exists(dispatcher)) return dispatcher;
  }
  return path;
}

std::filesystem::path FindInPath(const std::string& name) {
  const char* path = std::getenv("PATH");
  std::string_view rest = path ? path : "/usr/local/bin:/usr/bin:/bin";
  while (!rest.empty()) {
    const std::size_t colon = std::min(rest.find(':'), rest.size());
    const std::filesystem::path candidate =
        std::filesystem::path(rest.substr(0, colon).empty() ? "." : rest.substr(0, colon)) / name;
    if (::access(candidate.c_str(), X_OK) == 0) return candidate;
    rest.remove_prefix(std::min(colon + 1, rest.size()));
  }
  throw Error(fmt::format("{}: not found in PATH", name));
}

std::vector<int> AvailableCpus() {
  cpu_set_t set;
  CPU_ZERO(&set);
  std::vector<int> cpus;
  if (sched_getaffinity(0, sizeof(set), &set) == 0) {
    for (int cpu = 0; cpu < CPU_SETSIZE; ++cpu) {
      if (CPU_ISSET(cpu, &set)) cpus.push_back(cpu);
    }
  }
  if (cpus.empty()) cpus.push_back(0);
  return cpus;
}

}  // namespace photomat::batch
