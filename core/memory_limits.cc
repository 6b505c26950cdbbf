#include "core/memory_limits.h"

#include <malloc.h>
#include <sys/resource.h>
#include <unistd.h>

#include <algorithm>
#include <filesystem>
#include <fstream>
#include <string>
#include <thread>

namespace photomat {
namespace {

// glibc's HEAP_MAX_SIZE on 64-bit: 2 x the largest mmap threshold (32 MiB).
constexpr std::size_t kMallocArenaReservation = std::size_t{64} << 20;
constexpr std::size_t kDefaultThreadStack = std::size_t{8} << 20;

// The soft RLIMIT_AS, or none without one.
std::optional<std::size_t> AddressSpaceLimit() {
  rlimit limit{};
  if (getrlimit(RLIMIT_AS, &limit) != 0 || limit.rlim_cur == RLIM_INFINITY) return std::nullopt;
  return static_cast<std::size_t>(limit.rlim_cur);
}

}  // namespace

std::optional<std::size_t> MappedAddressSpace() {
  // /proc/self/statm's first field: the whole address space, in pages.
  std::size_t pages = 0;
  if (std::ifstream statm("/proc/self/statm"); !(statm >> pages)) return std::nullopt;
  return pages * static_cast<std::size_t>(sysconf(_SC_PAGESIZE));
}

std::optional<std::size_t> AddressSpaceRoom() {
  const std::optional<std::size_t> cap = AddressSpaceLimit();
  if (!cap) return std::nullopt;
  const std::optional<std::size_t> used = MappedAddressSpace();
  if (!used) return std::nullopt;
  return *cap > *used ? *cap - *used : 0;
}

std::optional<std::size_t> CgroupMemoryLimit() {
  // cgroup v2: this process's group is the "0::PATH" line of /proc/self/cgroup.
  std::ifstream groups("/proc/self/cgroup");
  for (std::string line; std::getline(groups, line);) {
    if (!line.starts_with("0::")) continue;
    std::ifstream max(std::filesystem::path("/sys/fs/cgroup") /
                      std::filesystem::path(line.substr(3)).relative_path() / "memory.max");
    std::size_t bytes = 0;
    if (max >> bytes) return bytes;  // "max" (no limit) does not parse
    return std::nullopt;
  }
  return std::nullopt;
}

void FitMallocToAddressSpaceLimit() {
  if (AddressSpaceLimit()) mallopt(M_ARENA_MAX, kMallocArenasUnderAddressSpaceLimit);
}

void KeepFreedMemoryForReuse() {
  if (AddressSpaceLimit()) return;
  mallopt(M_MMAP_THRESHOLD, static_cast<int>(kMallocReuseThreshold));
  mallopt(M_TRIM_THRESHOLD, static_cast<int>(kMallocKeepFreed));
}

std::size_t WorkerThreadsAddressSpace() {
  rlimit stack{};
  std::size_t stack_bytes = kDefaultThreadStack;
  if (getrlimit(RLIMIT_STACK, &stack) == 0 && stack.rlim_cur != RLIM_INFINITY) {
    stack_bytes = std::max(stack_bytes, static_cast<std::size_t>(stack.rlim_cur));
  }
  const std::size_t cores = std::max(1u, std::thread::hardware_concurrency());
  // The main arena grows from the program break, the rest are each a reservation.
  const std::size_t arenas = kMallocArenasUnderAddressSpaceLimit - 1;
  return 3 * cores * stack_bytes + arenas * kMallocArenaReservation;
}

std::size_t DefaultMemoryBudget(std::size_t minimum) {
  const long pages = sysconf(_SC_PHYS_PAGES), page = sysconf(_SC_PAGESIZE);
  const std::size_t physical =
      pages > 0 && page > 0 ? static_cast<std::size_t>(pages) * static_cast<std::size_t>(page)
                            : std::size_t{4} << 30;
  std::size_t budget = std::max(physical / 2, std::size_t{256} << 20);
  if (const std::optional<std::size_t> cgroup = CgroupMemoryLimit()) {
    budget = std::min(budget, *cgroup / 2);
  }
  if (const std::optional<std::size_t> room = AddressSpaceRoom()) {
    // The worker threads the command starts map stacks and malloc arenas from the same room.
    const std::size_t threads = WorkerThreadsAddressSpace();
    budget = std::min(budget, *room > threads ? (*room - threads) / 2 : 0);
  }
  return std::max(budget, minimum);
}

std::size_t DefaultBandBudget(std::size_t minimum, std::size_t fixed_bytes) {
  return std::min(DefaultMemoryBudget(minimum), fixed_bytes + kFastBandMemory);
}

int RowsWithinBytes(std::size_t memory_bytes, std::size_t row_bytes, int height) {
  const std::size_t rows = memory_bytes / std::max<std::size_t>(row_bytes, 1);
  return static_cast<int>(
      std::clamp<std::size_t>(rows, 1, static_cast<std::size_t>(std::max(height, 1))));
}

int BudgetedBandRows(int fixed_rows, std::size_t memory_bytes, std::size_t minimum,
                     std::size_t row_bytes, int height) {
  if (fixed_rows > 0) return std::min(fixed_rows, height);
  return RowsWithinBytes(memory_bytes > 0 ? memory_bytes : DefaultBandBudget(minimum), row_bytes,
                         height);
}

}  // namespace photomat
