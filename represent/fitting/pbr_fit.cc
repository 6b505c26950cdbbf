#include "represent/fitting/pbr_fit.h"

#include <ceres/ceres.h>
#include <ceres/sphere_manifold.h>
#include <fmt/format.h>
#include <tbb/blocked_range.h>
#include <tbb/enumerable_thread_specific.h>
#include <tbb/parallel_for.h>

#include <algorithm>
#include <array>
#include <cmath>

#include "core/error.h"
#include "core/microfacet_brdf.h"
#include "represent/model/shading.h"

namespace photomat {
namespace {

constexpr Eigen::Index kPixelGrain = 64;

// One observation (pixel, image): the model's three channels minus the measured ones.
struct ObservationResidual {
  std::array<double, 3> light;
  std::array<double, 3> observed;

  template <typename T>
  bool operator()(const T* base, const T* roughness, const T* f0, const T* normal,
                  T* residual) const {
    const MicrofacetResponse<T> r = MicrofacetRadiance(normal, light.data(), roughness[0], f0[0]);
    for (int c = 0; c < 3; ++c) residual[c] = r.diffuse * base[c] + r.specular - T(observed[c]);
    return true;
  }
};

// The regularisation of a pixel whose lights miss its lobe: roughness and F0 towards the prior.
struct PriorResidual {
  double weight, roughness_prior, f0_prior;

