#include "tests/support/test_support.h"

#include <sys/resource.h>
#include <sys/wait.h>
#include <unistd.h>

#include <array>
#include <cerrno>
#include <chrono>
#include <csignal>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <fstream>

namespace photomat::testing {

bool SameBits(const Image& a, const Image& b) {
  return a.SameShape(b) &&
         std::memcmp(a.values().data(), b.values().data(), a.values().size_bytes()) == 0;
}

std::optional<std::filesystem::path> TestDataDir() {
  const char* value = std::getenv(kTestDataVariable);
  if (value == nullptr || *value == '\0') return std::nullopt;
  return std::filesystem::path(value);
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

std::filesystem::path PhotomatExecutable() {
  const char* dir = std::getenv("PHOTOMAT_BINARY_DIR");
  return std::filesystem::path(dir ? dir : ".") / "bin" / "photomat";
}

RunResult RunPhotomat(const std::string& arguments) {
  const std::string command = PhotomatExecutable().string() + " " + arguments + " 2>&1";
  FILE* pipe = popen(command.c_str(), "r");
  if (pipe == nullptr) {
    ADD_FAILURE() << "cannot start `" << command << "`: " << std::strerror(errno);
    return {-1, ""};
  }
  std::string output;
  std::array<char, 4096> buffer;
  while (std::size_t n = std::fread(buffer.data(), 1, buffer.size(), pipe)) {
    output.append(buffer.data(), n);
  }
  const int status = pclose(pipe);
  return {WIFEXITED(status) ? WEXITSTATUS(status) : -1, output};
}

}  // namespace photomat::testing
