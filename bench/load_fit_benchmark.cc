// Load and fit times on a real capture (default: DiLiGenT cat, 96 images, 612x512, 16-bit RGB).
// Run through bench/load_fit_table, which starts one process per case so that each case's peak
// memory is its own, and prints the table the foundation issue asks for.
#include <benchmark/benchmark.h>
#include <sys/resource.h>

#include <algorithm>
#include <cstdlib>
#include <filesystem>
#include <string>

#include "capture/io/load_photometric_set.h"
#include "capture/io/streamed_set.h"
#include "core/memory_limits.h"
#include "represent/fitting/fit.h"

namespace photomat {
namespace {

std::filesystem::path CaptureFolder() {
  if (const char* set = std::getenv("PHOTOMAT_BENCH_SET")) return set;
  const char* data = std::getenv("PHOTOMAT_TEST_DATA");
  return std::filesystem::path(data ? data : "../shared/data") / "diligent" / "cat";
}

void ReportPeakMemory(benchmark::State& state) {
  rusage usage{};
  getrusage(RUSAGE_SELF, &usage);
  state.counters["peak_rss_mb"] = static_cast<double>(usage.ru_maxrss) / 1024.0;  // KiB -> MiB
}

void BM_Load(benchmark::State& state) {
  for (auto _ : state) {
    LoadedSet loaded = LoadPhotometricSet(CaptureFolder());
    benchmark::DoNotOptimize(loaded.set.image(0).values().data());
  }
  ReportPeakMemory(state);
}

// Decoding only, band by band as `photomat fit` streams: the load that bench/stream_fit_table
// divides by, PHOTOMAT_BENCH_BAND_ROWS rows at a time (default 64; the table passes the band
// height `photomat fit` reports). Every band is decoded into the same buffer (one band of every
// image, as the least-squares fit decodes into its image data matrix), so the load is the
// decoding alone: no allocation or first touch per band.
void BM_StreamedLoad(benchmark::State& state) {
  const char* rows_variable = std::getenv("PHOTOMAT_BENCH_BAND_ROWS");
  const int rows = std::max(1, rows_variable ? std::atoi(rows_variable) : 64);
  for (auto _ : state) {
    StreamedSet set = OpenStreamedSet(CaptureFolder());
    const std::ptrdiff_t plane = static_cast<std::ptrdiff_t>(set.width()) * rows;
    std::vector<float> buffer(static_cast<std::size_t>(plane) * set.channels() * set.size());
    while (set.next_row() < set.height()) {
      const int band_rows = std::min(rows, set.height() - set.next_row());
      std::vector<ImageView> views;
      for (int i = 0; i < set.size(); ++i) {
        float* image = buffer.data() + static_cast<std::ptrdiff_t>(i) * plane * set.channels();
        views.emplace_back(image, set.width(), band_rows, set.channels(), set.width(),
                           static_cast<std::ptrdiff_t>(set.width()) * band_rows);
      }
      set.ReadBandInto(views);
      benchmark::DoNotOptimize(buffer.data());
    }
  }
  ReportPeakMemory(state);
}

void BM_LoadAndFit(benchmark::State& state, const std::string& method) {
  for (auto _ : state) {
    const LoadedSet loaded = LoadPhotometricSet(CaptureFolder());
    const Representation representation = Fit(loaded.set, Method::Parse(method));
    benchmark::DoNotOptimize(representation.maps().values().data());
  }
  ReportPeakMemory(state);
}

BENCHMARK(BM_Load)->Unit(benchmark::kMillisecond)->UseRealTime()->Iterations(3);
BENCHMARK(BM_StreamedLoad)->Unit(benchmark::kMillisecond)->UseRealTime()->Iterations(1);
BENCHMARK_CAPTURE(BM_LoadAndFit, gradient, std::string("gradient"))
    ->Unit(benchmark::kMillisecond)
    ->UseRealTime()
    ->Iterations(3);
BENCHMARK_CAPTURE(BM_LoadAndFit, ptm, std::string("ptm"))
    ->Unit(benchmark::kMillisecond)
    ->UseRealTime()
    ->Iterations(3);
BENCHMARK_CAPTURE(BM_LoadAndFit, eigen6, std::string("eigen6"))
    ->Unit(benchmark::kMillisecond)
    ->UseRealTime()
    ->Iterations(3);

}  // namespace
}  // namespace photomat

// As every photomat command (apps/cli_main.cc): malloc keeps freed band buffers for reuse, so the
// load the fits are divided by pays no more page faults than the fits' own decoding does.
int main(int argc, char** argv) {
  photomat::FitMallocToAddressSpaceLimit();
  photomat::KeepFreedMemoryForReuse();
  benchmark::Initialize(&argc, argv);
  if (benchmark::ReportUnrecognizedArguments(argc, argv)) return 1;
  benchmark::RunSpecifiedBenchmarks();
  benchmark::Shutdown();
  return 0;
}
