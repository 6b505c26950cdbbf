// Calibration feeding the fits (calibrate + represent): the issue 5 "must show" figures on
// synthetic near-light captures and on DiLiGenT.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <numbers>
#include <numeric>
#include <optional>
#include <string>

#include "calibrate/radiometry/exposure.h"
#include "calibrate/radiometry/flat_field.h"
#include "calibrate/radiometry/near_light.h"
#include "calibrate/radiometry/semi_calibrated.h"
#include "calibrate/testing/synthetic_calibration.h"
#include "capture/io/load_photometric_set.h"
#include "capture/synthetic/synthetic_capture.h"
#include "core/error.h"
#include "core/image_io.h"
#include "represent/evaluation/evaluation.h"
#include "represent/fitting/fit.h"
#include "represent/fitting/pbr_fit.h"
#include "represent/fitting/robust_fit.h"
#include "represent/fitting/robust_intensities.h"
#include "represent/model/shading.h"
#include "tests/support/test_support.h"

namespace photomat {
namespace {

double GradientError(const PhotometricSet& set, const Image& truth) {
  const auto normals = EstimateNormals(Fit(set, Method::Parse("gradient")));
  return CompareNormals(*normals, truth, set.MaskOrAll()).mean_degrees;
}

// The thesis grid's directions, with lamps 2 sample widths away (a desk rig): the fall-off over
// the sample is about 2x between its near and far edges.
std::vector<NearLight> DeskLamps(int width) {
  std::vector<NearLight> lamps;
  for (const LightDirection& direction : ThesisLightGrid()) {
    NearLight lamp;
    lamp.position = 2.0 * width * direction.vector();
    lamp.intensity = lamp.position.squaredNorm();  // about 1 at the sample's centre
    lamps.push_back(lamp);
  }
  return lamps;
}

TEST(NearLightPipelineTest, FlatFieldCutsTheGradientNormalErrorFiveTimes) {
  SyntheticMaterialOptions options;
  options.width = options.height = 64;
  const SyntheticMaterial material = MakeSyntheticMaterial(options);
  const auto lamps = DeskLamps(64);
  const PhotometricSet sample = RenderNearLightCapture(material, lamps);
  const double uncorrected = GradientError(sample, material.normals);
  // From a matte target under the same lamps, and from the lamps' known positions.
  const PhotometricSet target = RenderNearLightTarget(64, 64, lamps, 0.5);
  const double with_target =
      GradientError(ApplyFlatField(sample, EstimateFlatField(target)), material.normals);
  const double with_positions = GradientError(
      ApplyFlatField(sample, FlatFieldFromNearLights(lamps, 64, 64, 3)), material.normals);
  std::printf(
      "near lights: Gradient mean error %.3f uncorrected, %.3f with a target flat-field "
      "(%.1fx), %.3f from the lamp positions (%.1fx)\n",
      uncorrected, with_target, uncorrected / with_target, with_positions,
      uncorrected / with_positions);
  RecordProperty("uncorrected_deg", std::to_string(uncorrected));
  RecordProperty("flat_field_deg", std::to_string(with_target));
  EXPECT_GE(uncorrected / with_target, 5.0);
  EXPECT_GE(uncorrected / with_positions, 5.0);
}

// A known GGX material (32 x 32 bumps, 25-degree relief, roughness 0.3-0.6, F0 0.04-0.12) under
// 150 near lamps on a golden-angle spiral up to slant 70, 1.2 sample widths from its centre (a
// lamp's direction changes by up to 30 degrees over the sample), exact images, corrected as
// `calibrate apply --near-lights` does. Height 0: the fit (as the flat-field) puts every pixel on
// the sample plane, and this test checks the light model, not that approximation. Each lamp's
// intensity makes its mean flat-field gain 1, so that the gains' normalisation is 1 and the
// corrected images are exactly what the near-light model of the fit (core/near_light.h) predicts.
struct NearGgxCapture {
  SyntheticMaterial truth;
  PhotometricSet corrected;
  NearLighting lighting;
};

NearGgxCapture RenderNearGgxCapture() {
  constexpr int kSize = 32;
  SyntheticMaterialOptions options;
  options.max_slope_degrees = 25.0;
  options.pattern = SurfacePattern::kBumps;
  options.width = options.height = kSize;
  options.seed = 5;
  options.roughness_min = 0.3;
  options.roughness_max = 0.6;
  options.f0_min = 0.04;
  options.f0_max = 0.12;
  SyntheticMaterial truth = MakeSyntheticMaterial(options);
  for (float& h : truth.height.values()) h = 0.0f;
  std::vector<NearLight> lamps;
  constexpr int kLamps = 150;
  const double lowest_z = std::cos(70.0 * std::numbers::pi / 180);
  const double golden = std::numbers::pi * (3.0 - std::sqrt(5.0));
  for (int i = 0; i < kLamps; ++i) {
    const double z = 1.0 - (1.0 - lowest_z) * (i + 0.5) / kLamps;
    const double r = std::sqrt(1.0 - z * z);
    NearLight lamp;
    lamp.position =
        1.2 * kSize * Eigen::Vector3d(r * std::cos(golden * i), r * std::sin(golden * i), z);
    double mean_gain = 0.0;  // FlatFieldFromNearLights' gain at intensity 1, over the pixels
    for (int y = 0; y < kSize; ++y) {
      for (int x = 0; x < kSize; ++x) {
        const Eigen::Vector3d to_lamp = lamp.position - SamplePoint(kSize, kSize, x, y);
        mean_gain += to_lamp.z() / std::pow(to_lamp.norm(), 3) / z / (kSize * kSize);
      }
    }
    lamp.intensity = 1.0 / mean_gain;
    lamps.push_back(lamp);
  }
  const PhotometricSet raw = RenderNearLightCapture(truth, lamps, true);
  PhotometricSet corrected = ApplyFlatField(raw, FlatFieldFromNearLights(lamps, kSize, kSize, 3));
  NearLighting lighting{lamps, kSize, kSize, 0};
  return {std::move(truth), std::move(corrected), std::move(lighting)};
}

struct NearGgxErrors {
  int sampled = 0;
  double roughness = 0.0, normal_degrees = 0.0;  // worst over the lobe-sampled pixels
};

// The pbr fit's worst errors on the pixels whose lobe some lamp samples (InSpecularLobe at the
// true normal and roughness, from the lamp's direction at that pixel).
NearGgxErrors PbrErrors(const Representation& pbr, const NearGgxCapture& capture) {
  using M = MicrofacetShading;
  NearGgxErrors errors;
  const Image& maps = pbr.maps();
  const SyntheticMaterial& truth = capture.truth;
  const int width = truth.normals.width();
  for (std::size_t p = 0; p < maps.pixel_count(); ++p) {
    const int x = static_cast<int>(p) % width, y = static_cast<int>(p) / width;
    const Eigen::Vector3d normal(truth.normals.pixel(p)[0], truth.normals.pixel(p)[1],
                                 truth.normals.pixel(p)[2]);
    const double roughness = truth.roughness.pixel(p)[0];
    bool sampled = false;
    for (int i = 0; i < capture.corrected.size() && !sampled; ++i) {
      sampled = InSpecularLobe(normal, capture.lighting.At(i, x, y).direction, roughness);
    }
    if (!sampled) continue;
    ++errors.sampled;
    errors.roughness =
        std::max(errors.roughness, std::abs(maps.pixel(p)[M::kRoughness] - roughness));
    const Eigen::Vector3d fitted(maps.pixel(p)[M::kNormal], maps.pixel(p)[M::kNormal + 1],
                                 maps.pixel(p)[M::kNormal + 2]);
    errors.normal_degrees =
        std::max(errors.normal_degrees, std::acos(std::min(1.0, fitted.normalized().dot(normal))) *
                                            180 / std::numbers::pi);
  }
  return errors;
}

TEST(NearLightPipelineTest, PbrWithTheNearLampsRecoversAGgxMaterialThatDistantLightsMiss) {
  NearGgxCapture capture = RenderNearGgxCapture();
  // The same corrected images fitted with the nominal directions only.
  std::optional<Representation> distant_fit;
  try {
    distant_fit.emplace(FitRobust(capture.corrected, Method::Parse("pbr")));
  } catch (const Error& error) {
    // A build without Ceres (PHOTOMAT_WITH_CERES=OFF) has no pbr fit, and says so.
    if (std::string(error.what()).find("built without") != std::string::npos) {
      GTEST_SKIP() << error.what();
    }
    throw;
  }
  const Representation& distant = *distant_fit;
  capture.corrected.set_near_lighting(capture.lighting);
  const Representation near = FitRobust(capture.corrected, Method::Parse("pbr"));
  EXPECT_EQ(near.details().at("pbr_light_model"), "near");
  EXPECT_EQ(distant.details().at("pbr_light_model"), "distant");
  // The least-squares entry point starts pbr from the robust fit too, and takes the set's lamps.
  EXPECT_EQ(Fit(capture.corrected, Method::Parse("pbr")).details().at("pbr_light_model"), "near");
  const NearGgxErrors with_lamps = PbrErrors(near, capture);
  const NearGgxErrors nominal = PbrErrors(distant, capture);
  std::printf(
      "near GGX capture, %d of %d pixels lobe-sampled: worst roughness error %.2e with the near "
      "lamps, %.3f with the nominal directions; worst normal error %.3f / %.2f degrees\n",
      with_lamps.sampled, 32 * 32, with_lamps.roughness, nominal.roughness,
      with_lamps.normal_degrees, nominal.normal_degrees);
  EXPECT_GT(with_lamps.sampled, 32 * 32 / 2);
  // The targets are 0.05 and 1 degree. Measured with the lamps (exact images: the
  // solver's tolerance) 5.4e-7 and 0.014 degrees; bounds 1e-4 and 0.05 degrees, far below the
  // targets, so that a light model off by a little shows at once.
  EXPECT_LT(with_lamps.roughness, 1e-4);
  EXPECT_LT(with_lamps.normal_degrees, 0.05);
  // With the nominal directions the same images miss both targets: measured 0.576 and 7.14
  // degrees; bounds half of that (and above the targets).
  EXPECT_GT(nominal.roughness, 0.29);
  EXPECT_GT(nominal.normal_degrees, 3.5);
}

// DiLiGenT cat with light_intensities.txt ignored: the intensities estimated jointly with the
// normals, weighted by the robust fit's outlier weights (represent/robust_intensities.h), give
// least-squares normals within 1 degree mean of the calibrated ones (the target). The
// rank-window weights alone leave 2.5 degrees: the cat's shadows and broad specular lobes pull on
// the intensity error that is a smooth function of the light direction, the near-ambiguity of
// semi-calibrated photometric stereo for lights within a cone.
TEST(SemiCalibratedDiligentTest, CatNormalsWithinOneDegreeOfTheCalibratedOnes) {
  PHOTOMAT_TEST_DATA_OR_SKIP(folder, "diligent/cat");
  LoadOptions raw;
  raw.apply_intensities = false;
  const LoadedSet loaded = LoadPhotometricSet(folder, raw);
  const Image truth = ReadImage(*loaded.ground_truth_normals).image;
  PhotometricSet calibrated = loaded.set;
  calibrated.ApplyIntensities();

  const SemiCalibratedResult estimate = EstimateLightIntensitiesRobust(loaded.set);
  PhotometricSet semi = loaded.set;
  semi.set_intensities(estimate.intensities);
  semi.ApplyIntensities();

  // The estimated intensities against the file's, both normalised to a mean of 1 per channel.
  const auto& given = loaded.set.intensities();
  double worst = 0.0;
  for (int c = 0; c < 3; ++c) {
    double mean = 0.0;
    for (const auto& row : given) mean += row[c] / static_cast<double>(given.size());
    for (std::size_t i = 0; i < given.size(); ++i) {
      worst = std::max(worst, std::abs(estimate.intensities[i][c] / (given[i][c] / mean) - 1.0));
    }
  }
  const auto calibrated_normals = *EstimateNormals(Fit(calibrated, Method::Parse("gradient")));
  const auto semi_normals = *EstimateNormals(Fit(semi, Method::Parse("gradient")));
  const NormalErrorStats between = CompareNormals(semi_normals, calibrated_normals, *semi.mask());
  const double calibrated_error =
      CompareNormals(calibrated_normals, truth, *semi.mask()).mean_degrees;
  const double semi_error = CompareNormals(semi_normals, truth, *semi.mask()).mean_degrees;
  std::printf(
      "semi-calibrated cat: %d iterations, intensities within %.2f %% of the file's; "
      "normals %.3f degrees mean from the calibrated ones; error to truth %.3f "
      "(calibrated %.3f)\n",
      estimate.iterations, 100 * worst, between.mean_degrees, semi_error, calibrated_error);
  RecordProperty("semi_calibrated_error_deg", std::to_string(semi_error));
  RecordProperty("calibrated_error_deg", std::to_string(calibrated_error));
  RecordProperty("normal_difference_deg", std::to_string(between.mean_degrees));
  EXPECT_LT(std::abs(semi_error - calibrated_error), 0.2);
  EXPECT_LT(between.mean_degrees, 1.0);
  EXPECT_LT(worst, 0.1);
}

}  // namespace
}  // namespace photomat
