#pragma once

#include <Eigen/Core>
#include <nlohmann/json.hpp>
#include <string>
#include <string_view>
#include <vector>

#include "represent/evaluation/evaluation.h"
#include "represent/evaluation/ranking.h"

namespace photomat {

// What ranks the methods in each predicted image (`evaluate --compare --rank-by`).
enum class RankingMeasure {
  // The prediction error e_k / sigma_k, lowest first: the thesis's. The PSNR would rank alike
  // (in one image both follow the RMS error), so it is not a measure of its own.
  kEta,
  kSsim,        // MethodEvaluation::ssim_prediction_per_image, highest first
  kDeltaE2000,  // MethodEvaluation::delta_e2000_prediction_per_image, lowest first
};
// "eta", "ssim" or "delta-e2000"; throws Error naming the accepted names for any other.
RankingMeasure ParseRankingMeasure(std::string_view name);
// The name ParseRankingMeasure reads.
std::string_view RankingMeasureName(RankingMeasure measure);
// What ranks first in an image ("the highest SSIM") and the name of the measure's mean column
// ("eta", "SSIM", "dE2000"), as the terminal's table says them or, with `html`, the report.
std::string_view RankingMeasureBest(RankingMeasure measure, bool html);
std::string_view RankingMeasureLabel(RankingMeasure measure, bool html);

// The ranking of methods over the predicted (held-out) images, as the thesis's psychophysical
// chapter ranks its conditions: blocks are the predicted images, treatments the methods, and in
// each image the method with the best value of the measure (by default the lowest prediction
// error e_k / sigma_k) ranks first. The Friedman test says whether the methods differ at all;
// the Nemenyi test which pairs do.
struct MethodComparison {
  RankingMeasure measure = RankingMeasure::kEta;
  std::vector<std::string> methods;  // in the order of the evaluations
  std::vector<int> images;           // the blocks: the predicted images, in prediction order
  std::vector<double> mean_values;   // per method: the measure's mean over `images`
  FriedmanTest friedman;             // mean ranks per method, chi-square, p, W, Iman-Davenport
  double alpha = 0.05;               // the level of the critical difference
  double critical_difference = 0.0;  // Nemenyi, in mean ranks, at `alpha`
  Eigen::MatrixXd pairwise_p;  // Nemenyi p-value of every pair of methods, ones on the diagonal

  // Method indices from the best mean rank to the worst (ties keep the evaluations' order).
  std::vector<int> RankOrder() const;
  // The JSON of `evaluate --json`'s "comparison" key: the measure (the name of its per-image
  // list in each method's JSON, and whether lower is better), the methods in rank order with mean
  // rank and the measure's mean (`mean_eta_prediction`, `mean_ssim_prediction` or
  // `mean_delta_e2000_prediction`), the Friedman and Nemenyi results and the pairwise p-values
  // keyed by method names (an infinite Iman-Davenport F, every image ranking alike, is written as
  // null).
  nlohmann::json ToJson() const;
};

// Compares `evaluations` over their predicted images by `measure`. Needs at least 2 methods, each
// evaluated with prediction over the same images (the same EvaluationOptions) and with the
// measure's value for each, and at least 2 images; throws Error saying which condition fails.
MethodComparison CompareMethods(const std::vector<MethodEvaluation>& evaluations,
                                RankingMeasure measure = RankingMeasure::kEta, double alpha = 0.05);

// A p-value as the table and the report print it: four decimals, or two significant digits below
// 1e-4 (e.g. 2.4e-06).
std::string FormatPValue(double p);

// The ranking as a text table for the terminal: one row per method in rank order, the Friedman
// line, the critical difference and the matrix of pairwise p-values.
std::string FormatComparisonTable(const MethodComparison& comparison);

}  // namespace photomat
