#include "represent/model/light_basis.h"

#include <gtest/gtest.h>

#include <Eigen/LU>

#include "core/error.h"

namespace photomat {
namespace {

TEST(LightBasisTest, ThreeImageClosedFormMatchesTheThesis) {
  // L = [l(0,45) l(90,45) l(180,45)]; c = L^-1 l gives unit vectors at the three lights, and
  // c2 = sin(tau) sin(sigma) / sin 45 in general (spec section 2.3).
  Eigen::Matrix3d l;
  l.col(0) = LightDirection::FromSlantTilt(45, 0).vector();
  l.col(1) = LightDirection::FromSlantTilt(45, 90).vector();
  l.col(2) = LightDirection::FromSlantTilt(45, 180).vector();
  const LinearLightBasis basis(l.inverse());
  EXPECT_TRUE(basis.Coefficients(LightDirection::FromSlantTilt(45, 0))
                  .isApprox(Eigen::Vector3d(1, 0, 0), 1e-12));
  EXPECT_TRUE(
      (basis.Coefficients(LightDirection::FromSlantTilt(45, 180)) - Eigen::Vector3d(0, 0, 1))
          .norm() < 1e-12);
  const double tau = 0.7, sigma = 0.4;
  const auto c =
      basis.Coefficients(LightDirection::FromSlantTilt(sigma * 180 / M_PI, tau * 180 / M_PI));
  EXPECT_NEAR(c[1], std::sin(tau) * std::sin(sigma) / std::sin(M_PI / 4), 1e-12);
  const double s45 = std::sin(M_PI / 4);
  EXPECT_NEAR(c[0],
              std::cos(tau) * std::sin(sigma) / (2 * s45) -
                  std::sin(tau) * std::sin(sigma) / (2 * s45) + std::cos(sigma) / (2 * s45),
              1e-12);
}

TEST(LightBasisTest, PtmTermsAreTheBiquadraticInLxLy) {
  const auto light = LightDirection::FromVector(0.3, -0.4, 0.866);
  const Eigen::VectorXd c = PtmLightBasis().Coefficients(light);
  const double u = light.x(), v = light.y();
  EXPECT_NEAR(c[0], u * u, 1e-15);
  EXPECT_NEAR(c[1], v * v, 1e-15);
  EXPECT_NEAR(c[2], u * v, 1e-15);
  EXPECT_NEAR(c[3], u, 1e-15);
  EXPECT_NEAR(c[4], v, 1e-15);
  EXPECT_EQ(c[5], 1.0);
}

void ExpectSameFunction(const LightBasis& a, const LightBasis& b) {
  for (double slant : {0.0, 20.0, 45.0, 70.0}) {
    for (double tilt : {0.0, 100.0, 355.0}) {
      const auto light = LightDirection::FromSlantTilt(slant, tilt);
      EXPECT_TRUE(a.Coefficients(light).isApprox(b.Coefficients(light), 1e-12));
    }
  }
}

TEST(LightBasisTest, EveryBasisRoundTripsThroughJson) {
  Eigen::MatrixXd values(2, 36);
  for (int i = 0; i < 36; ++i) values.col(i) << i * 0.5, std::sin(i);
  const std::vector<std::shared_ptr<LightBasis>> bases = {
      std::make_shared<LinearLightBasis>(Eigen::MatrixXd::Random(3, 3)),
      std::make_shared<PtmLightBasis>(),
      std::make_shared<InterpolatedLightBasis>(ThesisLightGrid(), values),
  };
  for (const auto& basis : bases) {
    const nlohmann::json json = nlohmann::json::parse(basis->ToJson().dump());
    const auto restored = LightBasisFromJson(JsonReader(json, "stack.exr"));
    EXPECT_EQ(restored->kind(), basis->kind());
    ExpectSameFunction(*basis, *restored);
  }
}

TEST(LightBasisTest, DamagedJsonNamesTheFault) {
  const auto json = nlohmann::json::parse(R"({"kind": "linear", "matrix": [[1, 0], [0, 1]]})");
  try {
    LightBasisFromJson(JsonReader(json, "s.exr", "basis"));
    FAIL() << "no error";
  } catch (const Error& e) {
    EXPECT_STREQ(e.what(), "s.exr: basis.matrix[0]: expected 3 numbers");
  }
  const auto unknown = nlohmann::json::parse(R"({"kind": "magic"})");
  EXPECT_THROW(LightBasisFromJson(JsonReader(unknown, "s.exr")), Error);
}

TEST(LightBasisTest, InterpolatedBasisBlendsTheNodeColumns) {
  const auto grid = ThesisLightGrid();
  Eigen::MatrixXd values(1, 36);
  for (int i = 0; i < 36; ++i) values(0, i) = i;
  const InterpolatedLightBasis basis(grid, values);
  // Halfway between tilts 0 (index 12) and 30 (index 13) at slant 45.
  EXPECT_NEAR(basis.Coefficients(LightDirection::FromSlantTilt(45, 15))[0], 12.5, 1e-9);
}

}  // namespace
}  // namespace photomat
