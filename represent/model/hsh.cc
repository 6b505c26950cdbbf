#include "represent/model/hsh.h"

#include <fmt/format.h>

#include <algorithm>
#include <cmath>

#include "core/error.h"

namespace photomat {

HshLightBasis::HshLightBasis(int terms) : terms_(terms) {
  if (!ValidTermCount(terms)) {
    throw Error(fmt::format("hemispherical harmonics have 4, 9 or 16 terms, not {}", terms));
  }
}

Eigen::VectorXd HshLightBasis::Coefficients(const LightDirection& light) const {
  const double c = std::clamp(light.z(), 0.0, 1.0);
  const double phi = std::atan2(light.y(), light.x());
  const double s = std::sqrt(std::max(0.0, c - c * c));
  const double c2 = c * c;
  const double pi = M_PI;
  Eigen::VectorXd h(terms_);
  h[0] = 1.0 / std::sqrt(2 * pi);
  h[1] = std::sqrt(6 / pi) * s * std::cos(phi);
  h[2] = std::sqrt(3 / (2 * pi)) * (2 * c - 1);
  h[3] = std::sqrt(6 / pi) * s * std::sin(phi);
  if (terms_ == 4) return h;
  h[4] = std::sqrt(30 / pi) * (c2 - c) * std::cos(2 * phi);
  h[5] = std::sqrt(30 / pi) * (2 * c - 1) * s * std::cos(phi);
  h[6] = std::sqrt(5 / (2 * pi)) * (6 * c2 - 6 * c + 1);
  h[7] = std::sqrt(30 / pi) * (2 * c - 1) * s * std::sin(phi);
  h[8] = std::sqrt(30 / pi) * (c2 - c) * std::sin(2 * phi);
  if (terms_ == 9) return h;
  const double s3 = s * s * s;
  h[9] = 2 * std::sqrt(35 / pi) * s3 * std::cos(3 * phi);
  h[10] = std::sqrt(210 / pi) * (2 * c - 1) * (c2 - c) * std::cos(2 * phi);
  h[11] = 2 * std::sqrt(21 / pi) * s * (5 * c2 - 5 * c + 1) * std::cos(phi);
  h[12] = std::sqrt(7 / (2 * pi)) * (20 * c2 * c - 30 * c2 + 12 * c - 1);
  h[13] = 2 * std::sqrt(21 / pi) * s * (5 * c2 - 5 * c + 1) * std::sin(phi);
  h[14] = std::sqrt(210 / pi) * (2 * c - 1) * (c2 - c) * std::sin(2 * phi);
  h[15] = 2 * std::sqrt(35 / pi) * s3 * std::sin(3 * phi);
  return h;
}

Eigen::MatrixXd HshTerms(const std::vector<LightDirection>& lights, int terms) {
  const HshLightBasis basis(terms);
  Eigen::MatrixXd matrix(terms, lights.size());
  for (std::size_t i = 0; i < lights.size(); ++i) matrix.col(i) = basis.Coefficients(lights[i]);
  return matrix;
}

}  // namespace photomat
