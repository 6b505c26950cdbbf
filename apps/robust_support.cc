#include "apps/robust_support.h"

#include <fmt/format.h>

#include "apps/cli_support.h"
#include "calibrate/radiometry/exposure.h"
#include "core/error.h"

namespace photomat::app {

RobustInput LoadSetForRobustFit(const std::filesystem::path& input, const LoadOptions& options) {
  LoadOptions raw = options;
  raw.apply_intensities = false;
  RobustInput result{LoadSetForCommand(input, raw), {}};
  result.measured = MeasuredPixelMasks(result.loaded.set);
  if (options.apply_intensities) result.loaded.set.ApplyIntensities();
  return result;
}

RobustFitOptions RobustOptionsFromCommandLine(const std::string& loss,
                                              const std::vector<Mask>& measured) {
  RobustFitOptions options;
  const auto parsed = ParseRobustLoss(loss);
  if (!parsed) throw Error(fmt::format("--loss: \"{}\": expected huber, cauchy or tukey", loss));
  options.loss = *parsed;
  options.measured = measured;
  return options;
}

std::string DescribeRobustFit(const RobustFitSummary& summary) {
  const auto share = [&](std::size_t count) {
    return summary.observations
               ? 100.0 * static_cast<double>(count) / static_cast<double>(summary.observations)
               : 0.0;
  };
  return fmt::format(
      "robust fit: {:.1f} % of observations clipped or under-exposed, {:.1f} % in attached "
      "shadow, {:.1f} % down-weighted (shadows, highlights); normals from {:.1f} %",
      share(summary.not_measured), share(summary.attached_shadow), share(summary.down_weighted),
      100.0 * summary.normal_inlier_fraction);
}

}  // namespace photomat::app
