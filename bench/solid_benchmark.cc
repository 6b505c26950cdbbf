// Solid texture timings on this machine, for bench/solid_table (issue 8's targets):
//   - a 64^3 exemplar grown to 128^3 (appearance space and similarity set built, not cached),
//   - a 128^3 block from three 128 x 128 views (Exemplar_20 of the solid exemplars when
//     $PHOTOMAT_TEST_DATA is set, otherwise slices of a procedural wood volume).
// Each case reports its phases as counters (seconds) and the process's peak resident memory.
#include <benchmark/benchmark.h>
#include <sys/resource.h>

#include <chrono>
#include <cstdlib>
#include <filesystem>
#include <string>

#include "core/image_io.h"
#include "synthesize/solid/exemplar_solid.h"
#include "synthesize/solid/procedural_exemplars.h"
#include "synthesize/solid/solid_quality.h"
#include "synthesize/solid/spectral_solid.h"

namespace photomat {
namespace {

double Since(std::chrono::steady_clock::time_point start) {
  return std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
}

void ReportPeakMemory(benchmark::State& state) {
  rusage usage{};
  getrusage(RUSAGE_SELF, &usage);
  state.counters["peak_rss_mb"] = static_cast<double>(usage.ru_maxrss) / 1024.0;
}

void BM_GrowExemplar(benchmark::State& state, ProceduralPattern pattern) {
  const int exemplar_size = static_cast<int>(state.range(0));
  const int output_size = static_cast<int>(state.range(1));
  const Image exemplar = MakeProceduralExemplar(pattern, exemplar_size, 1);
  double prepare = 0, synthesis = 0, match_error = 0, jitter_error = 0;
  for (auto _ : state) {
    const auto start = std::chrono::steady_clock::now();
    const PreparedExemplar prepared = PrepareExemplar(exemplar, {}, {}, std::nullopt);
    prepare = Since(start);
    ExemplarSolidOptions options;
    options.size = ImageExtent::Cube(output_size);
    const auto synthesis_start = std::chrono::steady_clock::now();
    const ExemplarSolidResult result = SynthesizeExemplarSolid(exemplar, prepared, options);
    synthesis = Since(synthesis_start);
    state.PauseTiming();
    match_error = NeighbourhoodMatchError(result.volume, exemplar, prepared.appearance);
    options.correction_passes = 0;
    jitter_error = NeighbourhoodMatchError(
        SynthesizeExemplarSolid(exemplar, prepared, options).volume, exemplar, prepared.appearance);
    state.ResumeTiming();
  }
  state.counters["prepare_s"] = prepare;
  state.counters["synthesis_s"] = synthesis;
  state.counters["match_error"] = match_error;
  state.counters["jitter_only_match_error"] = jitter_error;
  ReportPeakMemory(state);
}

// Statistics of a grown solid against the exemplar (spec section 11, items 4 and 5), corrected
// and jitter only (correction off): colour histogram L1, radially averaged spectrum (dB),
// neighbourhood-match error, and the largest coherent patch as a share of the output. An output
// of 64^3 is a whole number of periods of 16^3 and 32^3 exemplars and not of 24^3 ones. The third
// argument picks the settings: 0 the defaults, 1 histogram matching off, 2 occupancy matching
// off.
void MeasureGrowth(benchmark::State& state, const Image& exemplar, int output_size, int settings) {
  const auto spectrum = [&exemplar](const Image& solid) {
    return LogSpectralDistance(RadialPowerSpectrum(solid, 8), RadialPowerSpectrum(exemplar, 8));
  };
  for (auto _ : state) {
    const PreparedExemplar prepared = PrepareExemplar(exemplar, {}, {}, std::nullopt);
    ExemplarSolidOptions options;
    options.size = ImageExtent::Cube(output_size);
    if (settings == 1) options.histogram_matching = 0.0;
    if (settings == 2) options.occupancy_matching = 0.0;
    const ExemplarSolidResult corrected = SynthesizeExemplarSolid(exemplar, prepared, options);
    options.correction_passes = 0;
    const Image jitter = SynthesizeExemplarSolid(exemplar, prepared, options).volume;
    state.counters["histogram"] = HistogramDistance(corrected.volume, exemplar);
    state.counters["jitter_histogram"] = HistogramDistance(jitter, exemplar);
    state.counters["emd"] = EarthMoverDistance(corrected.volume, exemplar);
    state.counters["jitter_emd"] = EarthMoverDistance(jitter, exemplar);
    state.counters["spectrum_db"] = spectrum(corrected.volume);
    state.counters["jitter_spectrum_db"] = spectrum(jitter);
    state.counters["match_error"] =
        NeighbourhoodMatchError(corrected.volume, exemplar, prepared.appearance);
    state.counters["jitter_match_error"] =
        NeighbourhoodMatchError(jitter, exemplar, prepared.appearance);
    state.counters["largest_patch"] =
        static_cast<double>(
            CoherentPatches(corrected.coordinates, prepared.appearance.domain).largest) /
        static_cast<double>(corrected.volume.pixel_count());
  }
}

// Exemplar side, output side, settings: 16^3, 24^3 and 32^3 grown to 64^3 in every setting, and
// 16^3 to 32^3 (the tests' size) with and without histogram matching.
void GrowQualityCases(benchmark::internal::Benchmark* cases) {
  cases->ArgsProduct({{32, 24, 16}, {64}, {0, 1, 2}})
      ->Args({16, 32, 0})
      ->Args({16, 32, 1})
      ->Unit(benchmark::kSecond)
      ->Iterations(1);
}

void BM_GrowQuality(benchmark::State& state, ProceduralPattern pattern) {
  MeasureGrowth(state, MakeProceduralExemplar(pattern, static_cast<int>(state.range(0)), 3),
                static_cast<int>(state.range(1)), static_cast<int>(state.range(2)));
}

// The same for solids made from a photograph of the solid-exemplar set (the same view on all three
// planes, as `photomat solid from-views --view`; 3 iterations). Skipped without the data.
void BM_GrowRealQuality(benchmark::State& state, const char* photograph) {
  const char* data = std::getenv("PHOTOMAT_TEST_DATA");
  const std::filesystem::path file =
      data ? std::filesystem::path(data) / "textures" / "solid-exemplars" / photograph
           : std::filesystem::path();
  if (!data || !std::filesystem::exists(file)) {
    state.SkipWithError("needs $PHOTOMAT_TEST_DATA/textures/solid-exemplars");
    for (auto _ : state) {
    }
    return;
  }
  const Image view = ReadImage(file).image;
  SpectralSolidOptions options;
  options.size = static_cast<int>(state.range(0));
  options.iterations = 3;
  const Image exemplar =
      SynthesizeSpectralSolid(
          {{SlicePlane::kXY, view}, {SlicePlane::kXZ, view}, {SlicePlane::kYZ, view}}, options)
          .volume;
  MeasureGrowth(state, exemplar, static_cast<int>(state.range(1)),
                static_cast<int>(state.range(2)));
}

std::vector<SolidView> Views(int size) {
  std::vector<SolidView> views;
  if (const char* data = std::getenv("PHOTOMAT_TEST_DATA")) {
    const std::filesystem::path folder =
        std::filesystem::path(data) / "textures" / "solid-exemplars";
    for (SlicePlane plane : kAllSlicePlanes) {
      const auto file = folder / ("Exemplar_20_" + std::string(ToString(plane)) + ".jpg");
      if (std::filesystem::exists(file)) views.push_back({plane, ReadImage(file).image});
    }
    if (views.size() == 3) return views;
    views.clear();
  }
  const Image wood = MakeProceduralExemplar(ProceduralPattern::kWood, size, 1);
  for (SlicePlane plane : kAllSlicePlanes) {
    views.push_back({plane, ExtractSlice(wood, plane, size / 3)});
  }
  return views;
}

void BM_FromThreeViews(benchmark::State& state) {
  const int size = static_cast<int>(state.range(0));
  const std::vector<SolidView> views = Views(size);
  SpectralSolidOptions options;
  options.size = size;
  options.iterations = static_cast<int>(state.range(1));
  double inside = 0, histogram = 0;
  for (auto _ : state) {
    const SpectralSolidResult result = SynthesizeSpectralSolid(views, options);
    inside = histogram = 1e9;
    for (const PlaneFit& fit : result.iterations.back().fits) {
      inside = std::min(inside, fit.inside_bounds_average);
      histogram = std::min(histogram, -fit.histogram_l1_mean);
    }
    benchmark::DoNotOptimize(result.volume.values().data());
  }
  state.counters["worst_inside_bounds"] = inside;
  state.counters["worst_histogram_l1"] = -histogram;
  ReportPeakMemory(state);
}

BENCHMARK_CAPTURE(BM_GrowExemplar, marble, ProceduralPattern::kMarble)
    ->Args({64, 128})
    ->Unit(benchmark::kSecond)
    ->UseRealTime()
    ->Iterations(1);
BENCHMARK_CAPTURE(BM_GrowExemplar, cells, ProceduralPattern::kCells)
    ->Args({64, 128})
    ->Unit(benchmark::kSecond)
    ->UseRealTime()
    ->Iterations(1);
BENCHMARK_CAPTURE(BM_GrowQuality, marble, ProceduralPattern::kMarble)->Apply(GrowQualityCases);
BENCHMARK_CAPTURE(BM_GrowQuality, cells, ProceduralPattern::kCells)->Apply(GrowQualityCases);
BENCHMARK_CAPTURE(BM_GrowQuality, wood, ProceduralPattern::kWood)->Apply(GrowQualityCases);
BENCHMARK_CAPTURE(BM_GrowQuality, stripes, ProceduralPattern::kStripes)->Apply(GrowQualityCases);
BENCHMARK_CAPTURE(BM_GrowRealQuality, Exemplar_14, "Exemplar_14.jpg")
    ->ArgsProduct({{32, 24}, {64}, {0, 1}})
    ->Unit(benchmark::kSecond)
    ->Iterations(1);
BENCHMARK_CAPTURE(BM_GrowRealQuality, Exemplar_20, "Exemplar_20.jpg")
    ->ArgsProduct({{32, 24}, {64}, {0, 1}})
    ->Unit(benchmark::kSecond)
    ->Iterations(1);
BENCHMARK(BM_FromThreeViews)
    ->Args({128, 4})
    ->Unit(benchmark::kSecond)
    ->UseRealTime()
    ->Iterations(1);

}  // namespace
}  // namespace photomat

BENCHMARK_MAIN();
