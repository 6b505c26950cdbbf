#include "apps/light_profile_cli.h"

#include <map>
#include <string>

namespace photomat::app {

void AddLightProfileOptions(CLI::App& command, LightProfileCli& options) {
  command
      .add_option("--rbf-width", options.rbf_width_degrees,
                  "rbf: Gaussian kernel width in degrees (default: chosen by leave-one-out on "
                  "the capture, recorded in the stack)")
      ->check(CLI::Range(1e-3, 180.0));
  command
      .add_option("--rbf-regularisation", options.rbf_regularisation,
                  "rbf: added to the kernel matrix's unit diagonal; 0 interpolates the captured "
                  "lights exactly (default: chosen by leave-one-out)")
      ->check(CLI::Range(0.0, 1e6));
  command
      .add_option("--planes", options.planes,
                  "rbf, bilinear: PCA planes per colour channel (0: no PCA; -1: chosen by "
                  "leave-one-out on the capture, 1 to 16)")
      ->capture_default_str()
      ->check(CLI::Range(-1, 1024));
  command
      .add_option("--grid-size", options.grid_size,
                  "bilinear: nodes per side of the light grid over (lx, ly) in [-1, 1]^2")
      ->capture_default_str()
      ->check(CLI::Range(2, 32));
  const std::map<std::string, RbfTail> tails = {{"affine", RbfTail::kAffine},
                                                {"quadratic", RbfTail::kQuadratic}};
  command
      .add_option("--rbf-tail", options.rbf_tail,
                  "rbf: the low-order part under the Gaussians: affine (1, lx, ly, lz) or "
                  "quadratic (PTM's terms and lz)")
      ->transform(CLI::CheckedTransformer(tails))
      ->option_text("affine|quadratic (default: affine)");
  const std::map<std::string, LeaveOut> scores = {{"one", LeaveOut::kOne},
                                                  {"block", LeaveOut::kBlock},
                                                  {"edge", LeaveOut::kEdge},
                                                  {"side", LeaveOut::kSide}};
  command
      .add_option("--leave-out", options.leave_out,
                  "rbf, bilinear: how unset parameters are chosen on the capture's own lights: "
                  "one (each light left out), block (every 8th light at once), edge (each "
                  "light on the hull of the lights left out: extrapolation) or side (each side "
                  "of that hull at once: extrapolation one grid step beyond the lights)")
      ->transform(CLI::CheckedTransformer(scores))
      ->option_text("one|block|edge|side (default: one)");
}

void ApplyLightProfileOptions(const LightProfileCli& options, std::vector<Method>& methods) {
  for (Method& method : methods) {
    method.profile.rbf_width_degrees = options.rbf_width_degrees;
    method.profile.rbf_regularisation = options.rbf_regularisation;
    method.profile.planes = options.planes;
    method.profile.grid_size = options.grid_size;
    method.profile.rbf_tail = options.rbf_tail;
    method.profile.leave_out = options.leave_out;
  }
}

}  // namespace photomat::app
