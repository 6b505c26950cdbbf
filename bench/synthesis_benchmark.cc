// Synthesis time and quality (issue 4): image quilting with brute-force and fast exact search (and
// fast search with the variety preset, "variety"), and the pixel-based method, growing each
// exemplar of shared/data/textures/quilting and a 6-map PTM stack of the synthetic sample to
// 512 x 512. Run through bench/synthesis_table, which adds G'MIC's patch-based synthesis on the
// same inputs and prints the table the issue asks for.
//
// Each case times planning plus applying the plan in memory (no file I/O), as wall time and as
// the CPU time of all the process's threads, and reports, as counters, the quality of its output:
// the mean nearest-patch distance (7 x 7, RMS per value in min-max units of the sample), the seam
// score from the source map and the roughness ratio.
#include <benchmark/benchmark.h>
#include <sys/resource.h>

#include <cstdlib>
#include <filesystem>
#include <string>
#include <vector>

#include "capture/synthetic/synthetic_capture.h"
#include "core/error.h"
#include "core/image_io.h"
#include "represent/fitting/fit.h"
#include "synthesize/texture/synthesis.h"
#include "synthesize/texture/synthesis_quality.h"

namespace photomat {
namespace {

constexpr int kOutputSize = 512;
constexpr int kPtmSampleSize = 128;

// CPU seconds of every thread of this process so far (user + system): unlike wall time, barely
// affected by other processes competing for the cores.
double ProcessCpuSeconds() {
  rusage usage{};
  getrusage(RUSAGE_SELF, &usage);
  auto seconds = [](const timeval& t) { return t.tv_sec + t.tv_usec * 1e-6; };
  return seconds(usage.ru_utime) + seconds(usage.ru_stime);
}

std::filesystem::path ExemplarFolder() {
  const char* data = std::getenv("PHOTOMAT_TEST_DATA");
  return std::filesystem::path(data ? data : "../shared/data") / "textures" / "quilting";
}

// The bench's 6-channel stack: a PTM (a0..a5 of luminance) of the synthetic bricks sample,
// 128 x 128, rendered under the thesis's 36 lights with shadows and highlights, made grey.
Image SyntheticPtmMaps() {
  SyntheticMaterialOptions material_options;
  material_options.width = material_options.height = kPtmSampleSize;
  material_options.max_slope_degrees = 45.0;
  const SyntheticMaterial material = MakeSyntheticMaterial(material_options);
  std::vector<LightDirection> lights;
  for (double slant : {30.0, 45.0, 60.0}) {
    for (int tilt = 0; tilt < 360; tilt += 30)
      lights.push_back(LightDirection::FromSlantTilt(slant, tilt));
  }
  SyntheticRenderOptions render;
  render.shadows = true;
  render.specular = 0.25;
  const PhotometricSet colour = RenderSyntheticCapture(material, lights, render);
  std::vector<Image> grey;
  for (const Image& image : colour.images()) {
    Image y(image.width(), image.height(), 1);
    for (std::size_t i = 0; i < image.pixel_count(); ++i) {
      const auto p = image.pixel(i);
      y.pixel(i)[0] = (p[0] + p[1] + p[2]) / 3.0f;
    }
    grey.push_back(std::move(y));
  }
  const Representation ptm = Fit(PhotometricSet(std::move(grey), lights), Method::Parse("ptm"));
  return ptm.maps();
}

Image LoadExemplar(const std::string& name) {
  if (name == "ptm6") return SyntheticPtmMaps();
  Image image = ReadImage(ExemplarFolder() / (name + ".png")).image;  // alpha dropped
  return image;
}

SynthesisOptions OptionsFor(const Image& sample, const std::string& mode) {
  SynthesisOptions options;
  options.target = {kOutputSize, kOutputSize, false, 1};
  if (mode == "pixel") {
    options.method = SynthesisMethod::kPixel;
  } else if (mode == "variety") {
    options.quilt = VarietyQuiltOptions(sample.width(), sample.height());
  } else {
    options.quilt.search = ParseSearchMode(mode);
  }
  return options;
}

void BM_Synthesis(benchmark::State& state, const std::string& exemplar, const std::string& mode) {
  const Image sample = LoadExemplar(exemplar);
  const SynthesisOptions options = OptionsFor(sample, mode);
  SynthesisPlan plan;
  Image output;
  const double cpu_before = ProcessCpuSeconds();
  for (auto _ : state) {
    plan = PlanSynthesis(sample, options);
    output = plan.source_map.Apply(sample);
    benchmark::DoNotOptimize(output.values().data());
  }
  state.counters["process_cpu_ms"] =
      1000.0 * (ProcessCpuSeconds() - cpu_before) / static_cast<double>(state.iterations());
  const SynthesisQuality quality = MeasureSynthesis(sample, output, &plan.source_map);
  state.counters["channels"] = sample.channels();
  state.counters["sample_width"] = sample.width();
  state.counters["sample_height"] = sample.height();
  state.counters["nn_distance"] = quality.nearest_patch_distance;
  state.counters["seam_score"] = quality.seams ? quality.seams->ratio : 0.0;
  state.counters["roughness"] = quality.roughness.ratio;
  state.counters["coverage"] = quality.sample_coverage.value_or(0.0);
  if (plan.placement) {
    int searched = 0;
    for (const PlacedBlock& block : plan.placement->blocks) {
      searched += block.choice == PlacedBlock::Choice::kSearch;
    }
    state.counters["block"] = plan.placement->block_size;
    state.counters["blocks"] = static_cast<double>(plan.placement->blocks.size());
    state.counters["searched"] = searched;
  }
  if (const char* folder = std::getenv("PHOTOMAT_BENCH_OUT")) {
    if (sample.channels() <= 4) {
      ImageWriteOptions write;
      write.sample_type = SampleType::kUint8;
      write.encoding = ColourSpace::kSrgb;
      WriteImage(std::filesystem::path(folder) / (exemplar + "_" + mode + ".png"), output, write);
    }
  }
}

}  // namespace
}  // namespace photomat

int main(int argc, char** argv) {
  const std::vector<std::string> exemplars = {"input0", "input1", "input2",
                                              "input3", "input4", "ptm6"};
  for (const std::string& exemplar : exemplars) {
    for (const std::string mode : {"fast", "variety", "brute", "pixel"}) {
      auto* registered =
          benchmark::RegisterBenchmark(("BM_Synthesis/" + exemplar + "/" + mode).c_str(),
                                       [exemplar, mode](benchmark::State& state) {
                                         photomat::BM_Synthesis(state, exemplar, mode);
                                       });
      registered->Unit(benchmark::kMillisecond)->UseRealTime();
      registered->Iterations(mode == "fast" || mode == "variety" ? 5 : 1);
    }
  }
  benchmark::Initialize(&argc, argv);
  if (benchmark::ReportUnrecognizedArguments(argc, argv)) return 1;
  benchmark::RunSpecifiedBenchmarks();
  benchmark::Shutdown();
  return 0;
}
