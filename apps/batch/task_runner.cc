#include "apps/batch/task_runner.h"

#include <fcntl.h>
#include <fmt/format.h>
#include <sys/file.h>
#include <unistd.h>

#include <atomic>
#include <cerrno>
#include <chrono>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <fstream>
#include <mutex>
#include <thread>

#include "apps/batch/batch_summary.h"
#include "apps/batch/child_process.h"
#include "core/atomic_file.h"
#include "core/error.h"

namespace photomat::batch {
namespace {

namespace fs = std::filesystem;

// An exclusive flock(2) held for the object's lifetime; released by the kernel if the process
// dies, so a killed run never leaves a stale lock.
class FileLock {
 public:
  // Throws Error naming `path` with `busy` when another process holds it.
  FileLock(const fs::path& path, const std::string& busy) {
    fd_ = ::open(path.c_str(), O_RDWR | O_CREAT | O_CLOEXEC, 0644);
    if (fd_ < 0) throw Error(path, fmt::format("cannot open lock: {}", std::strerror(errno)));
    if (flock(fd_, LOCK_EX | LOCK_NB) != 0) {
      const int err = errno;
      ::close(fd_);
      if (err == EWOULDBLOCK) throw Error(path, busy);
      throw Error(path, fmt::format("cannot lock: {}", std::strerror(err)));
    }
  }
  ~FileLock() { ::close(fd_); }
  FileLock(const FileLock&) = delete;
  FileLock& operator=(const FileLock&) = delete;

