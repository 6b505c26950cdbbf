// `photomat batch slurm` on a real Slurm: Debian's slurm-wlm and munge, started by the test as a
// single-node cluster in a temporary folder (shared/specs/slurm-single-node.md has the settings
// checked on these machines), on free ports, stopped by pid and removed at the end. Skipped, with
// the reason, where the daemons cannot start.
#include <arpa/inet.h>
#include <fmt/format.h>
#include <gmock/gmock.h>
#include <gtest/gtest.h>
#include <netinet/in.h>
#include <sys/socket.h>
#include <unistd.h>

#include <chrono>
#include <csignal>
#include <cstdlib>
#include <fstream>
#include <random>
#include <thread>

#include "apps/batch/child_process.h"
#include "apps/batch/slurm.h"
#include "apps/batch/task_plan.h"
#include "apps/batch/task_record.h"
#include "apps/batch/testing/collection.h"
#include "core/atomic_file.h"
#include "core/error.h"
#include "core/json_file.h"
#include "tests/support/test_support.h"

namespace photomat::batch {
namespace {

namespace fs = std::filesystem;
using photomat::testing::TempDir;
using testing::CaptureFault;
using ::testing::HasSubstr;
using testing::RunPhotomatIn;
using testing::TestCapture;

using Clock = std::chrono::steady_clock;

// A TCP port nobody listens on now (the kernel's pick for port 0).
int FreePort() {
  const int fd = socket(AF_INET, SOCK_STREAM, 0);
  sockaddr_in address{};
  address.sin_family = AF_INET;
  address.sin_addr.s_addr = htonl(INADDR_LOOPBACK);
  bind(fd, reinterpret_cast<sockaddr*>(&address), sizeof(address));
  socklen_t length = sizeof(address);
  getsockname(fd, reinterpret_cast<sockaddr*>(&address), &length);
  close(fd);
  return ntohs(address.sin_port);
}

std::optional<fs::path> FindProgram(const std::string& name) {
  try {
    return FindInPath(name);
  } catch (const Error&) {
  }
  for (const char* dir : {"/usr/sbin", "/sbin", "/usr/bin"}) {
    if (access((fs::path(dir) / name).c_str(), X_OK) == 0) return fs::path(dir) / name;
  }
  return std::nullopt;
}

ChildOutcome RunProgram(const std::vector<std::string>& argv) {
  ChildCommand command;
  command.executable = FindProgram(argv[0]).value_or(argv[0]);
  command.arguments.assign(argv.begin() + 1, argv.end());
  command.output = ChildOutput::kCapture;
  return RunChild(command);
}

std::string Tail(const fs::path& file, std::size_t bytes = 1500) {
  std::error_code ec;
  if (!fs::exists(file, ec)) return "(no " + file.filename().string() + ")";
  const std::string text = ReadTextFile(file);
  return text.substr(text.size() > bytes ? text.size() - bytes : 0);
}

// A fresh folder with a short path: slurmstepd's Unix sockets live in the spool folder, and a
// socket path may not exceed 108 bytes (TempDir's names, with the test's name, do).
class ShortTempDir {
 public:
  ShortTempDir() {
    std::string pattern = (fs::temp_directory_path() / "pmslurm-XXXXXX").string();
    if (mkdtemp(pattern.data()) == nullptr) throw Error(pattern, "mkdtemp failed");
    path_ = pattern;
  }
  ~ShortTempDir() {
    std::error_code ec;
    fs::remove_all(path_, ec);
  }
  ShortTempDir(const ShortTempDir&) = delete;
  ShortTempDir& operator=(const ShortTempDir&) = delete;
  const fs::path& path() const { return path_; }
  fs::path operator/(const std::string& name) const { return path_ / name; }

