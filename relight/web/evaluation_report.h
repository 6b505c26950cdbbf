#pragma once

#include <cstddef>
#include <filesystem>
#include <optional>
#include <span>
#include <string>
#include <vector>

#include "capture/io/streamed_set.h"
#include "core/image.h"
#include "core/light_direction.h"
#include "core/photometric_set.h"
#include "core/progress.h"
#include "represent/evaluation/evaluation.h"
#include "represent/evaluation/method_comparison.h"
#include "represent/fitting/robust_fit.h"

namespace photomat {

// The evaluation report of `photomat evaluate --report DIR` and the demo: a folder with
// index.html (no scripts, no network access: opens from the file system), SVG charts inline and
// PNG images beside it, and report.json ("format": "photomat-report", the evaluation as
// `evaluate --json` writes it). It shows
//  - the eta table: reconstruction and prediction per method, normal errors where truth exists;
//  - a chart of eta per method, and one chart per method of its per-image errors
//    (<svg class="method-chart" data-method="NAME">);
//  - where ground truth normals exist, a heat map of each method's angular error, on one colour
//    scale for all methods (up to the 95th percentile of all errors, rounded up to 5 degrees);
//  - for chosen captured images, the photograph beside each method's relighting of its light
//    (the fit of all images) and, when prediction was evaluated, its prediction (a fit without
//    that image, or with held-out images the one fit without them). Dark images are brightened
//    for display by the same factor in a row (stated);
//  - with a comparison (evaluate --compare), the ranking of the methods over the predicted images:
//    the table of mean ranks, the Friedman test, the Nemenyi p-values of every pair and the
//    critical-difference diagram (<section id="ranking">).
// Pictures are shown at most kReportDisplaySide pixels on their longer side (report_pictures.h:
// a larger capture reduced by a whole factor, stated on the page and as report.json's
// "display_factor"); the heat scale and the brightening come from the pictures as shown.

struct EvaluationReportOptions {
  std::string title = "photomat evaluation";
  // Captured images to show beside their relighting (indices into the set); empty: up to three
  // spread-out lights (ChooseReportImages).
  std::vector<int> images;
  // The fits the evaluation used: set when it evaluated robust fits (EvaluationOptions::robust), so
  // that the relit images and normal maps are those of the same fits.
  std::optional<RobustFitOptions> robust;
  // pbr's fit, when the evaluation fitted it with options of its own (`evaluate` fits pbr robustly
  // with its --pbr-* options, with or without --robust); unset: as `robust` says (without it,
  // FitObservations' default robust start).
  std::optional<RobustFitOptions> pbr_robust;
  // The ranking of the methods (CompareMethods of the same evaluations), shown when set.
  std::optional<MethodComparison> comparison;
  Progress* progress = nullptr;
};

// Writes the report into `folder`, whole or not at all (an existing folder is replaced only if it
// is empty or a previous report). `evaluations` are EvaluateMethod's results on `set`; `truth` the
// ground-truth normals or null. Throws Error naming the folder, or for image indices out of range.
void WriteEvaluationReport(const std::filesystem::path& folder, const PhotometricSet& set,
                           const std::vector<MethodEvaluation>& evaluations, const Image* truth,
                           const EvaluationReportOptions& options = {});

// The same report from a set and its fits read band by band (`evaluate --stream --report`, README
// "Streamed relighting and export"), for sets too large to hold: `stacks[m]` is the fit of every
// image for evaluations[m] (a map stack, as the evaluation made it: least squares, or robust with
// options.robust, pbr with options.pbr_robust), the photographs are read from `set` in bands, the
// shown images' predictions are fitted band by band (VisitFoldFits, their folds only: a fold per
// shown image for leave-one-out, the one held-out fit otherwise) and `truth` (ground-truth normals)
// is read in bands. The pictures are gathered at display size as they stream (report_pictures.h),
// so memory follows the band. The same page and pictures as WriteEvaluationReport, to the fits'
// float rounding (a displayed code may step by one). Throws Error naming the stack or truth whose
// size differs from the set's, and as WriteEvaluationReport.
struct StreamedReportOptions {
  // Bytes the bands may hold; 0: DefaultBandBudget(kMinimumReportMemory).
  std::size_t memory_bytes = 0;
  // > 0: exactly this many rows per band (tests).
  int band_rows = 0;
};
inline constexpr std::size_t kMinimumReportMemory = std::size_t{16} << 20;
void WriteEvaluationReportStreamed(const std::filesystem::path& folder, StreamedSet& set,
                                   std::span<const std::filesystem::path> stacks,
                                   const std::vector<MethodEvaluation>& evaluations,
                                   const std::optional<std::filesystem::path>& truth,
                                   const EvaluationReportOptions& options = {},
                                   const StreamedReportOptions& bands = {});

// `count` images whose lights are far apart (farthest-point order, starting from the light
// nearest slant 45, tilt 0, the thesis's first 3I light), in the set's order.
std::vector<int> ChooseReportImages(const std::vector<LightDirection>& lights, int count = 3);

}  // namespace photomat
