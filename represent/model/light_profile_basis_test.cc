#include "represent/model/light_profile_basis.h"

#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include <cmath>

#include "core/error.h"
#include "core/json_file.h"

namespace photomat {
namespace {

using ::testing::HasSubstr;
using ::testing::ThrowsMessage;

// Lights at three slants, tilts staggered: an irregular set as hand-held captures give.
std::vector<LightDirection> StaggeredLights() {
  std::vector<LightDirection> lights;
  for (int ring = 0; ring < 3; ++ring) {
    for (int t = 0; t < 8; ++t) {
      lights.push_back(LightDirection::FromSlantTilt(20.0 + 20.0 * ring, 45.0 * t + 13.0 * ring));
    }
  }
  return lights;
}

TEST(RbfInterpolationTest, ReproducesTheNodesExactlyWithoutRegularisation) {
  const auto lights = StaggeredLights();
  const RbfInterpolation rbf(lights, 25.0, 0.0);
  for (std::size_t i = 0; i < lights.size(); ++i) {
    const Eigen::VectorXd w = rbf.Weights(lights[i]);
    Eigen::VectorXd unit = Eigen::VectorXd::Zero(static_cast<Eigen::Index>(lights.size()));
    unit[static_cast<Eigen::Index>(i)] = 1.0;
    EXPECT_LT((w - unit).cwiseAbs().maxCoeff(), 1e-9) << "light " << i;
  }
}

TEST(RbfInterpolationTest, ReproducesAffineFunctionsOfTheLightEverywhere) {
  // The affine tail: a profile a + b.l is interpolated exactly at any light, captured or not.
  const auto lights = StaggeredLights();
  const Eigen::Vector3d b(0.4, -0.3, 0.9);
  const auto truth = [&](const LightDirection& l) { return 0.2 + b.dot(l.vector()); };
  Eigen::VectorXd profile(static_cast<Eigen::Index>(lights.size()));
  for (std::size_t i = 0; i < lights.size(); ++i)
    profile[static_cast<Eigen::Index>(i)] = truth(lights[i]);
  for (double regularisation : {0.0, 1e-2}) {
    const RbfInterpolation rbf(lights, 30.0, regularisation);
    for (const auto& light :
         {LightDirection::FromSlantTilt(0, 0), LightDirection::FromSlantTilt(33, 101),
          LightDirection::FromSlantTilt(80, 250)}) {
      EXPECT_NEAR(rbf.Weights(light).dot(profile), truth(light), 1e-9) << regularisation;
    }
  }
}

TEST(RbfInterpolationTest, TheQuadraticTailReproducesPtmFunctionsEverywhere) {
  // The quadratic tail is a least-squares base under the Gaussians: a profile in PTM's span
  // (a quadratic of lx, ly) is interpolated exactly at any light, with or without regularisation,
  // and the nodes are still reproduced exactly without it.
  const auto lights = StaggeredLights();
  const auto truth = [](const LightDirection& l) {
    return 0.3 + 0.5 * l.x() - 0.2 * l.y() + 0.7 * l.x() * l.x() - 0.4 * l.y() * l.y() +
           0.6 * l.x() * l.y();
  };
  Eigen::VectorXd profile(static_cast<Eigen::Index>(lights.size()));
  for (std::size_t i = 0; i < lights.size(); ++i) {
    profile[static_cast<Eigen::Index>(i)] = truth(lights[i]);
  }
  for (double regularisation : {0.0, 1e-2}) {
    const RbfInterpolation rbf(lights, 30.0, regularisation, RbfTail::kQuadratic);
    EXPECT_EQ(rbf.tail(), RbfTail::kQuadratic);
    for (const auto& light :
         {LightDirection::FromSlantTilt(0, 0), LightDirection::FromSlantTilt(33, 101),
          LightDirection::FromSlantTilt(80, 250)}) {
      // Measured: below 1e-12; bound 1e-9.
      EXPECT_NEAR(rbf.Weights(light).dot(profile), truth(light), 1e-9) << regularisation;
    }
  }
  // The affine tail does not reproduce it between the lights.
  const RbfInterpolation affine(lights, 30.0, 1e-2);
  const auto light = LightDirection::FromSlantTilt(80, 250);
  EXPECT_GT(std::abs(affine.Weights(light).dot(profile) - truth(light)), 1e-3);
  const RbfInterpolation exact(lights, 25.0, 0.0, RbfTail::kQuadratic);
  for (std::size_t i = 0; i < lights.size(); ++i) {
    Eigen::VectorXd unit = Eigen::VectorXd::Zero(static_cast<Eigen::Index>(lights.size()));
    unit[static_cast<Eigen::Index>(i)] = 1.0;
    EXPECT_LT((exact.Weights(lights[i]) - unit).cwiseAbs().maxCoeff(), 1e-9) << "light " << i;
  }
}

TEST(RbfInterpolationTest, OneRingOfLightsStillSolves) {
  // Equal slants fix lz: the tail drops the term the lights do not determine.
  std::vector<LightDirection> ring;
  for (int t = 0; t < 12; ++t) ring.push_back(LightDirection::FromSlantTilt(45, 30.0 * t));
  const RbfInterpolation rbf(ring, 30.0, 0.0);
  EXPECT_NEAR(rbf.Weights(ring[3])[3], 1.0, 1e-9);
}

TEST(RbfInterpolationTest, RejectsBadParameters) {
  const auto lights = StaggeredLights();
  EXPECT_THAT([&] { RbfInterpolation(lights, 0.0, 0.0); },
              ThrowsMessage<Error>(HasSubstr("outside (0, 180]")));
  EXPECT_THAT([&] { RbfInterpolation(lights, 20.0, -1.0); },
              ThrowsMessage<Error>(HasSubstr("regularisation")));
  // A light captured twice makes the unregularised system singular; regularisation solves it.
  auto twice = lights;
  twice.push_back(lights.front());
  EXPECT_THAT([&] { RbfInterpolation(twice, 20.0, 0.0); },
              ThrowsMessage<Error>(HasSubstr("singular")));
  EXPECT_NO_THROW(RbfInterpolation(twice, 20.0, 1e-3));
}

TEST(BilinearLightBasisTest, GridWeightsInterpolateBilinearly) {
  // On a 5 x 5 grid (spacing 0.5) the node (2, 3) is at (0, 0.5).
  const auto at_node = BilinearLightBasis::GridWeights(5, 0.0, 0.5);
  double total = 0.0;
  for (const auto& [node, weight] : at_node) {
    total += weight;
    if (weight > 1e-12) {
      EXPECT_EQ(node, 3 * 5 + 2);
    }
  }
  EXPECT_NEAR(total, 1.0, 1e-12);
  // A function linear in (lx, ly) sampled on the nodes comes back exactly between them.
  const auto f = [](double x, double y) { return 0.3 + 1.2 * x - 0.7 * y; };
  Eigen::MatrixXd pca(25, 1);
  for (int j = 0; j < 5; ++j) {
    for (int i = 0; i < 5; ++i) pca(j * 5 + i, 0) = f(-1 + 0.5 * i, -1 + 0.5 * j);
  }
  const BilinearLightBasis basis(5, pca);
  const auto light = LightDirection::FromSlantTilt(40, 200);
  EXPECT_NEAR(basis.Coefficients(light)[0], f(light.x(), light.y()), 1e-12);
}

TEST(LightProfileBasisTest, JsonRoundTripGivesTheSameCoefficients) {
  const auto lights = StaggeredLights();
  const auto n = static_cast<Eigen::Index>(lights.size());
  Eigen::MatrixXd pca(n, 3);
  for (Eigen::Index i = 0; i < n; ++i) {
    for (int j = 0; j < 3; ++j) pca(i, j) = std::sin(0.7 * static_cast<double>(i) + j);
  }
  const RbfLightBasis rbf(RbfInterpolation(lights, 22.0, 1e-3), pca);
  const RbfLightBasis quadratic(RbfInterpolation(lights, 22.0, 1e-3, RbfTail::kQuadratic), pca);
  Eigen::MatrixXd grid_pca(16, 2);
  for (Eigen::Index i = 0; i < 16; ++i) grid_pca.row(i) << std::cos(0.3 * i), 0.1 * i;
  const BilinearLightBasis bilinear(4, grid_pca);
  EXPECT_EQ(quadratic.ToJson()["tail"], "quadratic");
  for (const LightBasis* basis :
       std::initializer_list<const LightBasis*>{&rbf, &quadratic, &bilinear}) {
    const nlohmann::json json = nlohmann::json::parse(basis->ToJson().dump());
    const auto loaded = LightBasisFromJson(JsonReader(json, "stack.exr"));
    EXPECT_EQ(loaded->kind(), basis->kind());
    const auto light = LightDirection::FromSlantTilt(37, 77);
    EXPECT_LT((loaded->Coefficients(light) - basis->Coefficients(light)).norm(), 1e-12);
  }
  // A stack written before the tail existed has none: affine.
  nlohmann::json old = rbf.ToJson();
  old.erase("tail");
  const auto loaded = LightBasisFromJson(JsonReader(old, "stack.exr"));
  const auto light = LightDirection::FromSlantTilt(37, 77);
  EXPECT_LT((loaded->Coefficients(light) - rbf.Coefficients(light)).norm(), 1e-12);
  nlohmann::json bad = rbf.ToJson();
  bad["tail"] = "cubic";
  EXPECT_THAT([&] { LightBasisFromJson(JsonReader(bad, "stack.exr")); },
              ThrowsMessage<Error>(HasSubstr("cubic")));
}

TEST(LightProfileBasisTest, RejectsAMismatchedPcaBasis) {
  EXPECT_THAT([] { BilinearLightBasis(4, Eigen::MatrixXd::Ones(15, 2)); },
              ThrowsMessage<Error>(HasSubstr("4x4 grid")));
  EXPECT_THAT(
      [] {
        RbfLightBasis(RbfInterpolation(StaggeredLights(), 20.0, 0.0), Eigen::MatrixXd::Ones(5, 2));
      },
      ThrowsMessage<Error>(HasSubstr("for 24 lights")));
}

}  // namespace
}  // namespace photomat
