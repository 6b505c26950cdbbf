#pragma once

#include <Eigen/Core>
#include <vector>

#include "core/light_direction.h"
#include "represent/model/light_basis.h"

namespace photomat {

// Hemispherical harmonics (Gautron et al. 2004), the light basis of HSH .rti files (RTIBuilder,
// RTIViewer, relight): spherical harmonics re-parameterised over the upper hemisphere through
// x = 2 cos(theta) - 1, so that they are orthonormal there. theta is the light's angle from the
// camera axis (slant), phi its azimuth atan2(ly, lx) (tilt). 4, 9 or 16 terms (orders 2, 3, 4).
//
// Term order and signs are those of RTIViewer, which every .rti file in the wild is read with:
// index l^2 + l + m for degree l and order m, m < 0 taking cos(|m| phi) and m > 0 sin(m phi).
// With c = cos(theta) and s = sqrt(c - c^2):
//   h0 = 1/sqrt(2 pi)
//   h1 = sqrt(6/pi) s cos(phi),  h2 = sqrt(3/(2 pi)) (2c - 1),  h3 = sqrt(6/pi) s sin(phi)
//   h4 = sqrt(30/pi) (c^2 - c) cos(2 phi),  h5 = sqrt(30/pi) (2c - 1) s cos(phi),
//   h6 = sqrt(5/(2 pi)) (6c^2 - 6c + 1),  h7 = sqrt(30/pi) (2c - 1) s sin(phi),
//   h8 = sqrt(30/pi) (c^2 - c) sin(2 phi)
//   h9 = 2 sqrt(35/pi) s^3 cos(3 phi),  h10 = sqrt(210/pi) (2c - 1)(c^2 - c) cos(2 phi),
//   h11 = 2 sqrt(21/pi) s (5c^2 - 5c + 1) cos(phi),  h12 = sqrt(7/(2 pi)) (20c^3 - 30c^2 + 12c -
//   1), h13 = 2 sqrt(21/pi) s (5c^2 - 5c + 1) sin(phi),  h14 = sqrt(210/pi) (2c - 1)(c^2 - c) sin(2
//   phi), h15 = 2 sqrt(35/pi) s^3 sin(3 phi).
// A light below the sample plane (lz < 0) is evaluated at the horizon (c = 0): the basis is only
// defined over the hemisphere (IMPLEMENTER CHOICE, as RTIViewer clamps its light).
class HshLightBasis final : public LightBasis {
 public:
  // Throws Error unless `terms` is 4, 9 or 16.
  explicit HshLightBasis(int terms);
  std::string_view kind() const override { return "hsh"; }
  int size() const override { return terms_; }
  Eigen::VectorXd Coefficients(const LightDirection& light) const override;
  nlohmann::json ToJson() const override { return {{"kind", "hsh"}, {"terms", terms_}}; }

  static bool ValidTermCount(int terms) { return terms == 4 || terms == 9 || terms == 16; }

 private:
  int terms_;
};

// The HSH terms of each light as the columns of a terms x n matrix.
Eigen::MatrixXd HshTerms(const std::vector<LightDirection>& lights, int terms);

}  // namespace photomat