 private:
  int fd_ = -1;
};

void CreateFolders(const fs::path& folder) {
  std::error_code ec;
  fs::create_directories(folder, ec);
  if (ec) throw Error(folder, fmt::format("cannot create folder: {}", ec.message()));
}

std::string HostName() {
  char name[256] = {};
  if (gethostname(name, sizeof(name) - 1) != 0) return "unknown";
  return name;
}

std::string SlurmJob() {
  const char* job = std::getenv("SLURM_ARRAY_JOB_ID");
  const char* index = std::getenv("SLURM_ARRAY_TASK_ID");
  if (job == nullptr || index == nullptr) return "";
  return fmt::format("{}_{}", job, index);
}

// Appends one line to the task's log (the steps append their own output to the same file).
void AppendLog(const fs::path& log, const std::string& line) {
  std::ofstream out(log, std::ios::app | std::ios::binary);
  out << line << '\n';
}

std::uintmax_t FileSize(const fs::path& path) {
  std::error_code ec;
  const std::uintmax_t size = fs::file_size(path, ec);
  return ec ? 0 : size;
}

std::string ReadFrom(const fs::path& path, std::uintmax_t offset) {
  std::ifstream in(path, std::ios::binary);
  in.seekg(static_cast<std::streamoff>(offset));
  return std::string(std::istreambuf_iterator<char>(in), std::istreambuf_iterator<char>());
}

std::string TemporaryPrefix(const Task& task) {
  return fmt::format(".{}.partial-", task.folder.filename().string());
}

// Temporary folders of earlier attempts that were killed; only called under the task's lock.
void RemoveStaleTemporaries(const Task& task) {
  const std::string prefix = TemporaryPrefix(task);
  std::error_code ec;
  for (const auto& entry : fs::directory_iterator(task.folder.parent_path(), ec)) {
    if (entry.path().filename().string().starts_with(prefix)) fs::remove_all(entry.path(), ec);
  }
}

// Publishes `temp` as the task's final folder in one rename; an earlier result (of another
// recipe) is swapped out atomically and then removed.
void Commit(const fs::path& temp, const fs::path& folder) {
  std::error_code ec;
  if (fs::exists(folder, ec)) {
    if (renameat2(AT_FDCWD, temp.c_str(), AT_FDCWD, folder.c_str(), RENAME_EXCHANGE) != 0) {
      throw Error(folder, fmt::format("cannot replace: {}", std::strerror(errno)));
    }
    fs::remove_all(temp, ec);  // the old result, now under the temporary name
  } else if (::rename(temp.c_str(), folder.c_str()) != 0) {
    throw Error(folder,
                fmt::format("cannot rename {} to it: {}", temp.string(), std::strerror(errno)));
  }
  const int fd = ::open(folder.parent_path().c_str(), O_RDONLY | O_DIRECTORY | O_CLOEXEC);
  if (fd >= 0) {
    ::fsync(fd);  // best effort: the rename is what matters
    ::close(fd);
  }
}

struct StepFailure {
  std::string step, error;
};

// Runs the task's steps in `temp`, in order, until one fails; their peak memory goes into
// `record`.
std::optional<StepFailure> RunSteps(const Task& task, const fs::path& temp,
                                    const fs::path& photomat, const std::vector<int>& cpus,
                                    const fs::path& log, TaskRecord& record) {
  for (const TaskStep& step : task.steps) {
    AppendLog(log, "$ " + ShellCommand("photomat", step.arguments));
    const std::uintmax_t offset = FileSize(log);
    ChildCommand command{photomat, step.arguments, temp, ChildOutput::kAppendToFile, log, cpus};
    ChildOutcome outcome;
    try {
      outcome = RunChild(command);
    } catch (const Error& error) {
      return StepFailure{step.name, error.what()};
    }
    record.peak_rss_bytes = std::max(record.peak_rss_bytes, outcome.peak_rss_bytes);
    if (!outcome.Succeeded()) {
      const std::string error = PhotomatErrorLine(ReadFrom(log, offset));
      return StepFailure{step.name, error.empty() ? "photomat " + outcome.Describe() : error};
    }
  }
  return std::nullopt;
}

std::string FormatBytes(std::int64_t bytes) {
  return fmt::format("{:.0f} MB", static_cast<double>(bytes) / (1024.0 * 1024.0));
}

// The outcome line `batch run` prints as each task ends.
std::string DescribeResult(const Task& task, const TaskRecord& record) {
  if (record.state == TaskState::kDone) {
    return fmt::format("{}: done in {:.1f} s (peak {})", task.name, record.elapsed_seconds,
                       FormatBytes(record.peak_rss_bytes));
  }
  return fmt::format("{}: FAILED at {}: {}", task.name, record.failed_step, record.error);
}

}  // namespace

std::string PhotomatErrorLine(const std::string& output) {
  constexpr std::string_view kPrefix = "photomat: error: ";
  std::string found;
  std::size_t start = 0;
  while (start < output.size()) {
    std::size_t end = output.find('\n', start);
    if (end == std::string::npos) end = output.size();
    const std::string_view line(output.data() + start, end - start);
    if (line.starts_with(kPrefix)) found = std::string(line.substr(kPrefix.size()));
    start = end + 1;
  }
  return found;
}

TaskRunResult RunTask(const fs::path& batch_dir, const Task& task, const fs::path& photomat,
                      const std::vector<int>& cpus) {
  CreateFolders(batch_dir / "records");
  CreateFolders(batch_dir / "logs");
  const fs::path record_path = RecordPath(batch_dir, task);
  const FileLock lock(fs::path(record_path).replace_extension(".lock"),
                      fmt::format("task {} ({}) is already running", task.index, task.name));
  if (std::optional<TaskRecord> done = DoneRecord(task)) return {*done, true};

  const fs::path log = LogPath(batch_dir, task);
  const auto start = std::chrono::steady_clock::now();
  TaskRecord record;
  const std::optional<TaskRecord> previous = ReadTaskRecord(record_path);
  record.attempt = (previous ? previous->attempt : 0) + 1;
  record.hash = task.hash;
  record.host = HostName();
  record.pid = static_cast<int>(getpid());
  record.slurm_job = SlurmJob();
  WriteTaskRecord(record_path, record);
  AppendLog(log, fmt::format("=== attempt {} of task {} ({}) on {}, pid {}{}", record.attempt,
                             task.index, task.name, record.host, record.pid,
                             record.slurm_job.empty() ? "" : ", Slurm job " + record.slurm_job));

  const auto fail = [&](const std::string& step, const std::string& error) {
    record.state = TaskState::kFailed;
    record.failed_step = step;
    record.error = error;
    record.elapsed_seconds =
        std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
    AppendLog(log, fmt::format("=== attempt {} failed at {}: {}", record.attempt, step, error));
    WriteTaskRecord(record_path, record);
    return TaskRunResult{record, false};
  };

  std::error_code ec;
  CreateFolders(task.folder.parent_path());
  if (fs::exists(task.folder, ec) && !fs::exists(DoneRecordPath(task), ec)) {
    return fail("start",
                fmt::format("{}: exists and was not written by photomat batch; move it away",
                            task.folder.string()));
  }
  RemoveStaleTemporaries(task);
  const fs::path temp = task.folder.parent_path() /
                        fmt::format("{}{}-{}", TemporaryPrefix(task), record.host, record.pid);
  CreateFolders(temp);
  if (const std::optional<StepFailure> failure =
          RunSteps(task, temp, photomat, cpus, log, record)) {
    fs::remove_all(temp, ec);
    return fail(failure->step, failure->error);
  }
  record.state = TaskState::kDone;
  record.elapsed_seconds =
      std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  try {
    WriteTaskRecord(temp / kDoneRecordName, record);
    Commit(temp, task.folder);
  } catch (const Error& error) {
    fs::remove_all(temp, ec);
    return fail("commit", error.what());
  }
  AppendLog(log,
            fmt::format("=== attempt {} done in {:.2f} s", record.attempt, record.elapsed_seconds));
  WriteTaskRecord(record_path, record);
  return {record, false};
}

int DefaultWorkers(int threads_per_task) {
  const int cores = static_cast<int>(AvailableCpus().size());
  return std::max(1, cores / std::max(1, threads_per_task));
}

BatchRunResult RunBatch(const fs::path& batch_dir, const BatchRunOptions& options) {
  const FileLock lock(batch_dir / ".batch-run.lock",
                      "another `photomat batch run` is using this batch folder");
  const TaskPlan plan = ReadTaskPlan(batch_dir);
  const fs::path photomat = options.photomat.empty() ? CurrentExecutable() : options.photomat;
  const int threads = std::max(1, options.threads_per_task);
  const int workers = options.workers > 0 ? options.workers : DefaultWorkers(threads);
  CreateFolders(batch_dir / "logs");

  BatchRunResult result;
  result.tasks = static_cast<int>(plan.tasks.size());
  std::vector<int> pending;
  for (const Task& task : plan.tasks) {
    if (IsTaskDone(task)) {
      ++result.already_done;
    } else {
      pending.push_back(task.index);
    }
  }
  fmt::print("batch {}: {} tasks, {} already done, {} to run on {} worker(s){}\n",
             batch_dir.string(), result.tasks, result.already_done, pending.size(), workers,
             options.pin_cpus ? fmt::format(" ({} core(s) each)", threads) : "");
  std::fflush(stdout);

  const std::vector<int> cpus = AvailableCpus();
  std::atomic<std::size_t> next{0};
  std::mutex mutex;  // guards `result` and the printed lines
  int finished = result.already_done;
  const auto work = [&](int slot) {
    // Pinned: this worker's share of the cores; TBB in each step sizes its pool from it.
    std::vector<int> share;
    for (int t = 0; options.pin_cpus && t < threads; ++t) {
      share.push_back(cpus[static_cast<std::size_t>(slot * threads + t) % cpus.size()]);
    }
    for (std::size_t i = next++; i < pending.size(); i = next++) {
      const Task& task = plan.tasks[static_cast<std::size_t>(pending[i])];
      TaskRecord record;
      try {
        record = RunTask(batch_dir, task, photomat, share).record;
      } catch (const Error& error) {
        // The task could not be attempted (e.g. it is running elsewhere).
        record.state = TaskState::kFailed;
        record.failed_step = "start";
        record.error = error.what();
      }
      const std::lock_guard<std::mutex> guard(mutex);
      ++finished;
      if (record.state == TaskState::kDone) {
        ++result.done;
      } else {
        result.failed.push_back(task.index);
      }
      fmt::print("[{}/{}] {}\n", finished, result.tasks, DescribeResult(task, record));
      std::fflush(stdout);
    }
  };
  std::vector<std::thread> pool;
  for (int w = 0; w < std::min<int>(workers, static_cast<int>(pending.size())); ++w) {
    pool.emplace_back(work, w);
  }
  for (std::thread& thread : pool) thread.join();
  std::sort(result.failed.begin(), result.failed.end());

  const BatchSummary summary = SummariseBatch(batch_dir, plan);
  WriteBatchSummary(batch_dir, summary);
  fmt::print("{}", FormatSummaryTable(summary));
  return result;
}

}  // namespace photomat::batch
