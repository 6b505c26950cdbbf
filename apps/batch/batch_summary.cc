#include "apps/batch/batch_summary.h"

#include <fmt/format.h>

#include <algorithm>

#include "apps/batch/task_record.h"
#include "core/atomic_file.h"
#include "core/error.h"
#include "core/json_file.h"
#include "core/markup.h"
#include "represent/model/method.h"

namespace photomat::batch {
namespace {

namespace fs = std::filesystem;

// The methods a task fits or evaluates: the --method list of its fit step, else --methods of its
// evaluation.
std::vector<std::string> TaskMethods(const Task& task) {
  for (const TaskStep& step : task.steps) {
    const auto& a = step.arguments;
    for (std::size_t i = 0; i + 1 < a.size(); ++i) {
      if ((a[0] == "fit" && a[i] == "--method") || (a[0] == "evaluate" && a[i] == "--methods")) {
        std::vector<std::string> names;
        for (const Method& method : ParseMethodList(a[i + 1])) names.push_back(method.Name());
        return names;
      }
    }
  }
  return {};
}

std::optional<double> NumberAt(const nlohmann::json& json,
                               std::initializer_list<const char*> path) {
  const nlohmann::json* node = &json;
  for (const char* key : path) {
    if (!node->is_object() || !node->contains(key)) return std::nullopt;
    node = &node->at(key);
  }
  if (!node->is_number()) return std::nullopt;
  return node->get<double>();
}

std::vector<MethodSummary> Methods(const Task& task) {
  nlohmann::json evaluation;
  const fs::path file = task.folder / "evaluation.json";
  std::error_code ec;
  if (fs::exists(file, ec)) {
    try {
      evaluation = ReadJsonFile(file);
    } catch (const Error&) {
      evaluation = nullptr;  // not ours to judge here: shown as "-"
    }
  }
  std::vector<MethodSummary> methods;
  for (const std::string& name : TaskMethods(task)) {
    MethodSummary method{name, {}, {}, {}};
    if (evaluation.is_object() && evaluation.contains(name)) {
      const nlohmann::json& e = evaluation[name];
      method.eta_reconstruction = NumberAt(e, {"eta_reconstruction"});
      method.eta_prediction = NumberAt(e, {"eta_prediction"});
      method.normal_mean_degrees = NumberAt(e, {"normals", "mean_angular_error_deg"});
    }
    methods.push_back(method);
  }
  return methods;
}

std::string Optional(const std::optional<double>& value, const char* format) {
  return value ? fmt::format(fmt::runtime(format), *value) : "-";
}

nlohmann::json OptionalJson(const std::optional<double>& value) {
  return value ? nlohmann::json(*value) : nlohmann::json(nullptr);
}

double Megabytes(std::int64_t bytes) { return static_cast<double>(bytes) / (1024.0 * 1024.0); }

std::string PercentEncode(const std::string& text) {
  std::string encoded;
  for (unsigned char c : text) {
    if (std::isalnum(c) || c == '/' || c == '-' || c == '_' || c == '.' || c == '~') {
      encoded += static_cast<char>(c);
    } else {
      encoded += fmt::format("%{:02X}", c);
    }
  }
  return encoded;
}

nlohmann::json SummaryJson(const BatchSummary& summary) {
  nlohmann::json tasks = nlohmann::json::array();
  for (const TaskSummary& t : summary.tasks) {
    nlohmann::json methods = nlohmann::json::array();
    for (const MethodSummary& m : t.methods) {
      methods.push_back({{"method", m.method},
                         {"eta_reconstruction", OptionalJson(m.eta_reconstruction)},
                         {"eta_prediction", OptionalJson(m.eta_prediction)},
                         {"normal_mean_angular_error_deg", OptionalJson(m.normal_mean_degrees)}});
    }
    tasks.push_back({{"index", t.index},
                     {"name", t.name},
                     {"capture", t.capture.string()},
                     {"folder", t.folder.string()},
                     {"state", t.state},
                     {"failed_step", t.failed_step},
                     {"error", t.error},
                     {"elapsed_seconds", t.elapsed_seconds},
                     {"peak_rss_bytes", t.peak_rss_bytes},
                     {"methods", methods}});
  }
  return {{"recipe_file", summary.recipe_file.string()},
          {"done", summary.Count("done")},
          {"failed", summary.Count("failed")},
          {"not_run", summary.Count("not run")},
          {"tasks", tasks}};
}

std::string IndexHtml(const fs::path& batch_dir, const BatchSummary& summary) {
  const auto link = [&](const fs::path& target, const std::string& text) {
    return fmt::format("<a href=\"{}\">{}</a>", EscapeMarkup(RelativeLink(batch_dir, target)),
                       EscapeMarkup(text));
  };
  std::string rows;
  for (const TaskSummary& t : summary.tasks) {
    std::vector<std::string> links;
    if (t.report) links.push_back(link(t.folder / "report" / "index.html", "report"));
    if (t.viewer) links.push_back(link(t.folder / "viewer" / "index.html", "viewer"));
    if (t.maps) links.push_back(link(t.folder / "maps", "maps"));
    std::error_code ec;
    if (fs::exists(LogPath(batch_dir, t.index, t.name), ec)) {
      links.push_back(link(LogPath(batch_dir, t.index, t.name), "log"));
    }
    const std::size_t span = std::max<std::size_t>(1, t.methods.size());
    for (std::size_t m = 0; m < span; ++m) {
      rows += "<tr>";
      if (m == 0) {
        rows += fmt::format("<td rowspan=\"{}\">{}</td><td rowspan=\"{}\" class=\"{}\">{}</td>",
                            span, EscapeMarkup(t.name), span, t.state == "done" ? "ok" : "bad",
                            EscapeMarkup(t.state));
      }
      if (t.state == "failed") {
        if (m == 0) {
          rows += fmt::format("<td colspan=\"4\" rowspan=\"{}\">{}: {}</td>", span,
                              EscapeMarkup(t.failed_step), EscapeMarkup(t.error));
        }
      } else if (m < t.methods.size()) {
        const MethodSummary& s = t.methods[m];
        rows += fmt::format("<td>{}</td><td>{}</td><td>{}</td><td>{}</td>", EscapeMarkup(s.method),
                            Optional(s.eta_reconstruction, "{:.6f}"),
                            Optional(s.eta_prediction, "{:.6f}"),
                            Optional(s.normal_mean_degrees, "{:.3f}"));
      } else {
        rows += "<td colspan=\"4\">-</td>";
      }
      if (m == 0) {
        rows += fmt::format(
            "<td rowspan=\"{0}\">{1:.1f}</td><td rowspan=\"{0}\">{2:.0f}</td>"
            "<td rowspan=\"{0}\">{3}</td>",
            span, t.elapsed_seconds, Megabytes(t.peak_rss_bytes), fmt::join(links, " "));
      }
      rows += "</tr>\n";
    }
  }
  const std::string title = "photomat batch: " + summary.recipe_file.string();
  return fmt::format(
      "<!DOCTYPE html>\n<html lang=\"en\">\n<head>\n<meta charset=\"utf-8\">\n<title>{0}</title>\n"
      "<style>body{{font-family:sans-serif;margin:2em}}table{{border-collapse:collapse}}"
      "td,th{{border:1px solid #bbb;padding:0.3em 0.6em;text-align:left}}.ok{{color:#060}}"
      ".bad{{color:#a00;font-weight:bold}}</style>\n</head>\n<body>\n<h1>{0}</h1>\n"
      "<p>{1} done, {2} failed, {3} not run. The viewers need a static file server (e.g. "
      "<code>python3 -m http.server</code> in a folder above this page and the "
      "outputs).</p>\n<table>\n"
      "<tr><th>capture</th><th>state</th><th>method</th><th>eta reconstruction</th>"
      "<th>eta prediction</th><th>normal error (deg)</th><th>time (s)</th><th>peak (MB)</th>"
      "<th>outputs</th></tr>\n{4}</table>\n</body>\n</html>\n",
      EscapeMarkup(title), summary.Count("done"), summary.Count("failed"), summary.Count("not run"),
      rows);
}

}  // namespace

int BatchSummary::Count(const std::string& state) const {
  return static_cast<int>(std::count_if(tasks.begin(), tasks.end(),
                                        [&](const TaskSummary& t) { return t.state == state; }));
}

BatchSummary SummariseBatch(const fs::path& batch_dir, const TaskPlan& plan) {
  BatchSummary summary;
  summary.recipe_file = plan.recipe_file;
  for (const Task& task : plan.tasks) {
    TaskSummary t;
    t.index = task.index;
    t.name = task.name;
    t.capture = task.capture;
    t.folder = task.folder;
    t.methods = Methods(task);
    std::optional<TaskRecord> record = DoneRecord(task);
    if (!record) {
      record = LastAttempt(batch_dir, task);
      if (record && record->state != TaskState::kFailed) record.reset();
    }
    t.state = record ? ToString(record->state) : "not run";
    if (record) {
      t.failed_step = record->failed_step;
      t.error = record->error;
      t.elapsed_seconds = record->elapsed_seconds;
      t.peak_rss_bytes = record->peak_rss_bytes;
    }
    if (t.state == "done") {
      std::error_code ec;
      t.report = fs::exists(task.folder / "report" / "index.html", ec);
      t.viewer = fs::exists(task.folder / "viewer" / "index.html", ec);
      t.maps = fs::exists(task.folder / "maps", ec);
    } else {
      t.methods.clear();  // the numbers would be an earlier recipe's
    }
    summary.tasks.push_back(std::move(t));
  }
  return summary;
}

std::string FormatSummaryTable(const BatchSummary& summary) {
  std::string table =
      fmt::format("{:<20} {:<8} {:<10} {:>12} {:>12} {:>11} {:>8} {:>8}\n", "capture", "state",
                  "method", "eta_recon.", "eta_pred.", "normal_deg", "time_s", "peak_MB");
  for (const TaskSummary& t : summary.tasks) {
    const std::string head = fmt::format("{:<20} {:<8}", t.name, t.state);
    if (t.state == "failed") {
      table += fmt::format("{} {}: {}\n", head, t.failed_step, t.error);
      continue;
    }
    if (t.methods.empty()) {
      table += fmt::format("{} {:<10} {:>12} {:>12} {:>11} {:>8.1f} {:>8.0f}\n", head, "-", "-",
                           "-", "-", t.elapsed_seconds, Megabytes(t.peak_rss_bytes));
    }
    for (std::size_t m = 0; m < t.methods.size(); ++m) {
      const MethodSummary& s = t.methods[m];
      table += fmt::format("{} {:<10} {:>12} {:>12} {:>11}", m == 0 ? head : std::string(29, ' '),
                           s.method, Optional(s.eta_reconstruction, "{:.6f}"),
                           Optional(s.eta_prediction, "{:.6f}"),
                           Optional(s.normal_mean_degrees, "{:.3f}"));
      table += m == 0 ? fmt::format(" {:>8.1f} {:>8.0f}\n", t.elapsed_seconds,
                                    Megabytes(t.peak_rss_bytes))
                      : "\n";
    }
  }
  table += fmt::format("{} done, {} failed, {} not run\n", summary.Count("done"),
                       summary.Count("failed"), summary.Count("not run"));
  return table;
}

void WriteBatchSummary(const fs::path& batch_dir, const BatchSummary& summary) {
  WriteJsonFile(batch_dir / "summary.json", SummaryJson(summary));
  WriteTextFileAtomically(batch_dir / "index.html", IndexHtml(batch_dir, summary));
}

std::string RelativeLink(const fs::path& from, const fs::path& target) {
  const fs::path base = fs::absolute(from).lexically_normal();
  return PercentEncode(
      fs::absolute(target).lexically_normal().lexically_relative(base).generic_string());
}

}  // namespace photomat::batch
