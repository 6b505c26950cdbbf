#include "tests/support/test_support.h"

#include <sys/resource.h>
#include <sys/wait.h>
#include <unistd.h>

#include <algorithm>
#include <array>
#include <cerrno>
#include <chrono>
#include <cmath>
#include <csignal>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <fstream>
#include <limits>
#include <regex>

namespace photomat::testing {

bool SameBits(const Image& a, const Image& b) {
  return a.SameShape(b) &&
         std::memcmp(a.values().data(), b.values().data(), a.values().size_bytes()) == 0;
}

double LargestDifferenceOverLargestValue(const Image& a, const Image& b) {
  EXPECT_TRUE(a.SameShape(b));
  if (!a.SameShape(b)) return std::numeric_limits<double>::infinity();
  double difference = 0.0, scale = 0.0;
  for (std::size_t i = 0; i < a.values().size(); ++i) {
    difference = std::max(difference, std::abs(double{a.values()[i]} - b.values()[i]));
    scale = std::max(scale, std::abs(double{b.values()[i]}));
  }
  return difference / std::max(scale, 1e-30);
}

std::optional<std::filesystem::path> TestDataDir() {
  const char* value = std::getenv(kTestDataVariable);
  if (value == nullptr || *value == '\0') return std::nullopt;
  return std::filesystem::path(value);
}

std::vector<std::string> EntriesOf(const std::filesystem::path& folder) {
  std::vector<std::string> names;
  for (const auto& entry : std::filesystem::directory_iterator(folder)) {
    names.push_back(entry.path().filename().string());
  }
  std::sort(names.begin(), names.end());
  return names;
}

std::size_t CountMatches(const std::string& text, const std::string& pattern) {
  const std::regex re(pattern);
  return static_cast<std::size_t>(
      std::distance(std::sregex_iterator(text.begin(), text.end(), re), std::sregex_iterator()));
}

TempDir::TempDir() {
  const auto stamp = std::chrono::steady_clock::now().time_since_epoch().count();
  const auto* info = ::testing::UnitTest::GetInstance()->current_test_info();
  const std::string name = info ? std::string(info->test_suite_name()) + "." + info->name() : "t";
  path_ = std::filesystem::temp_directory_path() /
          ("photomat-" + name + "-" + std::to_string(getpid()) + "-" + std::to_string(stamp));
  std::filesystem::create_directories(path_);
}

TempDir::~TempDir() {
  std::error_code ec;
  std::filesystem::remove_all(path_, ec);
}

void WriteFile(const std::filesystem::path& path, const std::string& contents) {
  std::filesystem::create_directories(path.parent_path());
  std::ofstream out(path, std::ios::binary);
  out << contents;
}

void LimitFileSize(std::size_t bytes) {
  std::signal(SIGXFSZ, SIG_IGN);
  rlimit limit{bytes, bytes};
  setrlimit(RLIMIT_FSIZE, &limit);
}

ImageWriteOptions Linear16Bit() {
  ImageWriteOptions options;
  options.sample_type = SampleType::kUint16;
  return options;
}

std::filesystem::path PhotomatExecutable() {
  const char* dir = std::getenv("PHOTOMAT_BINARY_DIR");
  return std::filesystem::path(dir ? dir : ".") / "bin" / "photomat";
}

std::string GenerateCapture(const std::filesystem::path& folder, const std::string& options) {
  const RunResult generated = RunPhotomat("generate --out " + folder.string() + " " + options);
  EXPECT_EQ(generated.exit_code, 0) << generated.output;
  return folder.string();
}

RunResult RunPhotomat(const std::string& arguments) { return RunPhotomat(arguments, {}); }

RunResult RunPhotomat(const std::string& arguments, const RunLimits& limits) {
  // Everything the child needs is made before fork: after it, only async-signal-safe calls.
  const std::string command = PhotomatExecutable().string() + " " + arguments;
  const rlimit address_space{limits.address_space_bytes, limits.address_space_bytes};
  const auto cpu_seconds = static_cast<rlim_t>(limits.cpu_seconds);
  const rlimit cpu_time{cpu_seconds, cpu_seconds};
  std::array<int, 2> output_pipe{};
  if (pipe(output_pipe.data()) != 0) {
    ADD_FAILURE() << "cannot make a pipe for `" << command << "`: " << std::strerror(errno);
    return {-1, ""};
  }
  const pid_t child = fork();
  if (child < 0) {
    ADD_FAILURE() << "cannot start `" << command << "`: " << std::strerror(errno);
    close(output_pipe[0]);
    close(output_pipe[1]);
    return {-1, ""};
  }
  if (child == 0) {
    dup2(output_pipe[1], STDOUT_FILENO);
    dup2(output_pipe[1], STDERR_FILENO);
    close(output_pipe[0]);
    close(output_pipe[1]);
    if (limits.address_space_bytes > 0) setrlimit(RLIMIT_AS, &address_space);
    if (limits.cpu_seconds > 0) setrlimit(RLIMIT_CPU, &cpu_time);
    execl("/bin/sh", "sh", "-c", command.c_str(), static_cast<char*>(nullptr));
    _exit(127);
  }
  close(output_pipe[1]);
  std::string output;
  std::array<char, 4096> buffer;
  for (;;) {
    const ssize_t n = read(output_pipe[0], buffer.data(), buffer.size());
    if (n < 0 && errno == EINTR) continue;
    if (n <= 0) break;
    output.append(buffer.data(), static_cast<std::size_t>(n));
  }
  close(output_pipe[0]);
  int status = 0;
  while (waitpid(child, &status, 0) < 0 && errno == EINTR) {
  }
  return {WIFEXITED(status) ? WEXITSTATUS(status) : -1, output};
}

std::size_t StartupAddressSpace(const std::string& command) {
  constexpr std::size_t kMiB = std::size_t{1} << 20;
  const auto starts = [&](std::size_t bytes) {
    return RunPhotomat(command + " --help", {bytes, 10}).exit_code == 0;
  };
  std::size_t fails = 64 * kMiB, runs = 8192 * kMiB;
  if (!starts(runs)) {
    ADD_FAILURE() << "`photomat " << command << " --help` does not start under 8 GiB";
    return runs;
  }
  while (runs - fails > 4 * kMiB) {
    const std::size_t middle = fails + (runs - fails) / 2;
    (starts(middle) ? runs : fails) = middle;
  }
  std::printf("photomat %s starts in %zu MiB of address space\n", command.c_str(), runs / kMiB);
  return runs;
}

}  // namespace photomat::testing
