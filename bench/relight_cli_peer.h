#ifndef PHOTOMAT_BENCH_RELIGHT_CLI_PEER_H_
#define PHOTOMAT_BENCH_RELIGHT_CLI_PEER_H_

#include <cstdint>
#include <filesystem>
#include <optional>
#include <string>

namespace photomat {

// relight-cli for the peer benchmarks: $PHOTOMAT_RELIGHT_CLI, else the build bench/peer_table
// caches under ~/.cache/photomat-peers, else none (the benchmark then leaves its columns empty).
std::optional<std::filesystem::path> FindRelightCli();

// relight-cli's arguments for one of its bases with the planes the peer benchmarks give it (RGB
// PTM's 18 coefficients, HSH's 27, 9 PCA planes for rbf and bilinear).
std::string RelightCliArguments(const std::string& basis);

// The bytes a result takes on disk: a file's size, or the sum over every file in a folder.
std::uintmax_t StoredBytes(const std::filesystem::path& path);

}  // namespace photomat

#endif  // PHOTOMAT_BENCH_RELIGHT_CLI_PEER_H_
