#include "bench/relight_cli_peer.h"

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

}  // namespace photomat
