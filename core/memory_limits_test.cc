#include "core/memory_limits.h"

#include <gtest/gtest.h>
#include <pthread.h>
#include <sys/resource.h>

#include <atomic>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <memory>
#include <thread>
#include <vector>

namespace photomat {
namespace {

std::size_t MappedBytes() { return MappedAddressSpace().value_or(0); }

// The tests below set RLIMIT_AS, which stays with the process that sets it: they run in a
// fresh child (a threadsafe death test re-executes the binary) and report by exit code.
void LimitAddressSpaceTo(std::size_t room) {
  const std::size_t limit = MappedBytes() + room;
  const rlimit rl{limit, limit};
  setrlimit(RLIMIT_AS, &rl);
}

void ExitIfRoomIsWhatTheLimitLeaves() {
  const std::size_t given = std::size_t{400} << 20;
  LimitAddressSpaceTo(given);
  const std::optional<std::size_t> room = AddressSpaceRoom();
  // The room given, less what this process mapped since it measured (a few pages).
  const bool right = room && *room <= given && *room > given - (std::size_t{20} << 20);
  if (!right) std::fprintf(stderr, "room %zu of %zu given\n", room.value_or(0), given);
  std::exit(right ? 0 : 1);
}

TEST(MemoryLimitsTest, AddressSpaceRoomIsWhatTheLimitLeaves) {
  GTEST_FLAG_SET(death_test_style, "threadsafe");
  EXPECT_EXIT(ExitIfRoomIsWhatTheLimitLeaves(), ::testing::ExitedWithCode(0), "");
}

TEST(MemoryLimitsTest, NoRoomWithoutALimit) {
  rlimit limit{};
  ASSERT_EQ(getrlimit(RLIMIT_AS, &limit), 0);
  if (limit.rlim_cur != RLIM_INFINITY) GTEST_SKIP() << "this process runs under a ulimit -v";
  EXPECT_FALSE(AddressSpaceRoom().has_value());
}

// Many threads allocating at once, each holding its blocks until all have allocated (so that
// malloc sees contention and would give each its own arena): returns the address space they
// added beyond their stacks.
std::size_t AddressSpaceOfContendedAllocation(int threads) {
  const std::size_t before = MappedBytes();
  std::atomic<int> allocated{0};
  std::atomic<bool> release{false};
  std::atomic<std::size_t> peak{0};
  std::vector<std::thread> workers;
  for (int t = 0; t < threads; ++t) {
    workers.emplace_back([&] {
      std::vector<std::unique_ptr<char[]>> blocks;
      for (int i = 0; i < 2000; ++i) blocks.push_back(std::make_unique<char[]>(512));
      if (++allocated == threads) peak = MappedBytes();
      while (!release) std::this_thread::yield();
    });
  }
  while (allocated < threads) std::this_thread::yield();
  release = true;
  for (std::thread& worker : workers) worker.join();
  return peak - before;
}

void ExitIfCappedArenasKeepToTheReserve() {
  LimitAddressSpaceTo(std::size_t{2} << 30);
  FitMallocToAddressSpaceLimit();
  constexpr int kThreads = 16;
  const std::size_t added = AddressSpaceOfContendedAllocation(kThreads);
  // Uncapped, glibc reserves up to 64 MiB per thread here (measured without the cap: 1089 MiB
  // added). Capped: one arena's 64 MiB, the 16 threads' stacks, and the blocks (16 MiB in
  // all), with 32 MiB to spare: 240 MiB with 8 MiB stacks (measured: 196-204 MiB).
  pthread_attr_t attributes;
  std::size_t stack = 0;
  pthread_getattr_default_np(&attributes);
  pthread_attr_getstacksize(&attributes, &stack);
  pthread_attr_destroy(&attributes);
  const std::size_t bound = kThreads * stack + ((std::size_t{64} + 16 + 32) << 20);
  if (added > bound) std::fprintf(stderr, "added %zu, bound %zu\n", added, bound);
  std::exit(added <= bound ? 0 : 1);
}

TEST(MemoryLimitsTest, UnderALimitThreadsShareTheCappedArenas) {
  GTEST_FLAG_SET(death_test_style, "threadsafe");
  EXPECT_EXIT(ExitIfCappedArenasKeepToTheReserve(), ::testing::ExitedWithCode(0), "");
}

TEST(MemoryLimitsTest, WorkerThreadsReserveAStackPerThreadAndTheArenas) {
  const std::size_t cores = std::max(1u, std::thread::hardware_concurrency());
  // At least 3 x cores stacks of 8 MiB and one arena of 64 MiB.
  EXPECT_GE(WorkerThreadsAddressSpace(), (3 * cores * 8 + 64) << 20);
}

// Without a limit the machine allows far more than the fast band size: the bands get
// kFastBandMemory beyond their fixed buffers.
TEST(MemoryLimitsTest, BandsGetTheFastBandSizeWhereMemoryAllowsMore) {
  const std::size_t fixed = std::size_t{3} << 20, minimum = std::size_t{16} << 20;
  if (DefaultMemoryBudget(minimum) < fixed + kFastBandMemory) {
    GTEST_SKIP() << "SKIPPED: this process may use less than " << (kFastBandMemory >> 20) << " MB";
  }
  EXPECT_EQ(DefaultBandBudget(minimum, fixed), fixed + kFastBandMemory);
  EXPECT_EQ(DefaultBandBudget(minimum), kFastBandMemory);
}

// Under an address-space limit that leaves less than the fast band size, the bands get what the
// limit allows (DefaultMemoryBudget), never below the step's minimum.
void ExitIfTightLimitBoundsTheBands() {
  const std::size_t minimum = std::size_t{1} << 20;
  LimitAddressSpaceTo(WorkerThreadsAddressSpace() + (std::size_t{40} << 20));
  const std::size_t bands = DefaultBandBudget(minimum, std::size_t{8} << 20);
  const bool right =
      bands == DefaultMemoryBudget(minimum) && bands < kFastBandMemory && bands >= minimum;
  if (!right) std::fprintf(stderr, "bands %zu under the limit\n", bands);
  std::exit(right ? 0 : 1);
}

TEST(MemoryLimitsTest, UnderATightLimitBandsGetWhatTheLimitAllows) {
  GTEST_FLAG_SET(death_test_style, "threadsafe");
  EXPECT_EXIT(ExitIfTightLimitBoundsTheBands(), ::testing::ExitedWithCode(0), "");
}

// Minor page faults of 20 rounds of allocating, touching and freeing 12 buffers of 8 MiB (a band
// of images), as a streamed fit does band after band.
long FaultsOfRepeatedBandAllocations() {
  const auto faults = [] {
    rusage usage{};
    getrusage(RUSAGE_SELF, &usage);
    return usage.ru_minflt;
  };
  const long before = faults();
  for (int round = 0; round < 20; ++round) {
    std::vector<std::unique_ptr<char[]>> band;
    for (int i = 0; i < 12; ++i) {
      band.push_back(std::make_unique<char[]>(std::size_t{8} << 20));
      std::memset(band.back().get(), round, std::size_t{8} << 20);
    }
  }
  return faults() - before;
}

void ExitIfFreedBandsAreReused() {
  KeepFreedMemoryForReuse();
  const long faults = FaultsOfRepeatedBandAllocations();
  // One band's first touch is 12 x 2048 = 24,576 faults. Kept for reuse: the first round's,
  // with one round's worth to spare (measured: 24,578).
  std::fprintf(stderr, "kept for reuse: %ld faults\n", faults);
  std::exit(faults <= 2 * 24576 ? 0 : 1);
}

TEST(MemoryLimitsTest, FreedBandBuffersAreReusedWithoutNewPageFaults) {
  if (AddressSpaceRoom()) GTEST_SKIP() << "SKIPPED: an address-space limit is set (ulimit -v)";
  GTEST_FLAG_SET(death_test_style, "threadsafe");
  EXPECT_EXIT(ExitIfFreedBandsAreReused(), ::testing::ExitedWithCode(0), "");
}

TEST(MemoryLimitsTest, WithoutTheThresholdsFreedBandsAreFreshPagesAgain) {
  // The measurement the choice rests on: glibc's defaults, in a child of their own, touch
  // fresh pages in most rounds (measured: 20 rounds' worth, 490,958 faults; bound: half of them).
  GTEST_FLAG_SET(death_test_style, "threadsafe");
  EXPECT_EXIT(
      {
        const long faults = FaultsOfRepeatedBandAllocations();
        std::fprintf(stderr, "glibc defaults: %ld faults\n", faults);
        std::exit(faults > 10 * 24576 ? 0 : 1);
      },
      ::testing::ExitedWithCode(0), "");
}

// A band's height: as many rows as the budget holds, at least one and at most the image's; a fixed
// height (tests) is kept within the image; no budget means the default band budget.
TEST(MemoryLimitsTest, BandRowsAreWhatTheBudgetHoldsWithinTheImage) {
  EXPECT_EQ(RowsWithinBytes(1000, 100, 50), 10);
  EXPECT_EQ(RowsWithinBytes(1099, 100, 50), 10);
  EXPECT_EQ(RowsWithinBytes(10, 100, 50), 1);       // less than a row: one row
  EXPECT_EQ(RowsWithinBytes(100000, 100, 50), 50);  // more than the image: the image
  EXPECT_EQ(BudgetedBandRows(7, 1000, 0, 100, 50), 7);
  EXPECT_EQ(BudgetedBandRows(70, 1000, 0, 100, 50), 50);
  EXPECT_EQ(BudgetedBandRows(0, 1000, 0, 100, 50), 10);
  const std::size_t minimum = std::size_t{16} << 20;
  const std::size_t row = std::size_t{1} << 20;
  EXPECT_EQ(BudgetedBandRows(0, 0, minimum, row, 1 << 20),
            static_cast<int>(DefaultBandBudget(minimum) / row));
}

}  // namespace
}  // namespace photomat