  template <typename T>
  bool operator()(const T* roughness, const T* f0, T* residual) const {
    residual[0] = T(weight) * (roughness[0] - T(roughness_prior));
    residual[1] = T(weight) * (f0[0] - T(f0_prior));
    return true;
  }
};

// The parameters of one pixel, in the shading's map order.
struct PixelParameters {
  std::array<double, 3> base{};
  double roughness = 0.5;
  double f0 = 0.04;
  std::array<double, 3> normal{0.0, 0.0, 1.0};
};

struct PixelData {
  std::vector<std::array<double, 3>> lights;
  std::vector<std::array<double, 3>> observed;
};

// Solves one pixel from `start`; `prior_weight` > 0 adds the regularisation. Returns the final
// cost.
double SolvePixel(const PixelData& data, const PbrFitOptions& options, double brightness,
                  double prior_weight, PixelParameters& p) {
  ceres::CauchyLoss loss(options.loss_scale * brightness);  // outlives the problem
  ceres::Problem::Options problem_options;
  problem_options.loss_function_ownership = ceres::DO_NOT_TAKE_OWNERSHIP;
  ceres::Problem problem(problem_options);
  for (std::size_t i = 0; i < data.lights.size(); ++i) {
    problem.AddResidualBlock(new ceres::AutoDiffCostFunction<ObservationResidual, 3, 3, 1, 1, 3>(
                                 new ObservationResidual{data.lights[i], data.observed[i]}),
                             &loss, p.base.data(), &p.roughness, &p.f0, p.normal.data());
  }
  if (prior_weight > 0.0) {
    problem.AddResidualBlock(
        new ceres::AutoDiffCostFunction<PriorResidual, 2, 1, 1>(
            new PriorResidual{prior_weight, options.prior_roughness, options.prior_f0}),
        nullptr, &p.roughness, &p.f0);
  }
  problem.SetManifold(p.normal.data(), new ceres::SphereManifold<3>());
  for (int c = 0; c < 3; ++c) problem.SetParameterLowerBound(p.base.data(), c, 0.0);
  problem.SetParameterLowerBound(&p.roughness, 0, options.min_roughness);
  problem.SetParameterUpperBound(&p.roughness, 0, 1.0);
  problem.SetParameterLowerBound(&p.f0, 0, 0.0);
  problem.SetParameterUpperBound(&p.f0, 0, 1.0);

  ceres::Solver::Options solver;
  solver.linear_solver_type = ceres::DENSE_QR;
  solver.max_num_iterations = options.max_iterations;
  solver.num_threads = 1;
  solver.logging_type = ceres::SILENT;
  solver.function_tolerance = 1e-12;
  solver.gradient_tolerance = 1e-14;
  solver.parameter_tolerance = 1e-12;
  ceres::Solver::Summary summary;
  ceres::Solve(solver, &problem, &summary);
  return summary.final_cost;
}

}  // namespace

Representation FitPbr(const Observations& observations, const std::vector<LightDirection>& lights,
                      std::span<const int> selected, const Eigen::Matrix3Xf& start_normals,
                      const Eigen::MatrixXf& start_albedo, std::span<const Mask> measured,
                      const PbrFitOptions& options, nlohmann::json details,
                      const std::filesystem::path& source, Progress* progress) {
  if (observations.channels() != 3) {
    throw Error(source, fmt::format("pbr fits RGB images; these have {} channel(s)",
                                    observations.channels()));
  }
  if (!(options.min_roughness > 0.0 && options.min_roughness <= options.start_roughness &&
        options.start_roughness <= 1.0 && options.start_f0 >= 0.0 && options.start_f0 <= 1.0 &&
        options.loss_scale > 0.0 && options.prior_weight >= 0.0)) {
    throw Error(source,
                "pbr options: need 0 < min roughness <= start roughness <= 1, 0 <= start F0 <= 1, "
                "a positive loss scale and a prior weight >= 0");
  }
  const Eigen::Index m = observations.pixels();
  const Eigen::MatrixXf& matrix = observations.matrix();
  const auto shading = std::make_shared<MicrofacetShading>();
  Image maps(observations.width(), observations.height(), shading->MapNames());
  struct Tally {
    std::size_t sampled = 0, unsampled = 0, regularised = 0;
    double cost = 0.0;
  };
  tbb::enumerable_thread_specific<Tally> tallies;
  NullProgress no_progress;
  Progress& bar = OrNull(progress, no_progress);
  bar.Start("pbr fit", static_cast<std::size_t>((m + kPixelGrain - 1) / kPixelGrain));
  tbb::parallel_for(tbb::blocked_range<Eigen::Index>(0, m, kPixelGrain), [&](const tbb::
                                                                                 blocked_range<
                                                                                     Eigen::Index>&
                                                                                     range) {
    Tally& tally = tallies.local();
    PixelData data;
    for (Eigen::Index k = range.begin(); k < range.end(); ++k) {
      const std::size_t pixel = observations.pixel_indices()[k];
      data.lights.clear();
      data.observed.clear();
      for (int image : selected) {
        if (!measured.empty() && !measured[image][pixel]) continue;
        const Eigen::Vector3d l = lights[image].vector();
        data.lights.push_back({l.x(), l.y(), l.z()});
        data.observed.push_back({matrix(k, image), matrix(m + k, image), matrix(2 * m + k, image)});
      }
      PixelParameters start;
      const double keep = 1.0 - options.start_f0;  // the diffuse share at normal incidence
      double brightness = 0.0;
      for (int c = 0; c < 3; ++c) {
        start.base[c] = std::max(0.0, static_cast<double>(start_albedo(c, k))) / keep;
        brightness += start.base[c] / 3.0;
      }
      brightness = std::max(brightness, 1e-4);
      Eigen::Vector3d n = start_normals.col(k).cast<double>();
      if (!(n.z() > 0.05)) n = Eigen::Vector3d::UnitZ();  // the view must see the surface
      start.normal = {n.x(), n.y(), n.z()};
      start.roughness = options.start_roughness;
      start.f0 = options.start_f0;
      PixelParameters fitted = start;
      double cost = 0.0;
      if (data.lights.size() >= 3) cost = SolvePixel(data, options, brightness, 0.0, fitted);
      const Eigen::Vector3d normal(fitted.normal[0], fitted.normal[1], fitted.normal[2]);
      const bool sampled = std::any_of(data.lights.begin(), data.lights.end(), [&](auto& l) {
        return InSpecularLobe(normal, Eigen::Vector3d(l[0], l[1], l[2]), fitted.roughness);
      });
      if (sampled) {
        ++tally.sampled;
      } else {
        ++tally.unsampled;
        if (options.prior_weight > 0.0 && data.lights.size() >= 3) {
          fitted = start;
          const double weight = options.prior_weight * brightness *
                                std::sqrt(static_cast<double>(data.lights.size()));
          cost = SolvePixel(data, options, brightness, weight, fitted);
          ++tally.regularised;
        }
      }
      tally.cost += cost;
      const auto out = maps.pixel(pixel);
      for (int c = 0; c < 3; ++c)
        out[MicrofacetShading::kBase + c] = static_cast<float>(fitted.base[c]);
      out[MicrofacetShading::kRoughness] = static_cast<float>(fitted.roughness);
      out[MicrofacetShading::kF0] = static_cast<float>(fitted.f0);
      for (int c = 0; c < 3; ++c)
        out[MicrofacetShading::kNormal + c] = static_cast<float>(fitted.normal[c]);
    }
    bar.Advance();
  });
  bar.Finish();
  Tally total;
  for (const Tally& t : tallies) {
    total.sampled += t.sampled;
    total.unsampled += t.unsampled;
    total.regularised += t.regularised;
    total.cost += t.cost;
  }
  if (!details.is_object()) details = nlohmann::json::object();
  details["pbr"] = options.ToJson();
  details["pbr_summary"] = {{"pixels", m},
                            {"lobe_sampled", total.sampled},
                            {"lobe_unsampled", total.unsampled},
                            {"regularised", total.regularised},
                            {"mean_final_cost", total.cost / std::max<double>(1.0, m)}};
  return Representation("pbr", std::move(maps), shading, std::move(details));
}

}  // namespace photomat
