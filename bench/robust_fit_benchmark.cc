// Robust photometric stereo on one DiLiGenT object (default cat: 96 images, 612 x 512, 45 200
// object pixels; PHOTOMAT_BENCH_SET=DIR for another): least squares against the robust fit, and
// the robust per-pixel problem solved two ways, photomat's IRLS with Eigen 3x3 solves and Ceres
// Solver with a Cauchy loss (one reused problem per thread, the cheapest way to run Ceres on
// millions of tiny problems). Run through bench/robust_fit_table, which prints the issue 5 table.
#include <benchmark/benchmark.h>
#include <ceres/ceres.h>
#include <tbb/blocked_range.h>
#include <tbb/enumerable_thread_specific.h>
#include <tbb/parallel_for.h>

#include <algorithm>
#include <cmath>
#include <cstdlib>
#include <filesystem>
#include <numeric>
#include <optional>

#include "capture/io/load_photometric_set.h"
#include "core/image_io.h"
#include "represent/evaluation/evaluation.h"
#include "represent/fitting/fit.h"
#include "represent/fitting/robust_fit.h"

namespace photomat {
namespace {

std::filesystem::path CaptureFolder() {
  if (const char* set = std::getenv("PHOTOMAT_BENCH_SET")) return set;
  const char* data = std::getenv("PHOTOMAT_TEST_DATA");
  return std::filesystem::path(data ? data : "../shared/data") / "diligent" / "cat";
}

struct Capture {
  LoadedSet loaded;
  std::optional<Image> truth;
};

const Capture& LoadedCapture() {
  static const Capture capture = [] {
    Capture c{LoadPhotometricSet(CaptureFolder()), std::nullopt};
    if (c.loaded.ground_truth_normals) c.truth = ReadImage(*c.loaded.ground_truth_normals).image;
    return c;
  }();
  return capture;
}

void ReportError(benchmark::State& state, const Image& normals) {
  const Capture& capture = LoadedCapture();
  if (!capture.truth) return;
  state.counters["mean_error_deg"] =
      CompareNormals(normals, *capture.truth, capture.loaded.set.MaskOrAll()).mean_degrees;
}

void BM_Load(benchmark::State& state) {
  for (auto _ : state) {
    LoadedSet loaded = LoadPhotometricSet(CaptureFolder());
    benchmark::DoNotOptimize(loaded.set.image(0).values().data());
  }
}

void BM_LeastSquaresFit(benchmark::State& state) {
  const PhotometricSet& set = LoadedCapture().loaded.set;
  std::optional<Representation> fit;
  for (auto _ : state) fit.emplace(Fit(set, Method::Parse("gradient")));
  ReportError(state, *EstimateNormals(*fit));
}

void BM_RobustFitIrls(benchmark::State& state) {
  const PhotometricSet& set = LoadedCapture().loaded.set;
  std::optional<Representation> fit;
  for (auto _ : state) fit.emplace(FitRobust(set, Method::Parse("gradient")));
  ReportError(state, *EstimateNormals(*fit));
}

// The robust pixel problem for Ceres: the window's residuals y_i - b.l_i under a Cauchy loss;
// observations outside the window carry weight 0. One problem per thread is built once over all
// images, and each pixel only changes the data it points to.
struct LambertianResidual {
  LambertianResidual(const Eigen::Vector3d& light, const double* value, const double* weight)
      : l(light), y(value), w(weight) {}
  template <typename T>
  bool operator()(const T* b, T* residual) const {
    residual[0] = T(*w) * (T(*y) - (b[0] * T(l.x()) + b[1] * T(l.y()) + b[2] * T(l.z())));
    return true;
  }
  Eigen::Vector3d l;
  const double* y;
  const double* w;
};

class CeresPixelSolver {
 public:
  explicit CeresPixelSolver(const std::vector<LightDirection>& lights)
      : y_(lights.size()), w_(lights.size()) {
    ceres::Problem::Options problem_options;
    problem_options.loss_function_ownership = ceres::DO_NOT_TAKE_OWNERSHIP;
    problem_ = std::make_unique<ceres::Problem>(problem_options);
    for (std::size_t i = 0; i < lights.size(); ++i) {
      problem_->AddResidualBlock(new ceres::AutoDiffCostFunction<LambertianResidual, 1, 3>(
                                     new LambertianResidual(lights[i].vector(), &y_[i], &w_[i])),
                                 &loss_, b_);
    }
    options_.linear_solver_type = ceres::DENSE_QR;
    options_.max_num_iterations = 20;
    options_.num_threads = 1;
    options_.logging_type = ceres::SILENT;
  }

