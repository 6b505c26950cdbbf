#pragma once

#include <CLI/CLI.hpp>
#include <filesystem>
#include <string>
#include <vector>

#include "capture/io/load_photometric_set.h"
#include "core/image.h"
#include "represent/fitting/robust_fit.h"

namespace photomat::app {

// `fit --robust` and `evaluate --robust`: a set loaded for a robust fit, with the per-image masks
// of the pixels that are measurements (calibrate's MeasuredPixelMasks on the images as stored,
// before the light intensities move the clipping level), then the intensities applied as asked.
struct RobustInput {
  LoadedSet loaded;
  std::vector<Mask> measured;
};
RobustInput LoadSetForRobustFit(const std::filesystem::path& input, const LoadOptions& options);

// RobustFitOptions from the command line's --loss (huber, cauchy, tukey); `measured` is not owned.
RobustFitOptions RobustOptionsFromCommandLine(const std::string& loss,
                                              const std::vector<Mask>& measured);

// The pbr fit's options (--pbr-...), for `fit` and `evaluate`.
void AddPbrOptions(CLI::App& command, PbrFitOptions& options);

// One line on what the weights rejected.
std::string DescribeRobustFit(const RobustFitSummary& summary);

}  // namespace photomat::app
