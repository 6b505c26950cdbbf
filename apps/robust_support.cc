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

void AddPbrOptions(CLI::App& command, PbrFitOptions& options) {
  command
      .add_option("--pbr-start-roughness", options.start_roughness,
                  "pbr: with --pbr-fixed-start, the roughness every pixel starts from")
      ->capture_default_str();
  command.add_flag(
      "!--pbr-fixed-start", options.grid_start,
      "pbr: start every pixel from --pbr-start-roughness and F0 0.04, not from the best pair of "
      "the roughness/F0 grid");
  command
      .add_option("--pbr-min-roughness", options.min_roughness,
                  "pbr: lower bound of the roughness (the GGX peak grows as 1/roughness^4)")
      ->capture_default_str();
  command
      .add_option("--pbr-loss-scale", options.loss_scale,
                  "pbr: Cauchy loss scale, as a fraction of the pixel's brightness (shadows and "
                  "clipped samples lose their pull beyond it)")
      ->capture_default_str();
  command
      .add_option("--pbr-prior-weight", options.prior_weight,
                  "pbr: regularise the pixels whose lights never sample the specular lobe: "
                  "roughness and F0 pulled towards the priors with this weight (0: off)")
      ->capture_default_str();
  command.add_option("--pbr-prior-roughness", options.prior_roughness, "pbr: roughness prior")
      ->capture_default_str();
  command.add_option("--pbr-prior-f0", options.prior_f0, "pbr: F0 prior")->capture_default_str();
  command.add_option("--pbr-iterations", options.max_iterations, "pbr: Ceres iterations per pixel")
      ->capture_default_str();
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
