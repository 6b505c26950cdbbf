#include "represent/fitting/pbr_fit.h"

#include <ceres/ceres.h>
#include <ceres/iteration_callback.h>
#include <ceres/sphere_manifold.h>
#include <fmt/format.h>
#include <tbb/blocked_range.h>
#include <tbb/enumerable_thread_specific.h>
#include <tbb/parallel_for.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <limits>
#include <numeric>
#include <span>
#include <vector>

#include "core/error.h"
#include "core/microfacet_brdf.h"
#include "represent/fitting/pbr_fit_summary.h"
#include "represent/fitting/pbr_pixel_cost.h"
#include "represent/model/shading.h"

namespace photomat {
namespace {

constexpr Eigen::Index kPixelGrain = 64;

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

// The start's grid (IMPLEMENTER CHOICE): perceptual roughness from the floor to 1 and F0 from 0
// (no specular) to 1, spaced more finely where GGX's lobe and Schlick's Fresnel change fastest.
constexpr std::array<double, 11> kGridRoughness = {0.0, 0.08, 0.12, 0.17, 0.23, 0.3,
                                                   0.4, 0.5,  0.62, 0.8,  1.0};
constexpr std::array<double, 10> kGridF0 = {0.0, 0.01, 0.02, 0.04, 0.07, 0.12, 0.2, 0.35, 0.6, 1.0};

// The start of one pixel's solve: at the fixed `p.normal`, every (roughness, F0) of the grid with
// the base colour that best fits it (least squares per channel, linear in the base colour: the
// data minus the specular, over the diffuse factor; clamped at 0); keeps the pair whose residuals
// cost least under the fit's Cauchy loss. So the solver starts in the basin of the right lobe and
// at the bound when the data want one (a diffuse pixel: F0 0), instead of walking there from a
// fixed guess, which took most pixels of DiLiGenT cat past 100 iterations.
void GridStart(const PbrPixelData& data, const PbrFitOptions& options, double loss_scale,
               PixelParameters& p) {
  const std::size_t n = data.lights.size();
  // Per light, n.l and the specular at F0 = 1 (pi D V n.l: the roughness's alone); Schlick's F is
  // linear in F0, so each F0 of the grid costs only a multiply-add per light.
  std::vector<double> n_dot_l(n), unit_specular(n), diffuse(n), specular(n);
  const double squared_scale = loss_scale * loss_scale;
  double best = std::numeric_limits<double>::infinity();
  PixelParameters chosen = p;
  for (double grid_roughness : kGridRoughness) {
    const double roughness = std::max(grid_roughness, options.min_roughness);
    const MicrofacetSurface surface(p.normal.data(), roughness, 1.0);
    for (std::size_t i = 0; i < n; ++i) {
      const MicrofacetDerivatives r = MicrofacetRadianceDerivatives(surface, data.lights[i], false);
      const double* l = data.lights[i].direction;
      const double cosine = p.normal[0] * l[0] + p.normal[1] * l[1] + p.normal[2] * l[2];
      n_dot_l[i] = cosine > 0.0 && p.normal[2] > 0.0 ? cosine : 0.0;  // as MicrofacetRadiance
      unit_specular[i] = r.value.specular;
    }
    for (double f0 : kGridF0) {
      for (std::size_t i = 0; i < n; ++i) {
        const double fresnel = f0 + (1.0 - f0) * data.lights[i].schlick;
        diffuse[i] = (1.0 - fresnel) * n_dot_l[i] * data.irradiance[i];
        specular[i] = fresnel * unit_specular[i] * data.irradiance[i];
      }
      PixelParameters candidate = p;
      candidate.roughness = roughness;
      candidate.f0 = f0;
      double dd = 0.0;
      for (std::size_t i = 0; i < n; ++i) dd += diffuse[i] * diffuse[i];
      for (int c = 0; c < 3; ++c) {
        double dy = 0.0;
        for (std::size_t i = 0; i < n; ++i) dy += diffuse[i] * (data.observed[i][c] - specular[i]);
        candidate.base[c] = dd > 0.0 ? std::max(0.0, dy / dd) : 0.0;
      }
      double cost = 0.0;
      for (std::size_t i = 0; i < n; ++i) {
        double squared = 0.0;
        for (int c = 0; c < 3; ++c) {
          const double residual =
              diffuse[i] * candidate.base[c] + specular[i] - data.observed[i][c];
          squared += residual * residual;
        }
        cost += squared_scale * std::log1p(squared / squared_scale);  // Cauchy's rho
      }
      if (cost < best) {
        best = cost;
        chosen = candidate;
      }
    }
  }
  p = chosen;
}

// One bounded scalar of a pixel's parameters and whether the solve holds it on its bound.
struct BoundedScalar {
  double* value;
  double lower, upper;
  bool pinned = false;
  int steps_on_bound = 0;  // successful steps in a row that ended on a bound

