#include "bench/relight_cli_peer.h"

#include <fmt/format.h>

#include <cstdlib>

namespace photomat {

std::optional<std::filesystem::path> FindRelightCli() {
  if (const char* cli = std::getenv("PHOTOMAT_RELIGHT_CLI"); cli && *cli) {
    return std::filesystem::path(cli);
  }
  if (const char* home = std::getenv("HOME")) {
    const std::filesystem::path cached =
        std::filesystem::path(home) / ".cache/photomat-peers/relight-build/relight-cli/relight-cli";
    if (std::filesystem::exists(cached)) return cached;
  }
  return std::nullopt;
}

std::string RelightCliArguments(const std::string& basis) {
  if (basis == "ptm") return "-b ptm -p 18";
  if (basis == "hsh") return "-b hsh -p 27";
  return fmt::format("-b {} -p 9", basis);
}

std::uintmax_t StoredBytes(const std::filesystem::path& path) {
  if (!std::filesystem::is_directory(path)) return std::filesystem::file_size(path);
  std::uintmax_t bytes = 0;
  for (const auto& entry : std::filesystem::recursive_directory_iterator(path)) {
    if (entry.is_regular_file()) bytes += entry.file_size();
  }
  return bytes;
}

}  // namespace photomat
