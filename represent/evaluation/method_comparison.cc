#include "represent/evaluation/method_comparison.h"

#include <fmt/format.h>

#include <algorithm>
#include <cmath>
#include <numeric>

#include "core/error.h"

namespace photomat {
namespace {

// JSON has no infinity: an unbounded statistic is written as null.
nlohmann::json FiniteOrNull(double value) {
  return std::isfinite(value) ? nlohmann::json(value) : nlohmann::json(nullptr);
}

}  // namespace

std::string FormatPValue(double p) {
  return p < 1e-4 ? fmt::format("{:.2g}", p) : fmt::format("{:.4f}", p);
}

std::vector<int> MethodComparison::RankOrder() const {
  std::vector<int> order(methods.size());
  std::iota(order.begin(), order.end(), 0);
  std::stable_sort(order.begin(), order.end(),
                   [&](int a, int b) { return friedman.mean_ranks[a] < friedman.mean_ranks[b]; });
  return order;
}

nlohmann::json MethodComparison::ToJson() const {
  nlohmann::json ranked = nlohmann::json::array();
  nlohmann::json pairwise = nlohmann::json::object();
  for (int m : RankOrder()) {
    ranked.push_back({{"method", methods[m]},
                      {"mean_rank", friedman.mean_ranks[m]},
                      {"mean_eta_prediction", mean_errors[m]}});
    nlohmann::json row = nlohmann::json::object();
    for (std::size_t other = 0; other < methods.size(); ++other) {
      if (static_cast<int>(other) != m) row[methods[other]] = pairwise_p(m, other);
    }
    pairwise[methods[m]] = row;
  }
  return {
      {"measure", "prediction_per_image"},
      {"lower_is_better", true},
      {"images", images},
      {"methods", ranked},
      {"friedman",
       {{"blocks", friedman.blocks},
        {"treatments", friedman.treatments},
        {"chi_square", friedman.chi_square},
        {"chi_square_without_tie_correction", friedman.chi_square_without_tie_correction},
        {"degrees_of_freedom", friedman.degrees_of_freedom},
        {"p_value", friedman.p_value},
        {"kendalls_w", friedman.kendalls_w},
        {"iman_davenport_f", FiniteOrNull(friedman.iman_davenport_f)},
        {"iman_davenport_p_value", friedman.iman_davenport_p_value}}},
      {"nemenyi",
       {{"alpha", alpha}, {"critical_difference", critical_difference}, {"p_values", pairwise}}}};
}

MethodComparison CompareMethods(const std::vector<MethodEvaluation>& evaluations, double alpha) {
  if (evaluations.size() < 2) {
    throw Error(
        fmt::format("ranking methods needs at least 2 methods, got {}", evaluations.size()));
  }
  const MethodEvaluation& first = evaluations.front();
  for (const MethodEvaluation& e : evaluations) {
    if (!e.eta_prediction || e.prediction_per_image.size() != e.prediction_images.size()) {
      throw Error(fmt::format(
          "ranking methods needs their prediction errors: {} was evaluated without prediction",
          e.method.Name()));
    }
    if (e.prediction_images != first.prediction_images) {
      throw Error(
          fmt::format("{} and {} predicted different images: they cannot be ranked image "
                      "by image",
                      first.method.Name(), e.method.Name()));
    }
  }
  const auto blocks = static_cast<Eigen::Index>(first.prediction_images.size());
  const auto treatments = static_cast<Eigen::Index>(evaluations.size());
  if (blocks < 2) {
    throw Error(fmt::format("ranking methods needs at least 2 predicted images, got {}", blocks));
  }
  MethodComparison comparison;
  comparison.images = first.prediction_images;
  comparison.alpha = alpha;
  Eigen::MatrixXd errors(blocks, treatments);
  for (Eigen::Index m = 0; m < treatments; ++m) {
    const MethodEvaluation& e = evaluations[m];
    comparison.methods.push_back(e.method.Name());
    for (Eigen::Index b = 0; b < blocks; ++b) {
      errors(b, m) = e.prediction_per_image[b];
      if (!std::isfinite(errors(b, m))) {
        throw Error(fmt::format("ranking methods: {}'s prediction error of image {} is {}",
                                e.method.Name(), comparison.images[b], errors(b, m)));
      }
    }
    comparison.mean_errors.push_back(errors.col(m).mean());
  }
  comparison.friedman = Friedman(errors);
  comparison.critical_difference =
      NemenyiCriticalDifference(static_cast<int>(treatments), static_cast<int>(blocks), alpha);
  comparison.pairwise_p = NemenyiPValues(comparison.friedman.mean_ranks, static_cast<int>(blocks));
  return comparison;
}

std::string FormatComparisonTable(const MethodComparison& c) {
  const FriedmanTest& f = c.friedman;
  std::size_t width = 6;
  for (const std::string& name : c.methods) width = std::max(width, name.size());
  std::string text = fmt::format(
      "Ranking over {} predicted images (in each image the lowest e_k/sigma_k ranks 1)\n"
      "{:>4}  {:<{}}  {:>9}  {:>12}\n",
      c.images.size(), "rank", "method", width, "mean rank", "mean eta");
  const std::vector<int> order = c.RankOrder();
  for (std::size_t r = 0; r < order.size(); ++r) {
    const int m = order[r];
    text += fmt::format("{:>4}  {:<{}}  {:>9.2f}  {:>12.5f}\n", r + 1, c.methods[m], width,
                        f.mean_ranks[m], c.mean_errors[m]);
  }
  text += fmt::format(
      "Friedman chi-square {:.2f} ({} df, tie-corrected), p = {}; Kendall's W {:.3f}; "
      "Iman-Davenport F {}, p = {}\n",
      f.chi_square, f.degrees_of_freedom, FormatPValue(f.p_value), f.kendalls_w,
      std::isfinite(f.iman_davenport_f) ? fmt::format("{:.2f}", f.iman_davenport_f) : "inf",
      FormatPValue(f.iman_davenport_p_value));
  text += fmt::format(
      "Nemenyi critical difference (alpha {}): {:.2f} mean ranks; pairwise p-values:\n{:<{}}",
      c.alpha, c.critical_difference, "", width);
  for (int m : order)
    text += fmt::format("  {:>{}}", c.methods[m], std::max<std::size_t>(width, 8));
  text += "\n";
  for (int i : order) {
    text += fmt::format("{:<{}}", c.methods[i], width);
    for (int j : order) {
      text += fmt::format("  {:>{}}", i == j ? "-" : FormatPValue(c.pairwise_p(i, j)),
                          std::max<std::size_t>(width, 8));
    }
    text += "\n";
  }
  return text;
}

}  // namespace photomat
