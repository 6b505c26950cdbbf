// The parts of the pbr fit that do not need Ceres (built in every configuration).
#include <cmath>

#include "represent/fitting/pbr_fit.h"

namespace photomat {

nlohmann::json PbrFitOptions::ToJson() const {
  return {{"start", grid_start ? "grid" : "fixed"},
          {"start_roughness", start_roughness},
          {"start_f0", start_f0},
          {"min_roughness", min_roughness},
          {"loss", "cauchy"},
          {"loss_scale", loss_scale},
          {"prior_weight", prior_weight},
          {"prior_roughness", prior_roughness},
          {"prior_f0", prior_f0},
          {"max_iterations", max_iterations}};
}

bool InSpecularLobe(const Eigen::Vector3d& normal, const Eigen::Vector3d& light, double roughness) {
  // D(x) / D(1) = alpha^4 / (x^2 (alpha^2 - 1) + 1)^2 >= 1/2 with x = n.h, alpha^2 = a2:
  // x^2 (a2 - 1) + 1 <= sqrt(2) a2.
  const double a2 = std::pow(roughness, 4);
  const Eigen::Vector3d half = (light + Eigen::Vector3d::UnitZ()).normalized();
  const double x = normal.dot(half);
  return x > 0.0 && x * x * (a2 - 1.0) + 1.0 <= std::sqrt(2.0) * a2;
}

}  // namespace photomat