  bool OnBound() const { return *value <= lower || *value >= upper; }
};

// A step that would leave the box is projected back onto it (Ceres' bounds), so a parameter the
// data push past its bound sits there while the Gauss-Newton step, computed as if it were free,
// keeps pointing out: every projected step then falls short of its model's prediction, the trust
// region shrinks and the solver crawls (on DiLiGenT cat most pixels took 100 iterations this way,
// a base channel at 0, F0 at 0 or roughness at a bound). This callback ends a solve once a free
// scalar has ended kStepsToPin successful steps in a row on its bound, so that SolvePixel holds it
// there and solves on without it.
class PinOnBound : public ceres::IterationCallback {
 public:
  static constexpr int kStepsToPin = 3;

  explicit PinOnBound(std::span<BoundedScalar> scalars) : scalars_(scalars) {}

  ceres::CallbackReturnType operator()(const ceres::IterationSummary& summary) override {
    if (!summary.step_is_successful) return ceres::SOLVER_CONTINUE;
    bool pin = false;
    for (BoundedScalar& scalar : scalars_) {
      if (scalar.pinned) continue;
      scalar.steps_on_bound = scalar.OnBound() ? scalar.steps_on_bound + 1 : 0;
      pin |= scalar.steps_on_bound >= kStepsToPin;
    }
    return pin ? ceres::SOLVER_TERMINATE_SUCCESSFULLY : ceres::SOLVER_CONTINUE;
  }

