#include "apps/batch/task_record.h"

#include <fmt/format.h>

#include <array>

#include "core/enum_names.h"
#include "core/error.h"
#include "core/json_file.h"

namespace photomat::batch {
namespace {

namespace fs = std::filesystem;

constexpr std::array<NamedValue<TaskState>, 3> kTaskStateNames = {
    {{TaskState::kRunning, "running"}, {TaskState::kFailed, "failed"}, {TaskState::kDone, "done"}}};

}  // namespace

std::string ToString(TaskState state) { return std::string(NameOf(state, kTaskStateNames)); }

fs::path RecordPath(const fs::path& batch_dir, const Task& task) {
  return batch_dir / "records" / fmt::format("{:04}.json", task.index);
}

fs::path LogPath(const fs::path& batch_dir, int index, const std::string& name) {
  return batch_dir / "logs" / fmt::format("{:04}-{}.log", index, name);
}

fs::path LogPath(const fs::path& batch_dir, const Task& task) {
  return LogPath(batch_dir, task.index, task.name);
}

fs::path DoneRecordPath(const Task& task) { return task.folder / kDoneRecordName; }

void WriteTaskRecord(const fs::path& path, const TaskRecord& record) {
  WriteJsonFile(path, {{"state", ToString(record.state)},
                       {"attempt", record.attempt},
                       {"hash", record.hash},
                       {"host", record.host},
                       {"pid", record.pid},
                       {"slurm_job", record.slurm_job},
                       {"failed_step", record.failed_step},
                       {"error", record.error},
                       {"elapsed_seconds", record.elapsed_seconds},
                       {"peak_rss_bytes", record.peak_rss_bytes}});
}

std::optional<TaskRecord> ReadTaskRecord(const fs::path& path) {
  std::error_code ec;
  if (!fs::exists(path, ec)) return std::nullopt;
  try {
    const nlohmann::json json = ReadJsonFile(path);
    const JsonReader root(json, path);
    TaskRecord record;
    const auto state = FindValueNamed(root["state"].String(), kTaskStateNames);
    if (!state) return std::nullopt;
    record.state = *state;
    record.attempt = root["attempt"].Integer();
    record.hash = root["hash"].String();
    record.host = root["host"].String();
    record.pid = root["pid"].Integer();
    record.slurm_job = root["slurm_job"].String();
    record.failed_step = root["failed_step"].String();
    record.error = root["error"].String();
    record.elapsed_seconds = root["elapsed_seconds"].Number();
    record.peak_rss_bytes = static_cast<std::int64_t>(root["peak_rss_bytes"].Number());
    return record;
  } catch (const Error&) {
    return std::nullopt;
  }
}

std::optional<TaskRecord> DoneRecord(const Task& task) {
  std::optional<TaskRecord> record = ReadTaskRecord(DoneRecordPath(task));
  if (!record || record->state != TaskState::kDone || record->hash != task.hash)
    return std::nullopt;
  return record;
}

bool IsTaskDone(const Task& task) { return DoneRecord(task).has_value(); }

std::optional<TaskRecord> LastAttempt(const fs::path& batch_dir, const Task& task) {
  std::optional<TaskRecord> record = ReadTaskRecord(RecordPath(batch_dir, task));
  if (!record || record->hash != task.hash) return std::nullopt;
  return record;
}

}  // namespace photomat::batch
