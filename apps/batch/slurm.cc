#include "apps/batch/slurm.h"

#include <fmt/format.h>
#include <unistd.h>

#include <algorithm>
#include <cctype>
#include <cmath>
#include <csignal>
#include <string>
#include <string_view>

#include "capture/io/load_photometric_set.h"
#include "core/atomic_file.h"
#include "core/error.h"
#include "core/json_file.h"
#include "relight/web/report_pictures.h"
#include "relight/web/viewer_pyramid.h"
#include "represent/model/method.h"

namespace photomat::batch {
namespace {

namespace fs = std::filesystem;

// A task never measured needs what its largest step needs. Every step needs kBaseBytes, the
// resident size of a photomat process before it reads a capture (measured: 148 MB for
// `photomat --version`), and then:
// - a step that holds the whole set (StepHoldsWholeSet): kWholeSetBytesPerPixelImage
//   (capture/io/load_photometric_set.h) x pixels x images,
//   what in-memory fitting and evaluation add per pixel and image (the test recipe's measured
//   peaks: 150 MB at 32 x 24 x 36, 198 MB at 192 x 192 x 36, i.e. 36 bytes; 40 with a little
//   room);
// - a streamed step (fit; maps and viewer from the stacks): kStreamedStepBytes for its bands (64
//   MiB by default, two at a time), decoders' chunks and writers, plus kStreamedBytesPerPixel x
//   pixels for what grows with the image: the tiled Poisson height's coarse grid, a dark frame
//   (12 bytes per pixel) while calibrating.
//   Measured at 8688 x 5792 x 50 (README "Streamed fitting", "Web viewer and evaluation
//   report"): fit 246-279 MB, the maps' export 394 MB, the export of the viewer's maps 977 MB
//   peak RSS; the estimate there is 2.0 GB. (The maps' export streams whenever the in-memory
//   one would not fit the memory limit, which Slurm's --mem sets.)
// - except the viewer of stacks up to kViewerTilingThresholdPixels, which is made in memory
//   whatever the limit: kInMemoryViewerBytesPerPixel x pixels (measured at 2048 x 2048: 226
//   bytes per pixel for one PTM stack, 505 for Gradient, PTM and HSH9 together (54 maps); at
//   4096 x 3072 for PTM, 217; 600 covers about 65 maps).
// - except the maps with `--height fc` (from the stacks, or from the capture's stack fitted in
//   bands): streamed too, but the whole-map FFT holds the gradient field and its spectra
//   (ExportMapsStreamed: about 41 bytes per pixel), so kFcMapsFixedBytes for the bands and
//   buffers plus kFcMapsBytesPerPixel x pixels. Measured at 4096 x 3072 x 50 (`export CAPTURE
//   --stream --out maps --height fc`, 2026-12-06, after the FFT height streamed): Gradient 742
//   MiB, PTM 754 MiB peak RSS (before, with the stack loaded whole and the in-memory export: 1317
//   and 8566 MiB); the estimate is 854 MiB.
// - a streamed evaluation with a report adds its pictures, held at display size
//   (relight/web/report_pictures.h: at most kReportDisplaySide on the longer side, 8 bytes per
//   value): the 3 images shown captured, relit and predicted by every method (RGB), a heat map
//   per method and the mask. Measured at 4096 x 3072 x 50 (`evaluate --stream --methods
//   gradient,ptm --hold-out-every 8 --report`, 2026-12-06): 601 MiB peak RSS, 285 MiB without
//   the report; the estimate is 1174 MiB (the streamed step's 790, 384 for the pictures).
// The request adds --mem-margin on top.
constexpr std::int64_t kBaseBytes = 150LL << 20;
constexpr std::int64_t kStreamedStepBytes = 256LL << 20;
constexpr double kStreamedBytesPerPixel = 32.0;
constexpr double kInMemoryViewerBytesPerPixel = 600.0;
constexpr std::int64_t kFcMapsFixedBytes = 128LL << 20;
constexpr double kFcMapsBytesPerPixel = 48.0;
constexpr std::size_t kMaxArrayIndices = 1000;

// The value after `option` in the step's arguments, or `otherwise`.
std::string OptionValue(const TaskStep& step, std::string_view option, std::string otherwise) {
  const auto found = std::find(step.arguments.begin(), step.arguments.end(), option);
  return found != step.arguments.end() && found + 1 != step.arguments.end() ? *(found + 1)
                                                                            : otherwise;
}

// The report's pictures of a streamed evaluation (above).
double ReportPictureBytes(const TaskStep& step, const Task& task) {
  if (step.name != "evaluate" ||
      std::find(step.arguments.begin(), step.arguments.end(), "--report") == step.arguments.end()) {
    return 0.0;
  }
  const auto methods =
      static_cast<double>(ParseMethodList(OptionValue(step, "--methods", "all")).size());
  const double side = kReportDisplaySide;
  const double display_pixels = std::min(static_cast<double>(task.pixels), side * side);
  constexpr double kShown = 3;
  return 8.0 * display_pixels * (3 * kShown * (1 + 2 * methods) + methods + 1);
}

double StepNeedBytes(const TaskStep& step, const Task& task) {
  const auto pixels = static_cast<double>(task.pixels);
  if (StepHoldsWholeSet(step))
    return kWholeSetBytesPerPixelImage * static_cast<double>(task.pixel_images);
  if (step.name == "maps" && OptionValue(step, "--height", "poisson") == "fc") {
    return static_cast<double>(kFcMapsFixedBytes) + kFcMapsBytesPerPixel * pixels;
  }
  if (step.name == "viewer" &&
      task.pixels <= static_cast<std::uint64_t>(kViewerTilingThresholdPixels)) {
    return kInMemoryViewerBytesPerPixel * pixels;
  }
  return static_cast<double>(kStreamedStepBytes) + kStreamedBytesPerPixel * pixels +
         ReportPictureBytes(step, task);
}

std::vector<std::string> SplitWords(const std::string& text) {
  std::vector<std::string> words;
  std::string word;
  for (char c : text) {
    if (std::isspace(static_cast<unsigned char>(c))) {
      if (!word.empty()) words.push_back(word), word.clear();
    } else {
      word += c;
    }
  }
  if (!word.empty()) words.push_back(word);
  return words;
}

// One "#SBATCH ..." line per option: a word starting with '-' opens a line, the words after it
// (an option's separate value) join it.
std::vector<std::string> Directives(const SlurmOptions& options) {
  std::vector<std::string> lines;
  if (!options.partition.empty()) lines.push_back("--partition=" + options.partition);
  if (!options.time.empty()) lines.push_back("--time=" + options.time);
  if (!options.account.empty()) lines.push_back("--account=" + options.account);
  if (!options.qos.empty()) lines.push_back("--qos=" + options.qos);
  for (const std::string& word : SplitWords(options.extra_sbatch)) {
    if (word.starts_with("-") || lines.empty()) {
      lines.push_back(word);
    } else {
      lines.back() += " " + word;
    }
  }
  return lines;
}

std::string Quote(const std::string& text) { return ShellCommand("", {text}).substr(1); }

fs::path JobsFile(const fs::path& batch_dir) { return batch_dir / "slurm" / "jobs.json"; }

// "12" or "12;cluster" (sbatch --parsable).
std::string ParsableJobId(const ChildOutcome& outcome, const fs::path& script) {
  std::string id = outcome.output.substr(0, outcome.output.find_first_of(";\n"));
  const bool numeric = !id.empty() && std::all_of(id.begin(), id.end(), [](char c) {
    return std::isdigit(static_cast<unsigned char>(c));
  });
  if (!outcome.Succeeded() || !numeric) {
    std::string message = outcome.output;
    while (!message.empty() && std::isspace(static_cast<unsigned char>(message.back())))
      message.pop_back();
    throw Error(script, fmt::format("sbatch failed ({}): {}", outcome.Describe(), message));
  }
  return id;
}

nlohmann::json SubmissionJson(const SlurmSubmission& submission) {
  nlohmann::json arrays = nlohmann::json::array();
  for (const SlurmArray& array : submission.arrays) {
    arrays.push_back({{"job", array.job},
                      {"tasks", array.tasks},
                      {"memory", array.memory},
                      {"script", array.script.string()}});
  }
  return {{"arrays", arrays}, {"summary_job", submission.summary_job}};
}

void AppendSubmission(const fs::path& batch_dir, const SlurmSubmission& submission) {
  nlohmann::json document = {{"submissions", nlohmann::json::array()}};
  if (fs::exists(JobsFile(batch_dir))) document = ReadJsonFile(JobsFile(batch_dir));
  document["submissions"].push_back(SubmissionJson(submission));
  WriteJsonFile(JobsFile(batch_dir), document);
}

std::vector<std::string> JobIds(const SlurmSubmission& submission) {
  std::vector<std::string> ids;
  for (const SlurmArray& array : submission.arrays) ids.push_back(array.job);
  if (!submission.summary_job.empty()) ids.push_back(submission.summary_job);
  return ids;
}

// States a job has left the queue in; squeue still lists them for MinJobAge (300 s by default)
// when asked for the job by id.
bool HasEnded(const std::string& state) {
  static const char* const kEnded[] = {"COMPLETED",     "CANCELLED", "FAILED",      "TIMEOUT",
                                       "NODE_FAIL",     "PREEMPTED", "BOOT_FAIL",   "DEADLINE",
                                       "OUT_OF_MEMORY", "REVOKED",   "SPECIAL_EXIT"};
  return std::find(std::begin(kEnded), std::end(kEnded), state) != std::end(kEnded);
}

// squeue's states of the submission's jobs, keyed "JOB_INDEX" (array tasks) or "JOB", split into
// those still queued or running and those that ended recently.
struct JobStates {
  std::map<std::string, std::string> queued, ended;
};
JobStates QueryQueue(const SlurmSubmission& submission, const SlurmClient& slurm) {
  const std::vector<std::string> ids = JobIds(submission);
  JobStates states;
  if (ids.empty()) return states;
  // Exits non-zero when every id has left slurmctld's memory; the output is then empty.
  const ChildOutcome queue =
      slurm({"squeue", "-h", "-r", "-o", "%i|%T", "-j", fmt::format("{}", fmt::join(ids, ","))});
  for (const auto& [job, state] : ParseJobStates(queue.output)) {
    (HasEnded(state) ? states.ended : states.queued)[job] = state;
  }
  return states;
}

std::string Lower(std::string text) {
  for (char& c : text) c = static_cast<char>(std::tolower(static_cast<unsigned char>(c)));
  return text;
}

}  // namespace

std::int64_t TaskMemoryNeedBytes(const Task& task, const std::optional<TaskRecord>& last_attempt) {
  if (last_attempt && last_attempt->peak_rss_bytes > 0) return last_attempt->peak_rss_bytes;
  std::int64_t step_need = 0;
  for (const TaskStep& step : task.steps) {
    step_need =
        std::max(step_need, static_cast<std::int64_t>(std::ceil(StepNeedBytes(step, task))));
  }
  return kBaseBytes + step_need;
}

std::int64_t MemoryRequestMib(std::int64_t need_bytes, double margin) {
  const double mib = static_cast<double>(need_bytes) * margin / (1024.0 * 1024.0);
  const std::int64_t rounded = static_cast<std::int64_t>(std::ceil(mib / 64.0)) * 64;
  return std::max<std::int64_t>(256, rounded);
}

SlurmClient SystemSlurmClient() {
  return [](const std::vector<std::string>& argv) {
    ChildCommand command;
    command.executable = FindInPath(argv.at(0));
    command.arguments.assign(argv.begin() + 1, argv.end());
    command.output = ChildOutput::kCapture;
    return RunChild(command);
  };
}

std::vector<SlurmArray> PlanArrays(const fs::path& batch_dir, const TaskPlan& plan,
                                   const SlurmOptions& options) {
  std::map<std::string, std::vector<int>> groups;  // memory request -> tasks
  for (const Task& task : plan.tasks) {
    if (IsTaskDone(task)) continue;
    const std::string memory =
        options.memory.empty()
            ? fmt::format("{}M",
                          MemoryRequestMib(TaskMemoryNeedBytes(task, LastAttempt(batch_dir, task)),
                                           options.memory_margin))
            : options.memory;
    groups[memory].push_back(task.index);
  }
  std::vector<SlurmArray> arrays;
  for (const auto& [memory, tasks] : groups) {
    for (std::size_t start = 0; start < tasks.size(); start += kMaxArrayIndices) {
      SlurmArray array;
      array.memory = memory;
      array.tasks.assign(
          tasks.begin() + static_cast<long>(start),
          tasks.begin() + static_cast<long>(std::min(tasks.size(), start + kMaxArrayIndices)));
      arrays.push_back(std::move(array));
    }
  }
  return arrays;
}

std::string ArrayScript(const fs::path& batch_dir, const fs::path& photomat,
                        const SlurmArray& array, const SlurmOptions& options) {
  std::string script = fmt::format(
      "#!/bin/bash\n"
      "# photomat batch: {} task(s) of {} not done at submission; array index i runs task "
      "tasks[i].\n"
      "#SBATCH --job-name=photomat-batch\n"
      "#SBATCH --array=0-{}\n"
      "#SBATCH --cpus-per-task={}\n"
      "#SBATCH --mem={}\n",
      array.tasks.size(), batch_dir.string(), array.tasks.size() - 1, options.cpus_per_task,
      array.memory);
  for (const std::string& line : Directives(options)) script += "#SBATCH " + line + "\n";
  script += fmt::format("tasks=({})\n", fmt::join(array.tasks, " "));
  script += fmt::format("exec {} batch run-task {} \"${{tasks[$SLURM_ARRAY_TASK_ID]}}\"\n",
                        Quote(photomat.string()), Quote(batch_dir.string()));
  return script;
}

std::vector<SlurmSubmission> ReadSubmissions(const fs::path& batch_dir) {
  const fs::path file = JobsFile(batch_dir);
  std::vector<SlurmSubmission> submissions;
  if (!fs::exists(file)) return submissions;
  const nlohmann::json document = ReadJsonFile(file);
  const JsonReader list = JsonReader(document, file)["submissions"];
  for (std::size_t s = 0; s < list.ArraySize(); ++s) {
    SlurmSubmission submission;
    const JsonReader arrays = list[s]["arrays"];
    for (std::size_t a = 0; a < arrays.ArraySize(); ++a) {
      SlurmArray array;
      array.job = arrays[a]["job"].String();
      array.memory = arrays[a]["memory"].String();
      array.script = arrays[a]["script"].String();
      const JsonReader tasks = arrays[a]["tasks"];
      for (std::size_t t = 0; t < tasks.ArraySize(); ++t) array.tasks.push_back(tasks[t].Integer());
      submission.arrays.push_back(std::move(array));
    }
    submission.summary_job = list[s]["summary_job"].String();
    submissions.push_back(std::move(submission));
  }
  return submissions;
}

SlurmSubmission SubmitBatch(const fs::path& batch_dir, const SlurmOptions& options,
                            const SlurmClient& slurm) {
  const fs::path dir = fs::absolute(batch_dir).lexically_normal();
  const TaskPlan plan = ReadTaskPlan(dir);
  const std::vector<SlurmSubmission> earlier = ReadSubmissions(dir);
  if (!earlier.empty()) {
    const std::map<std::string, std::string> queued = QueryQueue(earlier.back(), slurm).queued;
    if (!queued.empty()) {
      std::vector<std::string> jobs;
      for (const auto& [job, state] : queued) jobs.push_back(job + " " + Lower(state));
      throw Error(dir,
                  fmt::format("the previous submission is still in the queue ({}): wait for it, "
                              "or scancel it, before submitting again",
                              fmt::join(jobs, ", ")));
    }
  }
  SlurmSubmission submission;
  submission.arrays = PlanArrays(dir, plan, options);
  if (submission.arrays.empty()) return submission;
  const fs::path photomat = options.photomat.empty() ? CurrentExecutable() : options.photomat;
  const fs::path slurm_dir = dir / "slurm";
  std::error_code ec;
  fs::create_directories(slurm_dir, ec);
  fs::create_directories(dir / "logs", ec);
  const std::size_t number = earlier.size() + 1;
  const std::vector<std::string> common{"--parsable", "--chdir=" + dir.string()};
  std::vector<std::string> jobs;
  try {
    for (std::size_t a = 0; a < submission.arrays.size(); ++a) {
      SlurmArray& array = submission.arrays[a];
      array.script = slurm_dir / fmt::format("submission-{}-array-{}.sh", number, a);
      WriteTextFileAtomically(array.script, ArrayScript(dir, photomat, array, options));
      std::vector<std::string> argv{"sbatch"};
      argv.insert(argv.end(), common.begin(), common.end());
      argv.push_back("--output=" + (dir / "logs" / "slurm-%A_%a.out").string());
      argv.push_back(array.script.string());
      array.job = ParsableJobId(slurm(argv), array.script);
      jobs.push_back(array.job);
    }
    const fs::path summary = slurm_dir / fmt::format("submission-{}-summary.sh", number);
    std::string script =
        "#!/bin/bash\n# photomat batch: the summary and index once every array job has ended.\n"
        "#SBATCH --job-name=photomat-batch-summary\n#SBATCH --mem=512M\n";
    for (const std::string& line : Directives(options)) script += "#SBATCH " + line + "\n";
    script +=
        fmt::format("exec {} batch summary {}\n", Quote(photomat.string()), Quote(dir.string()));
    WriteTextFileAtomically(summary, script);
    std::vector<std::string> argv{"sbatch"};
    argv.insert(argv.end(), common.begin(), common.end());
    argv.push_back(fmt::format("--dependency=afterany:{}", fmt::join(jobs, ":")));
    argv.push_back("--output=" + (dir / "logs" / "slurm-summary-%j.out").string());
    argv.push_back(summary.string());
    submission.summary_job = ParsableJobId(slurm(argv), summary);
  } catch (const Error&) {
    // What was submitted runs; record it so that status and the next submission know.
    std::erase_if(submission.arrays, [](const SlurmArray& array) { return array.job.empty(); });
    if (!submission.arrays.empty()) AppendSubmission(dir, submission);
    throw;
  }
  AppendSubmission(dir, submission);
  return submission;
}

std::map<std::string, std::string> ParseJobStates(const std::string& output) {
  std::map<std::string, std::string> states;
  std::size_t start = 0;
  while (start < output.size()) {
    std::size_t end = output.find('\n', start);
    if (end == std::string::npos) end = output.size();
    const std::string line = output.substr(start, end - start);
    start = end + 1;
    const std::size_t bar = line.find('|');
    if (bar == std::string::npos || bar == 0) continue;
    std::string state = line.substr(bar + 1);
    state = state.substr(0, state.find_first_of(" |\r"));
    if (!state.empty()) states[line.substr(0, bar)] = state;
  }
  return states;
}

std::vector<TaskStatus> BatchStatus(const fs::path& batch_dir, const SlurmClient& slurm) {
  const fs::path dir = fs::absolute(batch_dir).lexically_normal();
  const TaskPlan plan = ReadTaskPlan(dir);
  const std::vector<SlurmSubmission> submissions = ReadSubmissions(dir);
  std::map<int, std::string> slurm_ids;  // task -> "JOB_INDEX" in the latest submission
  std::map<std::string, std::string> queue, accounting;
  bool have_accounting = false;
  if (!submissions.empty()) {
    const SlurmSubmission& latest = submissions.back();
    for (const SlurmArray& array : latest.arrays) {
      for (std::size_t i = 0; i < array.tasks.size(); ++i) {
        slurm_ids[array.tasks[i]] = fmt::format("{}_{}", array.job, i);
      }
    }
    JobStates states = QueryQueue(latest, slurm);
    queue = std::move(states.queued);
    const ChildOutcome sacct = slurm({"sacct", "-n", "-P", "-X", "-o", "JobID,State", "-j",
                                      fmt::format("{}", fmt::join(JobIds(latest), ","))});
    have_accounting = sacct.Succeeded();
    if (have_accounting) accounting = ParseJobStates(sacct.output);
    // What squeue still remembers of ended jobs counts as accounting where sacct has none.
    accounting.merge(states.ended);
  }
  char host_name[256] = {};
  gethostname(host_name, sizeof(host_name) - 1);
  const std::string host = host_name;
  std::vector<TaskStatus> status;
  for (const Task& task : plan.tasks) {
    TaskStatus s{task.index, task.name, "not run", ""};
    const auto id = slurm_ids.find(task.index);
    const std::optional<TaskRecord> record = LastAttempt(dir, task);
    if (const auto done = DoneRecord(task)) {
      s.state = "done";
      s.detail = fmt::format("{:.1f} s, peak {:.0f} MB", done->elapsed_seconds,
                             static_cast<double>(done->peak_rss_bytes) / (1024.0 * 1024.0));
    } else if (id != slurm_ids.end() && queue.contains(id->second)) {
      const std::string state = Lower(queue.at(id->second));
      s.state = state == "running" || state == "completing" ? "running"
                : state == "pending"                        ? "pending"
                                                            : state;
      s.detail = "Slurm job " + id->second;
    } else if (record && record->state == TaskState::kFailed) {
      s.state = "failed";
      s.detail = fmt::format("{}: {}", record->failed_step, record->error);
    } else if (id != slurm_ids.end()) {
      s.state = "stopped";
      const auto accounted = accounting.find(id->second);
      s.detail = accounted != accounting.end()
                     ? fmt::format("Slurm job {}: {}", id->second, accounted->second)
                     : fmt::format(
                           "Slurm job {} left the queue without a done record (cancelled, "
                           "preempted or its node lost{})",
                           id->second, have_accounting ? "" : "; sacct unavailable");
      s.state =
          accounted != accounting.end() && accounted->second == "COMPLETED" ? "failed" : s.state;
    } else if (record && record->state == TaskState::kRunning) {
      // Not Slurm's: a `batch run` here, if its process is still alive.
      const bool alive = record->host == host && record->pid > 0 && ::kill(record->pid, 0) == 0;
      s.state = alive ? "running" : "stopped";
      s.detail = alive ? fmt::format("attempt {}, pid {}", record->attempt, record->pid)
                       : fmt::format("attempt {} on {} (pid {}) did not finish", record->attempt,
                                     record->host, record->pid);
    }
    status.push_back(std::move(s));
  }
  return status;
}

std::string FormatStatus(const std::vector<TaskStatus>& status) {
  std::string text = fmt::format("{:>5}  {:<20} {:<8} {}\n", "task", "capture", "state", "detail");
  std::map<std::string, int> counts;
  for (const TaskStatus& s : status) {
    text += fmt::format("{:>5}  {:<20} {:<8} {}\n", s.index, s.name, s.state, s.detail);
    ++counts[s.state];
  }
  std::vector<std::string> parts;
  for (const char* state : {"done", "running", "pending", "failed", "stopped", "not run"}) {
    if (counts.contains(state)) parts.push_back(fmt::format("{} {}", counts[state], state));
  }
  for (const auto& [state, count] : counts) {
    if (std::find(parts.begin(), parts.end(), fmt::format("{} {}", count, state)) == parts.end()) {
      parts.push_back(fmt::format("{} {}", count, state));
    }
  }
  text += fmt::format("{}\n", fmt::join(parts, ", "));
  return text;
}

}  // namespace photomat::batch
