// Turk's reaction-diffusion model on the Stanford bunny (34,834 used vertices, 69,451 triangles)
// from the homogeneous state to a settled pattern. Run through bench/rd_table, which prints the
// table issue 9 asks for (target: under 60 s on the 2-core reference machine).
#include <benchmark/benchmark.h>
#include <sys/resource.h>

#include <cstdlib>
#include <filesystem>

#include "synthesize/mesh/mesh.h"
#include "synthesize/mesh/mesh_io.h"
#include "synthesize/surface/reaction_diffusion.h"

namespace photomat {
namespace {

std::filesystem::path BunnyFile() {
  if (const char* mesh = std::getenv("PHOTOMAT_BENCH_MESH")) return mesh;
  const char* data = std::getenv("PHOTOMAT_TEST_DATA");
  return std::filesystem::path(data ? data : "../shared/data") / "meshes" / "stanford-bunny.obj";
}

double ProcessCpuSeconds() {
  rusage usage{};
  getrusage(RUSAGE_SELF, &usage);
  auto seconds = [](const timeval& t) { return t.tv_sec + t.tv_usec * 1e-6; };
  return seconds(usage.ru_utime) + seconds(usage.ru_stime);
}

// The command line's defaults (jacobi case; gauss_seidel: --gauss-seidel --tau 1.2): bounding-box
// diagonal 100 (mean edge 0.59, a ninth of the wavelength 4.97 at s = 0.05), tau = 0.025 / s,
// settled when the RMS rate of change falls below 1e-3 after the pattern has grown.
void BM_TurkBunny(benchmark::State& state, SpeciesOrdering ordering) {
  TriangleMesh mesh = ReadMesh(BunnyFile());
  NormalizeMesh(mesh, MeshNormalization::kBoundingBox, 100.0);
  const FemDomain domain = FemDomain::FromMesh(mesh);
  SimulationResult result;
  const double cpu_start = ProcessCpuSeconds();
  for (auto _ : state) {
    auto model = MakeTurkModel({});
    SimulationOptions options;
    // Jacobi at the model's step (tau s = 0.025); Gauss-Seidel at tau s = 0.06.
    options.ordering = ordering;
    options.time_step =
        ordering == SpeciesOrdering::kJacobi ? model->suggested_time_step() : 0.06 / 0.05;
    options.max_steps = 10000;
    options.settle_rate = 1e-3;
    options.min_steps = 100;
    result = SimulateReactionDiffusion(*model, domain, options);
    benchmark::DoNotOptimize(result.fields[1].data());
  }
  state.counters["vertices"] = mesh.vertex_count();
  state.counters["steps"] = result.steps;
  state.counters["settled"] = result.settled ? 1 : 0;
  state.counters["cg_iterations"] = static_cast<double>(result.total_iterations);
  state.counters["cpu_seconds"] = ProcessCpuSeconds() - cpu_start;
  state.counters["contrast"] = result.fields[1].maxCoeff() - result.fields[1].minCoeff();
}

BENCHMARK_CAPTURE(BM_TurkBunny, jacobi, SpeciesOrdering::kJacobi)
    ->Unit(benchmark::kSecond)
    ->UseRealTime()
    ->Iterations(1);
BENCHMARK_CAPTURE(BM_TurkBunny, gauss_seidel, SpeciesOrdering::kGaussSeidel)
    ->Unit(benchmark::kSecond)
    ->UseRealTime()
    ->Iterations(1);

}  // namespace
}  // namespace photomat

BENCHMARK_MAIN();
