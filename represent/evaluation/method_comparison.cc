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

struct MeasureTraits {
  std::string_view name;        // as --rank-by reads it
  std::string_view json;        // the per-image list's key in a method's JSON
  std::string_view label;       // for the tables: "mean {label}"
  std::string_view best;        // what ranks first in an image
  std::string_view best_html;   // the same in the report
  std::string_view label_html;  // the report's "mean {label_html}"
  bool lower_is_better = true;
};

MeasureTraits Traits(RankingMeasure measure) {
  switch (measure) {
    case RankingMeasure::kSsim:
      return {"ssim",
              "ssim_prediction",
              "SSIM",
              "the highest SSIM",
              "the highest SSIM",
              "SSIM prediction",
              false};
    case RankingMeasure::kDeltaE2000:
      return {"delta-e2000",
              "delta_e2000_prediction",
              "dE2000",
              "the lowest mean Delta E 2000",
              "the lowest mean &#916;E 2000",
              "&#916;E 2000 prediction",
              true};
    case RankingMeasure::kEta:
      break;
  }
  return {"eta",
          "eta_prediction",
          "eta",
          "the lowest e_k/sigma_k",
          "the lowest prediction error e<sub>k</sub>/&#963;<sub>k</sub>",
          "eta prediction",
          true};
}

// The per-image values of `measure` in `e`, in the order of its prediction_images; empty when it
// was not measured.
const std::vector<double>& PerImage(const MethodEvaluation& e, RankingMeasure measure) {
  switch (measure) {
    case RankingMeasure::kSsim:
      return e.ssim_prediction_per_image;
    case RankingMeasure::kDeltaE2000:
      return e.delta_e2000_prediction_per_image;
    case RankingMeasure::kEta:
      break;
  }
  return e.prediction_per_image;
}

}  // namespace

RankingMeasure ParseRankingMeasure(std::string_view name) {
  for (RankingMeasure measure :
       {RankingMeasure::kEta, RankingMeasure::kSsim, RankingMeasure::kDeltaE2000}) {
    if (Traits(measure).name == name) return measure;
  }
  throw Error(fmt::format("unknown ranking measure '{}': expected eta, ssim or delta-e2000", name));
}

std::string_view RankingMeasureName(RankingMeasure measure) { return Traits(measure).name; }

std::string_view RankingMeasureBest(RankingMeasure measure, bool html) {
  return html ? Traits(measure).best_html : Traits(measure).best;
}

std::string_view RankingMeasureLabel(RankingMeasure measure, bool html) {
  return html ? Traits(measure).label_html : Traits(measure).label;
}

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
  const MeasureTraits traits = Traits(measure);
  for (int m : RankOrder()) {
    ranked.push_back({{"method", methods[m]},
                      {"mean_rank", friedman.mean_ranks[m]},
                      {fmt::format("mean_{}", traits.json), mean_values[m]}});
    nlohmann::json row = nlohmann::json::object();
    for (std::size_t other = 0; other < methods.size(); ++other) {
      if (static_cast<int>(other) != m) row[methods[other]] = pairwise_p(m, other);
    }
    pairwise[methods[m]] = row;
  }
  return {
      {"measure", fmt::format("{}_per_image", traits.json)},
      {"lower_is_better", traits.lower_is_better},
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

MethodComparison CompareMethods(const std::vector<MethodEvaluation>& evaluations,
                                RankingMeasure measure, double alpha) {
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
    if (PerImage(e, measure).size() != e.prediction_images.size()) {
      throw Error(fmt::format(
          "ranking methods by {} needs its value for every predicted image: {} has none (the "
          "streamed evaluation measures eta and PSNR only; the colour difference needs one or "
          "three channels)",
          Traits(measure).name, e.method.Name()));
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
  comparison.measure = measure;
  comparison.images = first.prediction_images;
  // Friedman ranks the lowest first: a measure where higher is better is ranked negated.
  const double sign = Traits(measure).lower_is_better ? 1.0 : -1.0;
  comparison.alpha = alpha;
  Eigen::MatrixXd values(blocks, treatments);
  for (Eigen::Index m = 0; m < treatments; ++m) {
    const MethodEvaluation& e = evaluations[m];
    comparison.methods.push_back(e.method.Name());
    for (Eigen::Index b = 0; b < blocks; ++b) {
      values(b, m) = PerImage(e, measure)[b];
      if (!std::isfinite(values(b, m))) {
        throw Error(fmt::format(
            "ranking methods: {}'s {} of image {} is {}", e.method.Name(),
            measure == RankingMeasure::kEta ? "prediction error" : Traits(measure).label,
            comparison.images[b], values(b, m)));
      }
    }
    comparison.mean_values.push_back(values.col(m).mean());
  }
  comparison.friedman = Friedman(sign * values);
  comparison.critical_difference =
      NemenyiCriticalDifference(static_cast<int>(treatments), static_cast<int>(blocks), alpha);
  comparison.pairwise_p = NemenyiPValues(comparison.friedman.mean_ranks, static_cast<int>(blocks));
  return comparison;
}

std::string FormatComparisonTable(const MethodComparison& c) {
  const FriedmanTest& f = c.friedman;
  std::size_t width = 6;
  for (const std::string& name : c.methods) width = std::max(width, name.size());
  const MeasureTraits traits = Traits(c.measure);
  std::string text = fmt::format(
      "Ranking over {} predicted images (in each image {} ranks 1)\n"
      "{:>4}  {:<{}}  {:>9}  {:>12}\n",
      c.images.size(), traits.best, "rank", "method", width, "mean rank",
      fmt::format("mean {}", traits.label));
  const std::vector<int> order = c.RankOrder();
  for (std::size_t r = 0; r < order.size(); ++r) {
    const int m = order[r];
    text += fmt::format("{:>4}  {:<{}}  {:>9.2f}  {:>12.5f}\n", r + 1, c.methods[m], width,
                        f.mean_ranks[m], c.mean_values[m]);
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