 private:
  fs::path path_;
};

// Where the cluster cannot start the tests skip with the reason, except where the environment
// says that a Slurm must start (PHOTOMAT_REQUIRE_SLURM=1, which scripts/clean-root-check sets:
// there, the packages are installed and a skip would hide a set-up fault), where it is a failure.
bool SlurmRequired() {
  const char* value = std::getenv("PHOTOMAT_REQUIRE_SLURM");
  return value != nullptr && std::string(value) == "1";
}

#define SKIP_UNLESS_REQUIRED(reason)                                                  \
  do {                                                                                \
    if (SlurmRequired()) GTEST_FAIL() << "PHOTOMAT_REQUIRE_SLURM=1 but " << (reason); \
    GTEST_SKIP() << (reason);                                                         \
  } while (false)

// The cluster: munged, slurmctld and slurmd of this test only, all files in one folder.
class SingleNodeSlurm : public ::testing::Test {
 protected:
  void SetUp() override {
    if (geteuid() != 0) {
      SKIP_UNLESS_REQUIRED("the single-node Slurm runs its daemons as root; not root");
    }
    for (const char* program :
         {"munged", "slurmctld", "slurmd", "sbatch", "squeue", "scancel", "sinfo"}) {
      if (!FindProgram(program)) {
        SKIP_UNLESS_REQUIRED(fmt::format(
            "{} not found: install slurm-wlm and munge (scripts/debian-packages.txt)", program));
      }
    }
    const fs::path root = cluster_.path();
    for (const char* folder : {"munge", "spool", "state", "log"})
      fs::create_directories(root / folder);
    fs::permissions(root / "munge", fs::perms::owner_all);
    std::mt19937_64 random(std::random_device{}());
    std::string key(1024, '\0');
    for (char& c : key) c = static_cast<char>(random());
    photomat::testing::WriteFile(root / "munge/key", key);
    fs::permissions(root / "munge/key", fs::perms::owner_read);
    const fs::path socket = root / "munge/socket";
    // -f: the folder is not the packaged one, whose permissions munged would insist on.
    const ChildOutcome munged = RunProgram(
        {"munged", "--key-file=" + (root / "munge/key").string(), "--socket=" + socket.string(),
         "--pid-file=" + MungePid().string(), "--log-file=" + (root / "munge/log").string(),
         "--seed-file=" + (root / "munge/seed").string(), "-f"});
    if (!munged.Succeeded()) {
      SKIP_UNLESS_REQUIRED(fmt::format("munged did not start: {}\nmunged log: {}", munged.output,
                                       Tail(root / "munge/log")));
    }

    char host[256] = {};
    gethostname(host, sizeof(host) - 1);
    const std::string node = std::string(host).substr(0, std::string(host).find('.'));
    const std::string r = root.string();
    const int controller_port = FreePort();
    int node_port = FreePort();
    while (node_port == controller_port) node_port = FreePort();
    photomat::testing::WriteFile(Config(),
                                 fmt::format(R"(ClusterName=photomat-test
SlurmctldHost={0}(127.0.0.1)
SlurmctldPort={1}
SlurmdPort={2}
AuthType=auth/munge
CredType=cred/munge
AuthInfo=socket={3}
SlurmUser=root
SlurmdUser=root
ProctrackType=proctrack/linuxproc
TaskPlugin=task/none
SelectType=select/cons_tres
SelectTypeParameters=CR_Core
JobAcctGatherType=jobacct_gather/none
JobCompType=jobcomp/none
AccountingStorageType=accounting_storage/none
SchedulerType=sched/builtin
ReturnToService=2
KillWait=5
MpiDefault=none
SlurmctldPidFile={4}/slurmctld.pid
SlurmdPidFile={4}/slurmd.pid
SlurmdSpoolDir={4}/spool
StateSaveLocation={4}/state
SlurmctldLogFile={4}/log/slurmctld.log
SlurmdLogFile={4}/log/slurmd.log
NodeName={0} NodeAddr=127.0.0.1 CPUs=2 RealMemory=8192 State=UNKNOWN
PartitionName=test Nodes={0} Default=YES MaxTime=INFINITE State=UP
)",
                                             node, controller_port, node_port, socket.string(), r));
    setenv("SLURM_CONF", Config().c_str(), 1);
    for (const char* daemon : {"slurmctld", "slurmd"}) {
      const ChildOutcome started = RunProgram({daemon, "-f", Config().string()});
      if (!started.Succeeded()) {
        // The daemon's own log says why (slurmd: "No filesystem mounted on /sys/fs/cgroup").
        SKIP_UNLESS_REQUIRED(fmt::format("{} did not start: {}\n{}.log: {}", daemon, started.output,
                                         daemon,
                                         Tail(root / "log" / (std::string(daemon) + ".log"))));
      }
    }
    const auto deadline = Clock::now() + std::chrono::seconds(30);
    std::string state;
    while (Clock::now() < deadline) {
      state = RunProgram({"sinfo", "-h", "-o", "%t"}).output;
      if (state == "idle\n") return;
      std::this_thread::sleep_for(std::chrono::milliseconds(200));
    }
    SKIP_UNLESS_REQUIRED(
        fmt::format("the node did not come up (sinfo: {})\nslurmctld.log: {}"
                    "\nslurmd.log: {}",
                    state, Tail(root / "log/slurmctld.log"), Tail(root / "log/slurmd.log")));
  }

