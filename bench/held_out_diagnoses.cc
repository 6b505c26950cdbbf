#include "bench/held_out_diagnoses.h"

#include <fmt/format.h>

#include <Eigen/Eigenvalues>
#include <algorithm>
#include <cmath>
#include <functional>
#include <limits>
#include <string>
#include <vector>

#include "core/error.h"
#include "represent/evaluation/evaluation.h"
#include "represent/model/light_interpolation.h"
#include "represent/model/light_profile_basis.h"

namespace photomat {
namespace {

// The mean held-out PSNR, clamped to [0, peak] as MaskedPsnr, of predicting the held-out lights
// by `weights` (held x training) from the training images compressed to `planes` PCA axes of the
// training lights (a pass over the pixels).
double ClampedHeldOutPsnr(const Observations& observations, const HoldOut& hold_out,
                          const Eigen::MatrixXd& weights, int planes, double peak) {
  const Eigen::MatrixXd& gram = observations.Gram();
  const Eigen::MatrixXf& matrix = observations.matrix();
  const Eigen::SelfAdjointEigenSolver<Eigen::MatrixXd> solver(
      gram(hold_out.selected, hold_out.selected));
  const Eigen::MatrixXd axes = solver.eigenvectors().rightCols(planes);
  const Eigen::MatrixXf combination =
      (axes * (axes.transpose() * weights.transpose())).cast<float>();
  const Eigen::MatrixXf predicted =
      (matrix(Eigen::all, hold_out.selected) * combination).cwiseMax(0.0f).cwiseMin(float(peak));
  double total = 0.0;
  for (std::size_t h = 0; h < hold_out.held_out.size(); ++h) {
    const double error =
        (predicted.col(h) - matrix.col(hold_out.held_out[h]).cwiseMax(0.0f).cwiseMin(float(peak)))
            .cast<double>()
            .squaredNorm();
    total += PsnrDecibels(peak, error / static_cast<double>(matrix.rows()));
  }
  return total / static_cast<double>(hold_out.held_out.size());
}

std::string SchemeName(LeaveOut scheme) {
  return scheme == LeaveOut::kEdge    ? "leave-edge-out"
         : scheme == LeaveOut::kSide  ? "leave-side-out"
         : scheme == LeaveOut::kBlock ? "leave-block-out"
                                      : "leave-one-out";
}

}  // namespace

std::vector<LightDirection> LightsOf(const std::vector<LightDirection>& lights,
                                     const std::vector<int>& indices) {
  std::vector<LightDirection> selected;
  for (int i : indices) selected.push_back(lights[static_cast<std::size_t>(i)]);
  return selected;
}

Eigen::MatrixXd RbfWeights(const std::vector<LightDirection>& nodes,
                           const std::vector<LightDirection>& targets, double width_degrees,
                           double regularisation, RbfTail tail) {
  const RbfInterpolation rbf(nodes, width_degrees, regularisation, tail);
  Eigen::MatrixXd weights(static_cast<Eigen::Index>(targets.size()),
                          static_cast<Eigen::Index>(nodes.size()));
  for (std::size_t h = 0; h < targets.size(); ++h) {
    weights.row(static_cast<Eigen::Index>(h)) = rbf.Weights(targets[h]).transpose();
  }
  return weights;
}

Eigen::MatrixXd BilinearWeights(const std::vector<LightDirection>& nodes,
                                const std::vector<LightDirection>& targets, int grid_size,
                                double smoothness) {
  const Eigen::MatrixXd resampling = BilinearResampling(nodes, grid_size, smoothness);
  Eigen::MatrixXd weights = Eigen::MatrixXd::Zero(static_cast<Eigen::Index>(targets.size()),
                                                  static_cast<Eigen::Index>(nodes.size()));
  for (std::size_t h = 0; h < targets.size(); ++h) {
    const LightDirection& l = targets[h];
    for (const auto& [node, w] : BilinearLightBasis::GridWeights(grid_size, l.x(), l.y())) {
      weights.row(static_cast<Eigen::Index>(h)) += w * resampling.row(node);
    }
  }
  return weights;
}

Eigen::MatrixXd PolyharmonicWeights(const std::vector<LightDirection>& nodes,
                                    const std::vector<LightDirection>& targets, int order,
                                    double regularisation) {
  const auto kernel = [order](const LightDirection& a, const LightDirection& b) {
    const double r = (a.vector() - b.vector()).norm();
    if (r <= 0.0) return 0.0;
    return order == 1 ? r : (order == 2 ? r * r * std::log(r) : r * r * r);
  };
  const auto tail = [](const LightDirection& l) {
    return Eigen::Vector4d(1.0, l.x(), l.y(), l.z());
  };
  const auto n = static_cast<Eigen::Index>(nodes.size());
  Eigen::MatrixXd system = Eigen::MatrixXd::Zero(n + 4, n + 4);
  for (Eigen::Index i = 0; i < n; ++i) {
    for (Eigen::Index j = 0; j < n; ++j) system(i, j) = kernel(nodes[i], nodes[j]);
    system(i, i) += regularisation;
    system.block(i, n, 1, 4) = tail(nodes[i]).transpose();
    system.block(n, i, 4, 1) = tail(nodes[i]);
  }
  const Eigen::MatrixXd solve = system.fullPivLu().inverse().topRows(n);
  Eigen::MatrixXd weights(static_cast<Eigen::Index>(targets.size()), n);
  for (std::size_t h = 0; h < targets.size(); ++h) {
    Eigen::VectorXd features(n + 4);
    for (Eigen::Index i = 0; i < n; ++i) features[i] = kernel(targets[h], nodes[i]);
    features.tail(4) = tail(targets[h]);
    weights.row(static_cast<Eigen::Index>(h)) = (solve * features).transpose();
  }
  return weights;
}

void PrintClampedScores(const Observations& observations, const std::vector<LightDirection>& lights,
                        const HoldOut& hold_out, double peak) {
  const std::vector<LightDirection> training = LightsOf(lights, hold_out.selected);
  const double spacing = MedianNearestNeighbourDegrees(training);
  // The mean PSNR of lights `held` predicted from lights `others` (indices into the set).
  struct Split {
    std::vector<int> held, others;
  };
  const auto mean_psnr = [&](const Split& split, double width, double regularisation, int planes) {
    return ClampedHeldOutPsnr(observations, HoldOut{"", split.held, split.others},
                              RbfWeights(LightsOf(lights, split.others),
                                         LightsOf(lights, split.held), width, regularisation),
                              planes, peak);
  };
  std::vector<Split> folds(LeaveOutFolds::kBlockStride);
  for (std::size_t t = 0; t < hold_out.selected.size(); ++t) {
    for (std::size_t f = 0; f < folds.size(); ++f) {
      (t % folds.size() == f ? folds[f].held : folds[f].others).push_back(hold_out.selected[t]);
    }
  }
  // Edge folds: each training light on the boundary of the training lights' hull in (lx, ly)
  // (HullBoundaryLights) left out alone: extrapolation, as the held-out row.
  std::vector<Split> edge_folds;
  for (int t : HullBoundaryLights(training)) {
    Split fold;
    fold.held.push_back(hold_out.selected[t]);
    for (int i : hold_out.selected) {
      if (i != fold.held.front()) fold.others.push_back(i);
    }
    edge_folds.push_back(std::move(fold));
  }
  fmt::print("{} edge folds\n", edge_folds.size());
  // Side folds: each side of that hull (HullSideLights) left out at once.
  std::vector<Split> side_folds;
  std::size_t side_lights = 0;
  for (const std::vector<int>& side : HullSideLights(training)) {
    Split fold;
    for (int t : side) fold.held.push_back(hold_out.selected[t]);
    for (std::size_t t = 0; t < training.size(); ++t) {
      if (!std::binary_search(side.begin(), side.end(), static_cast<int>(t))) {
        fold.others.push_back(hold_out.selected[t]);
      }
    }
    side_lights += fold.held.size();
    side_folds.push_back(std::move(fold));
  }
  double best_edge = -1e300, best_edge_test = 0.0, best_side = -1e300, best_side_test = 0.0;
  std::string best_edge_label, best_side_label;
  const Split test{hold_out.held_out, hold_out.selected};
  double best_score = -1e300, best_test = 0.0;
  std::string best_label;
  for (double factor : {0.7071, 1.0, 1.4142, 2.0, 2.8284}) {
    for (double regularisation : {0.0, 1e-3, 1e-2, 1e-1, 1.0}) {
      for (int planes : {4, 6, 9, 16}) {
        try {
          double score = 0.0;
          for (const Split& fold : folds) {
            score += mean_psnr(fold, factor * spacing, regularisation, planes);
          }
          score /= static_cast<double>(folds.size());
          double edge_score = 0.0;
          for (const Split& fold : edge_folds) {
            edge_score += mean_psnr(fold, factor * spacing, regularisation, planes);
          }
          edge_score /= static_cast<double>(std::max<std::size_t>(1, edge_folds.size()));
          // The mean over every left-out light of the sides, as the fit's score.
          double side_score = 0.0;
          for (const Split& fold : side_folds) {
            side_score += static_cast<double>(fold.held.size()) *
                          mean_psnr(fold, factor * spacing, regularisation, planes);
          }
          side_score /= static_cast<double>(std::max<std::size_t>(1, side_lights));
          if (side_score > best_side) {
            best_side = side_score;
            best_side_label = fmt::format("rbf {:.3g} deg / {:g}, {} planes", factor * spacing,
                                          regularisation, planes);
            best_side_test = mean_psnr(test, factor * spacing, regularisation, planes);
          }
          const double held = mean_psnr(test, factor * spacing, regularisation, planes);
          const std::string label = fmt::format("rbf {:.3g} deg / {:g}, {} planes",
                                                factor * spacing, regularisation, planes);
          fmt::print(
              "clamped leave-block-out {}: score {:.2f}, edge score {:.2f}, side score {:.2f}, "
              "held out {:.2f}\n",
              label, score, edge_score, side_score, held);
          if (edge_score > best_edge) {
            best_edge = edge_score;
            best_edge_test = held;
            best_edge_label = label;
          }
          if (score > best_score) {
            best_score = score;
            best_test = held;
            best_label = label;
          }
        } catch (const Error&) {
        }
      }
    }
  }
  fmt::print("chosen by the clamped leave-block-out score: {} (score {:.2f}): held out {:.2f}\n",
             best_label, best_score, best_test);
  fmt::print("chosen by the clamped edge score: {} (score {:.2f}): held out {:.2f}\n",
             best_edge_label, best_edge, best_edge_test);
  fmt::print("chosen by the clamped side score: {} (score {:.2f}): held out {:.2f}\n",
             best_side_label, best_side, best_side_test);
}

void PrintBlend(const Observations& observations, const std::vector<LightDirection>& lights,
                const HoldOut& hold_out, double peak, const LightProfileOptions& profile) {
  const Eigen::MatrixXd& gram = observations.Gram();
  const std::vector<LightDirection> training = LightsOf(lights, hold_out.selected);
  const Eigen::MatrixXd training_gram = gram(hold_out.selected, hold_out.selected);
  const double spacing = MedianNearestNeighbourDegrees(training);
  // Planes: the option's count, or (--planes -1) the best score's among 1..16.
  std::vector<int> plane_candidates = {profile.planes > 0 ? profile.planes
                                                          : LightProfileOptions::kDefaultPlanes};
  if (profile.planes == LightProfileOptions::kChoosePlanes) {
    plane_candidates.clear();
    for (int k = 1; k <= LightProfileOptions::kMaxChosenPlanes; ++k) plane_candidates.push_back(k);
  }
  const int grid = profile.grid_size;
  // The rbf and bilinear parts among the fit's candidates (kRbfWidthFactors, ...), a among these.
  const std::vector<double> alphas = {0.0, 0.25, 0.5, 0.75, 1.0};
  const std::vector<LightDirection> held = LightsOf(lights, hold_out.held_out);
  const auto held_rbf = [&](double width, double regularisation) {
    return RbfWeights(training, held, width, regularisation);
  };
  const auto held_bilinear = [&](double smoothness) {
    return BilinearWeights(training, held, grid, smoothness);
  };
  for (LeaveOut scheme : {LeaveOut::kOne, LeaveOut::kEdge, LeaveOut::kBlock, LeaveOut::kSide}) {
    const LeaveOutFolds folds(training_gram, scheme, training);
    struct Part {
      double width = 0.0, regularisation = 0.0, smoothness = 0.0;
      std::vector<Eigen::MatrixXd> weights;
    };
    std::vector<Part> rbfs, bilinears;
    for (double factor : kRbfWidthFactors) {
      for (double regularisation : kRbfRegularisations) {
        auto weights =
            RbfFoldWeights(folds, training, factor * spacing, regularisation, RbfTail::kAffine);
        if (!weights.empty()) {
          rbfs.push_back({factor * spacing, regularisation, 0.0, std::move(weights)});
        }
      }
    }
    for (double smoothness : kBilinearSmoothnesses) {
      auto weights = BilinearFoldWeights(folds, training, grid, smoothness);
      if (!weights.empty()) bilinears.push_back({0.0, 0.0, smoothness, std::move(weights)});
    }
    struct Choice {
      double score = -1e300;
      const Part* rbf = nullptr;
      const Part* bilinear = nullptr;
      double alpha = 0.0;
      int planes = 0;
    };
    std::vector<Choice> by_alpha(alphas.size());
    for (std::size_t a = 0; a < alphas.size(); ++a) {
      const double alpha = alphas[a];
      // A pure part does not depend on the other's settings: score it once.
      for (const Part& rbf : rbfs) {
        if (alpha == 0.0 && &rbf != &rbfs.front()) break;
        for (const Part& bilinear : bilinears) {
          if (alpha == 1.0 && &bilinear != &bilinears.front()) break;
          std::vector<Eigen::MatrixXd> blend;
          for (std::size_t f = 0; f < folds.folds().size(); ++f) {
            blend.push_back(alpha * rbf.weights[f] + (1.0 - alpha) * bilinear.weights[f]);
          }
          const Eigen::VectorXd scores = folds.Score(blend).mean_snr_db;
          for (int planes : plane_candidates) {
            const double score = scores[planes - 1];
            if (score > by_alpha[a].score) by_alpha[a] = {score, &rbf, &bilinear, alpha, planes};
          }
        }
      }
    }
    Choice joint;
    for (const Choice& choice : by_alpha) {
      if (choice.score > joint.score) joint = choice;
    }
    const auto held_psnr = [&](const Choice& c, double alpha) {
      return ClampedHeldOutPsnr(observations, hold_out,
                                alpha * held_rbf(c.rbf->width, c.rbf->regularisation) +
                                    (1.0 - alpha) * held_bilinear(c.bilinear->smoothness),
                                c.planes, peak);
    };
    for (const Choice& c : by_alpha) {
      fmt::print(
          "blend {} a={:.2f}: rbf {:.3g} deg / {:g}, bilinear {:g}, {} planes: score {:.3f}, "
          "held out {:.2f}\n",
          SchemeName(scheme), c.alpha, c.rbf->width, c.rbf->regularisation, c.bilinear->smoothness,
          c.planes, c.score, held_psnr(c, c.alpha));
    }
    fmt::print("blend {} chosen: a={:.2f}, {} planes (score {:.3f}): held out {:.2f}\n",
               SchemeName(scheme), joint.alpha, joint.planes, joint.score,
               held_psnr(joint, joint.alpha));
    double oracle = -1e300, oracle_alpha = 0.0;
    for (double alpha = 0.0; alpha <= 1.0001; alpha += 0.125) {
      const double value = held_psnr(joint, alpha);
      if (value > oracle) oracle = value, oracle_alpha = alpha;
    }
    fmt::print("ORACLE (held-out lights, not a choice) {} parts: best a={:.3f}: {:.2f}\n",
               SchemeName(scheme), oracle_alpha, oracle);
  }
}

void PrintPolyharmonic(const Observations& observations, const std::vector<LightDirection>& lights,
                       const HoldOut& hold_out, double peak) {
  const std::vector<LightDirection> training = LightsOf(lights, hold_out.selected);
  const std::vector<LightDirection> held = LightsOf(lights, hold_out.held_out);
  // The polyharmonic splines get the rbf fit's regularisations.
  const auto& regularisations = kRbfRegularisations;
  for (int order : {1, 2, 3}) {
    for (double regularisation : regularisations) {
      const Eigen::MatrixXd w = PolyharmonicWeights(training, held, order, regularisation);
      fmt::print(
          "polyharmonic order {} regularisation {}: k=4 {:.2f}, k=6 {:.2f}, k=9 {:.2f}, "
          "k=16 {:.2f}\n",
          order, regularisation, ClampedHeldOutPsnr(observations, hold_out, w, 4, peak),
          ClampedHeldOutPsnr(observations, hold_out, w, 6, peak),
          ClampedHeldOutPsnr(observations, hold_out, w, 9, peak),
          ClampedHeldOutPsnr(observations, hold_out, w, 16, peak));
    }
  }
  const Eigen::MatrixXd gram = observations.Gram()(hold_out.selected, hold_out.selected);
  const double spacing = MedianNearestNeighbourDegrees(training);
  for (LeaveOut scheme : {LeaveOut::kOne, LeaveOut::kBlock, LeaveOut::kEdge, LeaveOut::kSide}) {
    const LeaveOutFolds folds(gram, scheme, training);
    struct Choice {
      std::string label;
      double score = -std::numeric_limits<double>::infinity();
      int planes = 0;
      Eigen::MatrixXd weights;
    };
    Choice cubic, any;
    const auto consider = [&](Choice& best, const std::string& label,
                              const LeaveOutFolds::Scores& scores,
                              const std::function<Eigen::MatrixXd()>& held_weights) {
      for (int k = 1; k <= std::min<int>(16, scores.mean_snr_db.size()); ++k) {
        if (scores.mean_snr_db[k - 1] > best.score) {
          best = {label, scores.mean_snr_db[k - 1], k, held_weights()};
        }
      }
    };
    for (double regularisation : regularisations) {
      std::vector<Eigen::MatrixXd> fold_weights;
      for (const LeaveOutFolds::Fold& fold : folds.folds()) {
        std::vector<LightDirection> nodes, targets;
        for (int i : fold.others) nodes.push_back(training[i]);
        for (int i : fold.held_out) targets.push_back(training[i]);
        fold_weights.push_back(PolyharmonicWeights(nodes, targets, 3, regularisation));
      }
      const auto held_weights = [&] {
        return PolyharmonicWeights(training, held, 3, regularisation);
      };
      consider(cubic, fmt::format("cubic {}", regularisation), folds.Score(fold_weights),
               held_weights);
      if (scheme != LeaveOut::kSide) continue;
      for (std::size_t f = 0; f < folds.folds().size(); ++f) {
        const LeaveOutFolds::Fold& fold = folds.folds()[f];
        double decibels = 0.0;
        Eigen::Vector2d centre = Eigen::Vector2d::Zero();
        for (std::size_t h = 0; h < fold.held_out.size(); ++h) {
          const int light = fold.held_out[h];
          const Eigen::Vector4d a =
              fold.axes.leftCols(4).transpose() * fold_weights[f].row(h).transpose();
          double error = gram(light, light);
          for (int j = 0; j < 4; ++j) {
            error += fold.eigenvalues[j] * a[j] * a[j] - 2.0 * a[j] * fold.cross(j, h);
          }
          decibels += 10.0 * std::log10(gram(light, light) / error);
          centre += Eigen::Vector2d(training[light].x(), training[light].y());
        }
        const double count = static_cast<double>(fold.held_out.size());
        fmt::print(
            "  side {} ({} lights around lx {:.2f}, ly {:.2f}): cubic {} 4 planes {:.3f} dB\n", f,
            fold.held_out.size(), centre.x() / count, centre.y() / count, regularisation,
            decibels / count);
      }
    }
    any = cubic;
    for (double factor : kRbfWidthFactors) {
      for (double regularisation : regularisations) {
        const double width = factor * spacing;
        const auto fold_weights =
            RbfFoldWeights(folds, training, width, regularisation, RbfTail::kAffine);
        if (fold_weights.empty()) continue;
        consider(any, fmt::format("gaussian {:.3g} deg / {}", width, regularisation),
                 folds.Score(fold_weights),
                 [&] { return RbfWeights(training, held, width, regularisation); });
      }
    }
    for (const Choice* choice : {&cubic, &any}) {
      fmt::print("{} picks {} with {} planes (score {:.3f} dB): held-out {:.2f}\n",
                 SchemeName(scheme), choice->label, choice->planes, choice->score,
                 ClampedHeldOutPsnr(observations, hold_out, choice->weights, choice->planes, peak));
    }
  }
}

void PrintOracle(const Observations& observations, const std::vector<LightDirection>& lights,
                 const HoldOut& hold_out, double peak, int grid_size) {
  const Eigen::MatrixXd& gram = observations.Gram();
  const Eigen::SelfAdjointEigenSolver<Eigen::MatrixXd> solver(
      gram(hold_out.selected, hold_out.selected));
  const Eigen::MatrixXd axes = solver.eigenvectors().rowwise().reverse();
  const Eigen::VectorXd eigenvalues = solver.eigenvalues().reverse();
  const Eigen::MatrixXd cross = axes.transpose() * gram(hold_out.selected, hold_out.held_out);
  const double count = static_cast<double>(observations.matrix().rows());
  const std::vector<LightDirection> training = LightsOf(lights, hold_out.selected);
  const std::vector<LightDirection> held = LightsOf(lights, hold_out.held_out);
  // Mean PSNR per plane count 1..16 and uncompressed (last) of weights (held x training).
  const auto psnr = [&](const Eigen::MatrixXd& weights) {
    std::vector<double> mean(17, 0.0);
    for (Eigen::Index h = 0; h < weights.rows(); ++h) {
      const Eigen::VectorXd a = axes.transpose() * weights.row(h).transpose();
      double error = gram(hold_out.held_out[h], hold_out.held_out[h]);
      for (Eigen::Index j = 0; j < a.size(); ++j) {
        error += eigenvalues[j] * a[j] * a[j] - 2.0 * a[j] * cross(j, h);
        const Eigen::Index entry = j < 16 ? j : (j == a.size() - 1 ? 16 : -1);
        if (entry >= 0) mean[entry] += 10.0 * std::log10(peak * peak * count / error);
      }
    }
    for (double& m : mean) m /= static_cast<double>(weights.rows());
    return mean;
  };
  const auto print = [](const std::string& label, const std::vector<double>& mean) {
    const auto best = std::max_element(mean.begin(), mean.end() - 1);
    fmt::print(
        "oracle {}: k=4 {:.2f}, k=6 {:.2f}, k=9 {:.2f}, k=16 {:.2f}, all {:.2f}, best k={} "
        "{:.2f}\n",
        label, mean[3], mean[5], mean[8], mean[15], mean[16], best - mean.begin() + 1, *best);
  };
  for (RbfTail tail : {RbfTail::kAffine, RbfTail::kQuadratic}) {
    for (double width : {4.4, 6.2, 8.8, 12.4, 17.5, 24.8}) {
      for (double regularisation : {0.0, 1e-3, 1e-2, 1e-1, 1.0}) {
        try {
          print(fmt::format("rbf {} width {} reg {}", ToString(tail), width, regularisation),
                psnr(RbfWeights(training, held, width, regularisation, tail)));
        } catch (const Error&) {
        }
      }
    }
  }
  const auto rbf_weights = [&](double width, double regularisation, RbfTail tail) {
    return RbfWeights(training, held, width, regularisation, tail);
  };
  const auto bilinear_weights = [&](double smoothness) {
    return BilinearWeights(training, held, grid_size, smoothness);
  };
  for (double alpha : {0.25, 0.5, 0.75}) {
    print(fmt::format("mix {} rbf 12.4/0.01 + bilinear 1e-4", alpha),
          psnr(alpha * rbf_weights(12.4, 0.01, RbfTail::kAffine) +
               (1 - alpha) * bilinear_weights(1e-4)));
    print(fmt::format("mix {} rbf 8.8/0.01 + bilinear 1e-4", alpha),
          psnr(alpha * rbf_weights(8.8, 0.01, RbfTail::kAffine) +
               (1 - alpha) * bilinear_weights(1e-4)));
    print(fmt::format("mix {} rbf 8.8/0.01 + rbf 17.5/0.01", alpha),
          psnr(alpha * rbf_weights(8.8, 0.01, RbfTail::kAffine) +
               (1 - alpha) * rbf_weights(17.5, 0.01, RbfTail::kAffine)));
  }
  // The candidates the training lights choose (planes 9 and chosen), for comparison.
  const Eigen::MatrixXd training_gram = gram(hold_out.selected, hold_out.selected);
  for (LeaveOut scheme : {LeaveOut::kOne, LeaveOut::kBlock}) {
    for (int planes : {LightProfileOptions::kDefaultPlanes, LightProfileOptions::kChoosePlanes}) {
      LightProfileOptions options;
      options.leave_out = scheme;
      options.planes = planes;
      options.grid_size = grid_size;
      const RbfParameters rbf = ChooseRbfParameters(training, training_gram, options);
      const BilinearParameters bilinear =
          ChooseBilinearParameters(training, training_gram, options);
      const auto mean_rbf = psnr(rbf_weights(rbf.width_degrees, rbf.regularisation, rbf.tail));
      const auto mean_bilinear = psnr(bilinear_weights(bilinear.smoothness));
      fmt::print(
          "chosen by {} (planes {}): rbf {:.3g} deg / {:.3g}, {} planes: {:.2f}; bilinear {:.3g}, "
          "{} planes: {:.2f}\n",
          scheme == LeaveOut::kBlock ? "leave-block-out" : "leave-one-out", planes,
          rbf.width_degrees, rbf.regularisation, rbf.planes, mean_rbf[std::min(rbf.planes, 16) - 1],
          bilinear.smoothness, bilinear.planes, mean_bilinear[std::min(bilinear.planes, 16) - 1]);
    }
  }
  for (double smoothness : {1e-4, 1e-3, 1e-2, 1e-1, 1.0}) {
    print(fmt::format("bilinear smoothness {}", smoothness),
          psnr(BilinearWeights(training, held, grid_size, smoothness)));
  }
}

}  // namespace photomat
