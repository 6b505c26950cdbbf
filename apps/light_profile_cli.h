#pragma once

#include <CLI/CLI.hpp>
#include <optional>
#include <vector>

#include "represent/model/method.h"

namespace photomat::app {

// The rbf and bilinear methods' options (--rbf-width, --rbf-regularisation, --planes,
// --grid-size, --rbf-tail, --leave-out), for `fit` and `evaluate`.
struct LightProfileCli {
  std::optional<double> rbf_width_degrees;
  std::optional<double> rbf_regularisation;
  int planes = LightProfileOptions::kDefaultPlanes;
  int grid_size = LightProfileOptions::kDefaultGridSize;
  RbfTail rbf_tail = RbfTail::kAffine;
  LeaveOut leave_out = LeaveOut::kOne;
};
void AddLightProfileOptions(CLI::App& command, LightProfileCli& options);
// Sets the options on every rbf and bilinear method of `methods`.
void ApplyLightProfileOptions(const LightProfileCli& options, std::vector<Method>& methods);

}  // namespace photomat::app