  // Also after a failed assertion: cancel what is left, stop each daemon by its pid file.
  void TearDown() override {
    if (fs::exists(Config())) {
      RunProgram({"scancel", "--user=root"});
      const auto deadline = Clock::now() + std::chrono::seconds(15);
      while (Clock::now() < deadline && !RunProgram({"squeue", "-h"}).output.empty()) {
        std::this_thread::sleep_for(std::chrono::milliseconds(200));
      }
    }
    for (const fs::path& pid_file :
         {cluster_ / "slurmd.pid", cluster_ / "slurmctld.pid", MungePid()}) {
      Stop(pid_file);
    }
    unsetenv("SLURM_CONF");
  }

  static void Stop(const fs::path& pid_file) {
    std::ifstream in(pid_file);
    pid_t pid = 0;
    if (!(in >> pid) || pid <= 1) return;
    ::kill(pid, SIGTERM);
    for (int i = 0; i < 100 && ::kill(pid, 0) == 0; ++i) {
      std::this_thread::sleep_for(std::chrono::milliseconds(50));
    }
    if (::kill(pid, 0) == 0) ::kill(pid, SIGKILL);
  }

  fs::path Config() const { return cluster_ / "slurm.conf"; }
  fs::path MungePid() const { return cluster_ / "munge/pid"; }

  // Waits until none of the batch's recorded jobs is in the queue any more.
  void WaitForBatch(const fs::path& batch, std::chrono::seconds timeout) {
    std::vector<std::string> ids;
    for (const SlurmSubmission& s : ReadSubmissions(batch)) {
      for (const SlurmArray& array : s.arrays) ids.push_back(array.job);
      ids.push_back(s.summary_job);
    }
    const auto deadline = Clock::now() + timeout;
    std::string queued;
    while (Clock::now() < deadline) {
      queued = RunProgram({"squeue", "-h", "-t", "PD,R,CG,CF,S", "-o", "%i %T", "-j",
                           fmt::format("{}", fmt::join(ids, ","))})
                   .output;
      if (queued.empty()) return;
      std::this_thread::sleep_for(std::chrono::milliseconds(250));
    }
    FAIL() << "jobs still queued after " << timeout.count() << " s:\n"
           << queued << "slurmctld.log: " << Tail(cluster_ / "log/slurmctld.log")
           << "\nslurmd.log: " << Tail(cluster_ / "log/slurmd.log");
  }

