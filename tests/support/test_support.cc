#include "tests/support/test_support.h"

#include <sys/resource.h>
#include <unistd.h>

#include <csignal>

#include <chrono>
#include <cstdlib>
#include <fstream>

namespace photomat::testing {

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

}  // namespace photomat::testing