  // The same start and window as photomat's robust fit, then Ceres on the Cauchy loss.
  Eigen::Vector3d Solve(const std::vector<double>& y, const Eigen::Matrix3Xd& l) {
    const int n = static_cast<int>(y.size());
    std::vector<int> order(n);
    std::iota(order.begin(), order.end(), 0);
    std::sort(order.begin(), order.end(), [&](int a, int c) { return y[a] < y[c]; });
    const RobustFitOptions defaults;
    const int first = static_cast<int>(std::floor(defaults.dark_fraction * n));
    const int last = n - static_cast<int>(std::floor(defaults.bright_fraction * n));
    std::fill(w_.begin(), w_.end(), 0.0);
    for (int r = first; r < last; ++r) w_[order[r]] = 1.0;
    Eigen::Matrix3d a = Eigen::Matrix3d::Zero();
    Eigen::Vector3d rhs = Eigen::Vector3d::Zero();
    for (int i = 0; i < n; ++i) {
      if (w_[i] == 0.0) continue;
      a += l.col(i) * l.col(i).transpose();
      rhs += y[i] * l.col(i);
    }
    const Eigen::Vector3d start = a.ldlt().solve(rhs);
    std::vector<double> residuals;
    for (int i = 0; i < n; ++i) {
      y_[i] = y[i];
      if (w_[i] > 0.0 && start.dot(l.col(i)) < defaults.attached_shadow_cosine * start.norm()) {
        w_[i] = 0.0;
      }
      if (w_[i] > 0.0) residuals.push_back(std::abs(y[i] - start.dot(l.col(i))));
    }
    std::nth_element(residuals.begin(), residuals.begin() + residuals.size() / 2, residuals.end());
    const double sigma = std::max(1.4826 * residuals[residuals.size() / 2], 0.01 * start.norm());
    loss_.Reset(new ceres::CauchyLoss(DefaultLossScale(RobustLoss::kCauchy) * sigma),
                ceres::TAKE_OWNERSHIP);
    for (int k = 0; k < 3; ++k) b_[k] = start[k];
    ceres::Solver::Summary summary;
    ceres::Solve(options_, problem_.get(), &summary);
    return Eigen::Vector3d(b_[0], b_[1], b_[2]);
  }

 private:
  std::vector<double> y_, w_;
  double b_[3] = {0.0, 0.0, 1.0};
  ceres::LossFunctionWrapper loss_{new ceres::TrivialLoss, ceres::TAKE_OWNERSHIP};
  std::unique_ptr<ceres::Problem> problem_;
  ceres::Solver::Options options_;
};

Image CeresRobustNormals(const PhotometricSet& set) {
  const Observations observations(set);
  const Eigen::Index m = observations.pixels();
  const int n = set.size(), channels = set.channels();
  const Eigen::Matrix3Xd l = LightMatrix(set.lights());
  Image normals(set.width(), set.height(), 3);
  tbb::enumerable_thread_specific<CeresPixelSolver> solvers(
      [&] { return CeresPixelSolver(set.lights()); });
  tbb::parallel_for(tbb::blocked_range<Eigen::Index>(0, m, 256),
                    [&](const tbb::blocked_range<Eigen::Index>& range) {
                      CeresPixelSolver& solver = solvers.local();
                      std::vector<double> y(n);
                      for (Eigen::Index k = range.begin(); k < range.end(); ++k) {
                        for (int i = 0; i < n; ++i) {
                          double sum = 0.0;
                          for (int c = 0; c < channels; ++c) {
                            sum += observations.matrix()(c * m + k, i);
                          }
                          y[i] = sum;
                        }
                        const Eigen::Vector3d b = solver.Solve(y, l).normalized();
                        const auto pixel = normals.pixel(observations.pixel_indices()[k]);
                        for (int c = 0; c < 3; ++c) pixel[c] = static_cast<float>(b[c]);
                      }
                    });
  return normals;
}

void BM_RobustFitCeres(benchmark::State& state) {
  const PhotometricSet& set = LoadedCapture().loaded.set;
  std::optional<Image> normals;
  for (auto _ : state) normals.emplace(CeresRobustNormals(set));
  ReportError(state, *normals);
}

void BM_LoadAndRobustFit(benchmark::State& state) {
  for (auto _ : state) {
    const LoadedSet loaded = LoadPhotometricSet(CaptureFolder());
    const Representation fit = FitRobust(loaded.set, Method::Parse("gradient"));
    benchmark::DoNotOptimize(fit.maps().values().data());
  }
}

BENCHMARK(BM_Load)->Unit(benchmark::kMillisecond)->UseRealTime()->Iterations(3);
BENCHMARK(BM_LeastSquaresFit)->Unit(benchmark::kMillisecond)->UseRealTime()->Iterations(3);
BENCHMARK(BM_RobustFitIrls)->Unit(benchmark::kMillisecond)->UseRealTime()->Iterations(3);
BENCHMARK(BM_RobustFitCeres)->Unit(benchmark::kMillisecond)->UseRealTime()->Iterations(3);
BENCHMARK(BM_LoadAndRobustFit)->Unit(benchmark::kMillisecond)->UseRealTime()->Iterations(3);

}  // namespace
}  // namespace photomat

BENCHMARK_MAIN();