  ShortTempDir cluster_;
};

TEST_F(SingleNodeSlurm, EightCapturesTwoBrokenThroughTheJobArray) {
  TempDir dir;
  const std::vector<TestCapture> captures = testing::EightCapturesTwoBroken();
  const fs::path batch = testing::PlanTestCollection(dir.path(), captures);

  const auto start = Clock::now();
  const ChildOutcome submit = RunPhotomatIn(dir.path(), {"batch", "slurm", batch.string()});
  std::cout << submit.output;
  ASSERT_TRUE(submit.Succeeded()) << submit.output;
  EXPECT_THAT(submit.output, HasSubstr("array of 8 task(s) (0,1,2,3,4,5,6,7)"));
  WaitForBatch(batch, std::chrono::seconds(90));
  std::cout << "the array and the summary job ran in "
            << std::chrono::duration<double>(Clock::now() - start).count() << " s\n";

  const ChildOutcome status = RunPhotomatIn(dir.path(), {"batch", "status", batch.string()});
  std::cout << status.output;
  EXPECT_THAT(status.output, HasSubstr("6 done, 2 failed"));
  const std::string captures_dir = (dir / "captures").string();
  EXPECT_THAT(status.output, HasSubstr("failed   fit: " + captures_dir +
                                       "/capture-3/img_007.png: image file not found"));
  EXPECT_THAT(status.output, HasSubstr("failed   fit: " + captures_dir +
                                       "/capture-6/lights.lp: line 5: \"abc\" is not a number"));

  const TaskPlan plan = ReadTaskPlan(batch);
  for (const Task& task : plan.tasks) {
    const std::optional<TaskRecord> record = LastAttempt(batch, task);
    ASSERT_TRUE(record) << task.name;
    EXPECT_THAT(record->slurm_job, HasSubstr(fmt::format("_{}", task.index)))
        << "ran as an array task";
    if (captures[task.index].fault != CaptureFault::kNone) continue;
    const fs::path by_hand = dir / "by-hand" / task.name;
    ASSERT_EQ(testing::RunByHand(task.capture, task.name, by_hand), "");
    testing::ExpectSameOutputs(by_hand, task.folder);
  }
  // The dependent job wrote the summary and the index.
  const nlohmann::json summary = ReadJsonFile(batch / "summary.json");
  EXPECT_EQ(summary["done"], 6);
  EXPECT_EQ(summary["failed"], 2);
  EXPECT_TRUE(fs::exists(batch / "index.html"));
}

TEST_F(SingleNodeSlurm, CancelledArrayTaskIsTheOnlyOneThatRunsAgain) {
  TempDir dir;
  // The middle capture is large enough to be cancelled while it runs.
  const fs::path batch = testing::PlanTestCollection(
      dir.path(),
      {{"capture-0", "32x24", 1}, {"capture-1", "128x128", 2}, {"capture-2", "32x24", 3}});
  const TaskPlan plan = ReadTaskPlan(batch);
  const Task& slow = plan.tasks[1];

  const ChildOutcome submit = RunPhotomatIn(dir.path(), {"batch", "slurm", batch.string()});
  ASSERT_TRUE(submit.Succeeded()) << submit.output;
  // The large capture needs more memory, so it has an array of its own: find its array index.
  std::string slurm_id;
  const std::vector<SlurmSubmission> submissions = ReadSubmissions(batch);
  for (const SlurmArray& array : submissions.back().arrays) {
    for (std::size_t i = 0; i < array.tasks.size(); ++i) {
      if (array.tasks[i] == slow.index) slurm_id = fmt::format("{}_{}", array.job, i);
    }
  }
  ASSERT_FALSE(slurm_id.empty());
  // Cancel it while it runs.
  const auto deadline = Clock::now() + std::chrono::seconds(60);
  bool running = false;
  while (Clock::now() < deadline && !running) {
    const std::optional<TaskRecord> record = LastAttempt(batch, slow);
    running = record && record->state == TaskState::kRunning;
    if (!running) std::this_thread::sleep_for(std::chrono::milliseconds(20));
  }
  ASSERT_TRUE(running) << "task 1 never started";
  ASSERT_TRUE(RunProgram({"scancel", slurm_id}).Succeeded());
  WaitForBatch(batch, std::chrono::seconds(60));

  const ChildOutcome after_cancel = RunPhotomatIn(dir.path(), {"batch", "status", batch.string()});
  std::cout << after_cancel.output;
  EXPECT_THAT(after_cancel.output, HasSubstr("2 done, 1 stopped"));
  EXPECT_THAT(after_cancel.output, HasSubstr("stopped  Slurm job " + slurm_id));
  EXPECT_FALSE(IsTaskDone(slow)) << "slurmd.log: " << Tail(cluster_ / "log/slurmd.log")
                                 << "\nslurmctld.log: " << Tail(cluster_ / "log/slurmctld.log")
                                 << "\ntask log: " << Tail(LogPath(batch, slow));
  EXPECT_FALSE(fs::exists(slow.folder)) << "nothing of the cancelled task is final";

  const ChildOutcome resubmit = RunPhotomatIn(dir.path(), {"batch", "slurm", batch.string()});
  std::cout << resubmit.output;
  ASSERT_TRUE(resubmit.Succeeded()) << resubmit.output;
  EXPECT_THAT(resubmit.output, HasSubstr("array of 1 task(s) (1)"));
  WaitForBatch(batch, std::chrono::seconds(90));
  const ChildOutcome status = RunPhotomatIn(dir.path(), {"batch", "status", batch.string()});
  std::cout << status.output;
  EXPECT_THAT(status.output, HasSubstr("3 done\n"));
  // Attempts (numbered by the task records as each starts): one each for the tasks that were
  // never cancelled, two for the cancelled one.
  for (const Task& task : plan.tasks) {
    EXPECT_EQ(DoneRecord(task)->attempt, task.index == 1 ? 2 : 1) << task.name;
  }

  testing::ExpectSameAsByHand(
      {{slow.capture, slow.name, dir / "by-hand" / slow.name, slow.folder}});
}

}  // namespace
}  // namespace photomat::batch
