#ifndef PHOTOMAT_CORE_MEMORY_LIMITS_H_
#define PHOTOMAT_CORE_MEMORY_LIMITS_H_

#include <cstddef>
#include <optional>

// The limits a process's memory runs into (a batch system's cgroup, `ulimit -v`), and what the
// program maps beyond its data, so that work sized from a budget (the streamed fit's bands)
// fits under them.
namespace photomat {

// The address space this process maps now (/proc/self/statm), or none where it cannot be read.
std::optional<std::size_t> MappedAddressSpace();

// The address space left under the soft RLIMIT_AS, or none without a limit.
std::optional<std::size_t> AddressSpaceRoom();

// This process's cgroup v2 memory.max, or none where there is no limit or no cgroup v2.
std::optional<std::size_t> CgroupMemoryLimit();

// IMPLEMENTER CHOICE: under an address-space limit, glibc's malloc may keep at most this many
// arenas (the main one included). Each further arena reserves 64 MiB of address space for a
// thread that allocates while others do (up to 8 per core); measured on 2 cores, a streamed fit
// made 4 to 5 of them, 250-320 MiB of a 1000 MiB limit reserved, not used. Two keep the
// contention low (most large buffers are mapped directly) and the reservation to 64 MiB.
inline constexpr int kMallocArenasUnderAddressSpaceLimit = 2;

// Caps malloc's arenas at kMallocArenasUnderAddressSpaceLimit when RLIMIT_AS is set; no effect
// otherwise. For a program's main(), before it starts threads: the arenas are process-wide.
void FitMallocToAddressSpaceLimit();

// IMPLEMENTER CHOICE: outside an address-space limit, malloc keeps freed buffers for reuse:
// blocks up to kMallocReuseThreshold come from its heaps instead of fresh mappings, and freed heap
// memory is returned to the system only beyond kMallocKeepFreed. Streamed work allocates the same
// band buffers again and again; with glibc's defaults each band's buffers were fresh pages, and
// the kernel's first-touch faults cost a 12 MP x 50 PTM fit 7 s of system time in 6-row bands
// (3.3 s kept; README, "Streamed fitting"). Under RLIMIT_AS address space is what runs out, so
// there the defaults stay.
inline constexpr std::size_t kMallocReuseThreshold = std::size_t{32} << 20;
inline constexpr std::size_t kMallocKeepFreed = std::size_t{1} << 30;

// Sets the thresholds above when RLIMIT_AS is not set; no effect otherwise. For a program's
// main(), with FitMallocToAddressSpaceLimit.
void KeepFreedMemoryForReuse();

// The address space worker threads started from now on will map besides the data they hold:
// a stack each (RLIMIT_STACK, at least 8 MiB) for TBB's workers and the image decoders' two
// pools (one thread per core each), and the malloc arenas FitMallocToAddressSpaceLimit allows.
std::size_t WorkerThreadsAddressSpace();

// The memory a streamed command may give its bands by default (streamed fit, relight, export,
// evaluation): IMPLEMENTER CHOICE, half the machine's physical memory (sysconf), at least 256
// MiB: the rest is for the program, the decoders and the system; but at most half the process's
// memory limits: its cgroup's (memory.max, as a Slurm job or a container sets it) and the room
// its address-space limit (RLIMIT_AS, `ulimit -v`) leaves beyond what is mapped already (the
// program's libraries alone map about 0.6 GB) and what the worker threads will map
// (WorkerThreadsAddressSpace); never below `minimum`.
std::size_t DefaultMemoryBudget(std::size_t minimum);

// IMPLEMENTER CHOICE: without an explicit budget a streamed step's bands hold at most this much
// (beyond its fixed buffers), even where DefaultMemoryBudget allows more. Bands are for memory,
// but they are faster too: a whole-image band of DiLiGenT cat (96 x 612 x 512 x 3) allocates and
// first touches 0.9 GB per fit, and the kernel's page faults cost as much CPU as the fit (README,
// "Streamed fitting": CPU time per band size); bands this small are reused by malloc from one to
// the next (KeepFreedMemoryForReuse), and there are enough of them for reading to overlap work.
inline constexpr std::size_t kFastBandMemory = std::size_t{64} << 20;

// The budget a streamed step (fit, relight, export, evaluation) gives its bands when the caller
// gives none: `fixed_bytes` (buffers whatever the band height, e.g. the decoders' chunks) plus
// kFastBandMemory, at most DefaultMemoryBudget(minimum).
std::size_t DefaultBandBudget(std::size_t minimum, std::size_t fixed_bytes = 0);

// As many rows of `row_bytes` as `memory_bytes` holds, at least 1 and at most `height`: a band's
// height from its budget.
int RowsWithinBytes(std::size_t memory_bytes, std::size_t row_bytes, int height);

// A streamed step's band height: `fixed_rows` when positive (tests; at most `height`), else
// RowsWithinBytes of its budget, `memory_bytes` or, when 0, DefaultBandBudget(`minimum`).
int BudgetedBandRows(int fixed_rows, std::size_t memory_bytes, std::size_t minimum,
                     std::size_t row_bytes, int height);

}  // namespace photomat

#endif  // PHOTOMAT_CORE_MEMORY_LIMITS_H_