 private:
  std::span<BoundedScalar> scalars_;
};

// Solves one pixel from `p` (the start); `prior_weight` > 0 adds the regularisation. Returns the
// final cost. An active-set scheme over Ceres' bounded trust-region solve: a scalar that settles
// on its bound is held there (PinOnBound) and the rest solved on; once nothing more settles, a
// held scalar whose gradient points back into the box (the data now pull it inside) is freed and
// the solve goes on, at most max_iterations steps in all.
double SolvePixel(const PbrPixelData& data, const PbrFitOptions& options, double brightness,
                  double prior_weight, PixelParameters& p) {
  ceres::Problem problem;
  const double scale = options.loss_scale * brightness;
  problem.AddResidualBlock(new PbrPixelCost(data, scale * scale), nullptr, &p.base[0], &p.base[1],
                           &p.base[2], &p.roughness, &p.f0, p.normal.data());
  if (prior_weight > 0.0) {
    problem.AddResidualBlock(
        new ceres::AutoDiffCostFunction<PriorResidual, 2, 1, 1>(
            new PriorResidual{prior_weight, options.prior_roughness, options.prior_f0}),
        nullptr, &p.roughness, &p.f0);
  }
  problem.SetManifold(p.normal.data(), new ceres::SphereManifold<3>());
  constexpr double kUnbounded = std::numeric_limits<double>::max();
  std::array<BoundedScalar, 5> scalars = {{{&p.base[0], 0.0, kUnbounded},
                                           {&p.base[1], 0.0, kUnbounded},
                                           {&p.base[2], 0.0, kUnbounded},
                                           {&p.roughness, options.min_roughness, 1.0},
                                           {&p.f0, 0.0, 1.0}}};
  for (const BoundedScalar& scalar : scalars) {
    problem.SetParameterLowerBound(scalar.value, 0, scalar.lower);
    if (scalar.upper < kUnbounded) problem.SetParameterUpperBound(scalar.value, 0, scalar.upper);
  }

  PinOnBound pin_on_bound(scalars);
  ceres::Solver::Options solver;
  solver.linear_solver_type = ceres::DENSE_NORMAL_CHOLESKY;  // 8 unknowns: the normal equations
  solver.num_threads = 1;
  solver.logging_type = ceres::SILENT;
  // IMPLEMENTER CHOICE: Ceres' default relative cost decrease (1e-6) ends a solve. Past it the
  // steps crawl along directions the data barely constrain (on DiLiGenT cat, 1e-8 instead took
  // 47 % more steps for 0.2 % less cost, moving roughness by 0.011 and F0 by 0.022 on average).
  solver.function_tolerance = 1e-6;
  solver.gradient_tolerance = 1e-14;
  solver.parameter_tolerance = 1e-12;
  solver.update_state_every_iteration = true;  // PinOnBound reads the parameters
  solver.callbacks.push_back(&pin_on_bound);
  // The gradient by the bounded scalars, for freeing held ones (below).
  ceres::Problem::EvaluateOptions evaluate;
  for (const BoundedScalar& scalar : scalars) evaluate.parameter_blocks.push_back(scalar.value);
  int steps_left = options.max_iterations;
  double cost = 0.0;
  while (steps_left > 0) {
    for (BoundedScalar& scalar : scalars) {
      if (scalar.pinned) {
        problem.SetParameterBlockConstant(scalar.value);
      } else {
        problem.SetParameterBlockVariable(scalar.value);
      }
    }
    solver.max_num_iterations = steps_left;
    ceres::Solver::Summary summary;
    ceres::Solve(solver, &problem, &summary);
    cost = summary.final_cost;
    const int steps = std::max(1, static_cast<int>(summary.iterations.size()) - 1);
    steps_left -= steps;
    bool changed = false;
    for (BoundedScalar& scalar : scalars) {
      if (!scalar.pinned && scalar.steps_on_bound >= PinOnBound::kStepsToPin) {
        scalar.pinned = changed = true;
      }
    }
    if (changed) continue;
    // Nothing settled: free the held scalars the data pull back inside (the gradient of the
    // cost, with every scalar variable, points out of the box at them).
    for (BoundedScalar& scalar : scalars) problem.SetParameterBlockVariable(scalar.value);
    std::vector<double> gradient;
    problem.Evaluate(evaluate, nullptr, nullptr, &gradient, nullptr);
    for (std::size_t i = 0; i < scalars.size(); ++i) {
      BoundedScalar& scalar = scalars[i];
      if (!scalar.pinned) continue;
      const bool inward = *scalar.value <= scalar.lower ? gradient[i] < 0.0 : gradient[i] > 0.0;
      if (inward) {
        scalar.pinned = false;
        scalar.steps_on_bound = 0;
        changed = true;
      }
    }
    if (!changed) break;
  }
  return cost;
}

void CheckPbrInputs(const Observations& observations, const std::vector<LightDirection>& lights,
                    const NearLighting* near_lighting, const PbrFitOptions& options,
                    const std::filesystem::path& source) {
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
  if (near_lighting && near_lighting->lamps.size() != lights.size()) {
    throw Error(source, fmt::format("{} near lamps for {} lights", near_lighting->lamps.size(),
                                    lights.size()));
  }
}

// What the pixels' fits share: the observations, which of them count, and the lights.
struct PbrFitInputs {
  const Observations& observations;
  std::span<const int> selected;
  std::span<const Mask> measured;
  const NearLighting* near_lighting;
  std::vector<MicrofacetLight> light_terms;  // distant: once per image, not per pixel
};

// Pixel k's measured samples: each selected image's RGB under its light (as the pixel sees a
// near lamp: its own direction and relative irradiance).
void GatherPixelData(const PbrFitInputs& in, Eigen::Index k, PbrPixelData& data) {
  const Observations& observations = in.observations;
  const Eigen::Index m = observations.pixels();
  const Eigen::MatrixXf& matrix = observations.matrix();
  const std::size_t pixel = observations.pixel_indices()[k];
  const auto width = static_cast<std::size_t>(observations.width());
  data.lights.clear();
  data.irradiance.clear();
  data.observed.clear();
  const int column = static_cast<int>(pixel % width);
  const int row = static_cast<int>(pixel / width);
  for (int image : in.selected) {
    if (!in.measured.empty() && !in.measured[image][pixel]) continue;
    if (in.near_lighting) {
      const LampAtPixel lamp = in.near_lighting->At(image, column, row);
      data.lights.emplace_back(lamp.direction.data());
      data.irradiance.push_back(lamp.irradiance);
    } else {
      data.lights.push_back(in.light_terms[image]);
      data.irradiance.push_back(1.0);
    }
    data.observed.push_back({matrix(k, image), matrix(m + k, image), matrix(2 * m + k, image)});
  }
}

// The start of pixel k's fit from the Lambertian start (normals and albedo) and the options;
// `brightness` is the start's mean base colour (the scale of the loss and the prior).
PixelParameters StartOfPixel(const Eigen::Matrix3Xf& start_normals,
                             const Eigen::MatrixXf& start_albedo, Eigen::Index k,
                             const PbrFitOptions& options, double& brightness) {
  PixelParameters start;
  const double keep = 1.0 - options.start_f0;  // the diffuse share at normal incidence
  brightness = 0.0;
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
  return start;
}

// One pixel's fit from `start`: solved when it has 3 samples or more; a pixel whose fitted lobe
// no light samples is solved again with the roughness prior (when it has a weight). Counted in
// `tally`; its final cost in `cost`.
PixelParameters FitPbrPixel(const PbrPixelData& data, PixelParameters start,
                            const PbrFitOptions& options, double brightness, PbrFitSummary& tally,
                            double& cost) {
  const bool enough = data.lights.size() >= 3;
  if (options.grid_start && enough) {
    GridStart(data, options, options.loss_scale * brightness, start);
  }
  PixelParameters fitted = start;
  cost = 0.0;
  if (enough) cost = SolvePixel(data, options, brightness, 0.0, fitted);
  const Eigen::Vector3d normal(fitted.normal[0], fitted.normal[1], fitted.normal[2]);
  const bool sampled = std::any_of(data.lights.begin(), data.lights.end(), [&](auto& l) {
    return InSpecularLobe(normal, Eigen::Vector3d(l.direction), fitted.roughness);
  });
  if (sampled) {
    ++tally.lobe_sampled;
  } else {
    ++tally.lobe_unsampled;
    if (options.prior_weight > 0.0 && enough) {
      fitted = start;
      const double weight =
          options.prior_weight * brightness * std::sqrt(static_cast<double>(data.lights.size()));
      cost = SolvePixel(data, options, brightness, weight, fitted);
      ++tally.regularised;
    }
  }
  return fitted;
}

void StorePixel(PixelValues<float> out, const PixelParameters& fitted) {
  for (int c = 0; c < 3; ++c) {
    out[MicrofacetShading::kBase + c] = static_cast<float>(fitted.base[c]);
    out[MicrofacetShading::kNormal + c] = static_cast<float>(fitted.normal[c]);
  }
  out[MicrofacetShading::kRoughness] = static_cast<float>(fitted.roughness);
  out[MicrofacetShading::kF0] = static_cast<float>(fitted.f0);
}

}  // namespace

Representation FitPbr(const Observations& observations, const std::vector<LightDirection>& lights,
                      const NearLighting* near_lighting, std::span<const int> selected,
                      const Eigen::Matrix3Xf& start_normals, const Eigen::MatrixXf& start_albedo,
                      std::span<const Mask> measured, const PbrFitOptions& options,
                      nlohmann::json details, const std::filesystem::path& source,
                      Progress* progress) {
  CheckPbrInputs(observations, lights, near_lighting, options, source);
  const Eigen::Index m = observations.pixels();
  const auto shading = std::make_shared<MicrofacetShading>();
  Image maps(observations.width(), observations.height(), shading->MapNames());
  PbrFitInputs inputs{observations, selected, measured, near_lighting, {}};
  for (const LightDirection& light : lights) {
    const Eigen::Vector3d l = light.vector();
    inputs.light_terms.emplace_back(l.data());
  }
  tbb::enumerable_thread_specific<PbrFitSummary> tallies;
  // Each pixel's final cost, summed in pixel order after the loop: a sum in the threads' tallies
  // would depend on how the scheduler split the pixels, and the summary would differ from run to
  // run in its last digits.
  std::vector<double> costs(static_cast<std::size_t>(m));
  NullProgress no_progress;
  Progress& bar = OrNull(progress, no_progress);
  bar.Start("pbr fit", static_cast<std::size_t>((m + kPixelGrain - 1) / kPixelGrain));
  const auto fit_range = [&](const tbb::blocked_range<Eigen::Index>& range) {
    PbrFitSummary& tally = tallies.local();
    PbrPixelData data;
    for (Eigen::Index k = range.begin(); k < range.end(); ++k) {
      GatherPixelData(inputs, k, data);
      double brightness = 0.0;
      const PixelParameters start =
          StartOfPixel(start_normals, start_albedo, k, options, brightness);
      StorePixel(
          maps.pixel(observations.pixel_indices()[k]),
          FitPbrPixel(data, start, options, brightness, tally, costs[static_cast<std::size_t>(k)]));
    }
    bar.Advance();
  };
  tbb::parallel_for(tbb::blocked_range<Eigen::Index>(0, m, kPixelGrain), fit_range);
  bar.Finish();
  PbrFitSummary total;
  for (const PbrFitSummary& t : tallies) total.Add(t);
  total.total_cost = std::accumulate(costs.begin(), costs.end(), 0.0);
  total.pixels = static_cast<std::size_t>(m);  // pixels with fewer than 3 samples too
  if (!details.is_object()) details = nlohmann::json::object();
  details["pbr"] = options.ToJson();
  details["pbr_summary"] = total.ToJson();
  details["pbr_light_model"] = near_lighting ? "near" : "distant";
  return Representation("pbr", std::move(maps), shading, std::move(details));
}

}  // namespace photomat
