#ifndef PHOTOMAT_BENCH_RELIGHT_CLI_PEER_H_
#define PHOTOMAT_BENCH_RELIGHT_CLI_PEER_H_

#include <filesystem>
#include <optional>

namespace photomat {

// relight-cli for the peer benchmarks: $PHOTOMAT_RELIGHT_CLI, else the build bench/peer_table
// caches under ~/.cache/photomat-peers, else none (the benchmark then leaves its columns empty).
std::optional<std::filesystem::path> FindRelightCli();

}  // namespace photomat

#endif  // PHOTOMAT_BENCH_RELIGHT_CLI_PEER_H_
