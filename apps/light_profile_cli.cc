#include "apps/light_profile_cli.h"

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
}

void ApplyLightProfileOptions(const LightProfileCli& options, std::vector<Method>& methods) {
  for (Method& method : methods) {
    method.profile.rbf_width_degrees = options.rbf_width_degrees;
    method.profile.rbf_regularisation = options.rbf_regularisation;
    method.profile.planes = options.planes;
    method.profile.grid_size = options.grid_size;
  }
}

}  // namespace photomat::app
