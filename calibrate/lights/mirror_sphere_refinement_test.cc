// The mirror-sphere calibration with its Ceres refinement (built with PHOTOMAT_WITH_CERES): the
// outline's geometric fit and the joint refinement of the sphere with the lights.
#include <fmt/format.h>
#include <gtest/gtest.h>

#include <Eigen/Dense>
#include <algorithm>
#include <filesystem>

#include "calibrate/lights/light_list.h"
#include "calibrate/lights/mirror_sphere.h"
#include "calibrate/testing/synthetic_calibration.h"
#include "core/image_io.h"
#include "tests/support/test_support.h"

namespace photomat {
namespace {

TEST(MirrorSphereTest, MaskOutlineGivesTheCircleToASmallFractionOfAPixel) {
  MirrorSphereRenderOptions options;
  options.sphere = {Eigen::Vector2d(151.37, 117.81), 83.4};
  const MirrorSphereRender render =
      RenderMirrorSphere({LightDirection::FromVector(0, 0, 1)}, options);
  const SphereCircle circle = FitSphereToMask(render.coverage);
  // Measured errors: centre 0.0009, 0.0039 px, radius 0.0025 px; bounds 0.008 = 0.0039 * 2 and
  // 0.005 = 0.0025 * 2.
  EXPECT_NEAR(circle.centre.x(), 151.37, 0.008);
  EXPECT_NEAR(circle.centre.y(), 117.81, 0.008);
  EXPECT_NEAR(circle.radius, 83.4, 0.005);
}

TEST(MirrorSphereTest, SyntheticSphereWithMaskRecoversLightsWithinHalfADegree) {
  const std::vector<LightDirection> lights = ThesisLightGrid();
  MirrorSphereRenderOptions options = SmallSphereRenderOptions();
  options.noise_sigma = 0.005;
  const MirrorSphereRender render = RenderMirrorSphere(lights, options);
  const MirrorSphereCalibration result = CalibrateLightsFromMirrorSphere(
      render.images, SphereImageNames(lights.size()), render.coverage, MirrorSphereOptions{});
  const AngleStats stats = CompareLights(result.lights, lights);
  RecordProperty("mean_error_deg", std::to_string(stats.mean));
  std::printf("synthetic sphere with mask: mean %.3f, max %.3f degrees\n", stats.mean, stats.max);
  // Measured: mean 0.065, max 0.128 degrees, radius error 0.0047 px, edge RMS 0.070 px; bounds
  // 0.098 = 0.065 * 1.5, 0.19 = 0.128 * 1.5, 0.0094 = 0.0047 * 2, 0.105 = 0.070 * 1.5.
  EXPECT_LT(stats.mean, 0.098);
  EXPECT_LT(stats.max, 0.19);
  EXPECT_NEAR(result.sphere.radius, 60.0, 0.0094);
  EXPECT_LT(result.edge_rms_pixels, 0.105);
}

TEST(MirrorSphereTest, SyntheticSphereWithoutMaskIsDetectedAndCalibrated) {
  const std::vector<LightDirection> lights = ThesisLightGrid();
  MirrorSphereRenderOptions options = SmallSphereRenderOptions();
  options.sphere = {Eigen::Vector2d(110.2, 72.6), 55.0};
  const MirrorSphereRender render = RenderMirrorSphere(lights, options);
  const MirrorSphereCalibration result = CalibrateLightsFromMirrorSphere(
      render.images, SphereImageNames(lights.size()), std::nullopt, MirrorSphereOptions{});
  // Measured errors: centre 0.0073, 0.109 px, radius 0.0038 px, edge RMS 0.166 px, lights 0.249
  // degrees mean; bounds 0.015 = 0.0073 * 2, 0.165 = 0.109 * 1.5, 0.0076 = 0.0038 * 2,
  // 0.25 = 0.166 * 1.5, 0.375 = 0.249 * 1.5.
  EXPECT_NEAR(result.sphere.centre.x(), 110.2, 0.015);
  EXPECT_NEAR(result.sphere.centre.y(), 72.6, 0.165);
  EXPECT_NEAR(result.sphere.radius, 55.0, 0.0076);
  EXPECT_LT(result.edge_rms_pixels, 0.25);
  EXPECT_LT(CompareLights(result.lights, lights).mean, 0.375);
}

TEST(MirrorSphereTest, PerspectiveCameraNeedsThePerspectiveModel) {
  // A wide-angle camera close to the sphere: the orthographic model is visibly wrong, the
  // perspective one with the same intrinsics is not.
  const std::vector<LightDirection> lights = ThesisLightGrid();
  MirrorSphereRenderOptions options = SmallSphereRenderOptions();
  const CameraIntrinsics camera{200.0, 200.0, 99.5, 74.5};
  options.camera = camera;
  options.sphere_centre_camera = Eigen::Vector3d(0.6, -0.3, 4.5);
  const MirrorSphereRender render = RenderMirrorSphere(lights, options);
  MirrorSphereOptions perspective;
  perspective.camera = camera;
  const auto with_camera = CalibrateLightsFromMirrorSphere(
      render.images, SphereImageNames(lights.size()), render.coverage, perspective);
  const auto orthographic = CalibrateLightsFromMirrorSphere(
      render.images, SphereImageNames(lights.size()), render.coverage, MirrorSphereOptions{});
  const double perspective_error = CompareLights(with_camera.lights, lights).mean;
  RecordProperty("perspective_mean_error_deg", std::to_string(perspective_error));
  std::printf("synthetic perspective sphere: mean %.3f degrees (orthographic model: %.3f)\n",
              perspective_error, CompareLights(orthographic.lights, lights).mean);
  // Measured 0.105 degrees (orthographic model 5.59); bounds 0.16 = 0.105 * 1.5 and
  // 3.7 = 5.59 / 1.5.
  EXPECT_LT(perspective_error, 0.16);
  EXPECT_GT(CompareLights(orthographic.lights, lights).mean, 3.7);
}

// The University of Washington chrome sphere (12 images, 8-bit, anti-aliased mask) against the
// lights.txt shipped beside it.
AngleStats UwChromeAgainstTheShippedLights(const std::filesystem::path& folder) {
  std::vector<Image> images;
  std::vector<std::string> names;
  for (int i = 0; i < 12; ++i) {
    names.push_back(fmt::format("chrome.{}.png", i));
    images.push_back(ReadImage(folder / "chrome" / names.back()).image);
  }
  ImageReadOptions coverage;
  coverage.colour_space = ColourSpace::kLinear;
  const Image mask = ReadImage(folder / "chrome" / "chrome.mask.png", coverage).image;
  const MirrorSphereCalibration result =
      CalibrateLightsFromMirrorSphere(images, names, mask, MirrorSphereOptions{});
  const std::vector<LightDirection> reference = ReadLightList(folder / "lights.txt");
  EXPECT_EQ(reference.size(), 12u);
  return CompareLights(result.lights, reference);
}

// The target is 2 degrees; measured 3.09 mean, 8.55 max. The shortfall is the file's,
// not this calibration's (README "Calibration"): every highlight definition (this weighted
// centroid, the centroid of the clipped pixels, sRGB or linear decoding) agrees to 0.15 px,
// while lights.txt puts the highlights 1.2 to 8.9 px away, nearly all to the left; the
// orthographic sphere that agrees best with the file (1.25 degrees) has a radius of 130 px where
// the outline (mask and visible rim) measures 119.5; a perspective camera does not close the gap
// (2.9 degrees at best); and the matte grey sphere under the same lights (next test) agrees
// with these lights, not with the file's. This bound guards against regressions; the target is
// kept in the next test, as an expected failure.
TEST(MirrorSphereRealTest, UwChromeSphereAgreesWithTheShippedLights) {
  PHOTOMAT_TEST_DATA_OR_SKIP(folder, "uw-psm");
  const AngleStats stats = UwChromeAgainstTheShippedLights(folder);
  RecordProperty("mean_difference_deg", std::to_string(stats.mean));
  RecordProperty("max_difference_deg", std::to_string(stats.max));
  std::printf("uw-psm chrome: mean %.3f, max %.3f degrees\n", stats.mean, stats.max);
  EXPECT_LT(stats.mean, 3.5);
}

// The 2-degree target, not met: a visible expected failure. It prints what it misses and why, and
// fails once the target is met, so that 2 degrees then becomes the bound of the test above.
TEST(MirrorSphereRealTest, UwChromeSphereMissesTheTwoDegreeTarget) {
  PHOTOMAT_TEST_DATA_OR_SKIP(folder, "uw-psm");
  constexpr double kTargetDegrees = 2.0;
  const AngleStats stats = UwChromeAgainstTheShippedLights(folder);
  std::printf(
      "EXPECTED FAILURE: target %.1f degrees mean against uw-psm lights.txt not met (measured "
      "%.2f) because lights.txt disagrees with the chrome highlights and with the matte sphere "
      "(README \"Calibration\")\n",
      kTargetDegrees, stats.mean);
  RecordProperty("expected_failure",
                 fmt::format("mean {:.2f} degrees against target {}", stats.mean, kTargetDegrees));
  EXPECT_GE(stats.mean, kTargetDegrees)
      << "the 2-degree target is met (" << stats.mean
      << "): make it the bound of UwChromeSphereAgreesWithTheShippedLights and delete this test";
}

// Light directions from a matte (Lambertian) sphere of known outline, independent of any
// highlight: per image, the least-squares b in I = n.b over the lit, unclipped pixels (orthographic
// normals from the circle; the rim and the shadow terminator left out).
std::vector<LightDirection> LightsFromMatteSphere(const std::vector<Image>& images,
                                                  const SphereCircle& sphere) {
  std::vector<LightDirection> lights;
  for (const Image& image : images) {
    const float peak = *std::max_element(image.values().begin(), image.values().end());
    Eigen::Matrix3d normal_sums = Eigen::Matrix3d::Zero();
    Eigen::Vector3d value_sums = Eigen::Vector3d::Zero();
    for (int y = 0; y < image.height(); ++y) {
      for (int x = 0; x < image.width(); ++x) {
        const Eigen::Vector2d d =
            (Eigen::Vector2d(x + 0.5, y + 0.5) - sphere.centre) / sphere.radius;
        if (d.norm() > 0.95) continue;
        const Eigen::Vector3d n(d.x(), -d.y(), std::sqrt(1.0 - d.squaredNorm()));
        double value = 0.0;
        for (float v : image.pixel(x, y)) value += v / static_cast<double>(image.channels());
        if (value < 0.25 * peak || value > 0.98) continue;
        normal_sums += n * n.transpose();
        value_sums += value * n;
      }
    }
    lights.push_back(LightDirection::FromVector(normal_sums.ldlt().solve(value_sums)));
  }
  return lights;
}

// uw-psm's grey sphere was photographed under the same 12 lights: its shading measures them
// without any highlight. The chrome calibration agrees with it better than the shipped lights.txt
// does (measured: 1.87 against 3.36 degrees mean), most of all for the lights where the file and
// the chrome disagree. The grey images are read as linear (course assignments built on this data
// say so; decoded as sRGB the matte fit is 6.6 degrees from the chrome, 8.7 from the file).
TEST(MirrorSphereRealTest, UwChromeLightsAgreeWithTheMatteSphereBetterThanTheShippedFile) {
  PHOTOMAT_TEST_DATA_OR_SKIP(folder, "uw-psm");
  ImageReadOptions linear;
  linear.colour_space = ColourSpace::kLinear;
  std::vector<Image> chrome, grey;
  for (int i = 0; i < 12; ++i) {
    chrome.push_back(ReadImage(folder / "chrome" / fmt::format("chrome.{}.png", i)).image);
    grey.push_back(ReadImage(folder / "gray" / fmt::format("gray.{}.png", i), linear).image);
  }
  const Image chrome_mask = ReadImage(folder / "chrome" / "chrome.mask.png", linear).image;
  const Image grey_mask = ReadImage(folder / "gray" / "gray.mask.png", linear).image;
  const std::vector<LightDirection> from_chrome =
      CalibrateLightsFromMirrorSphere(chrome, SphereImageNames(12), chrome_mask, {}).lights;
  const std::vector<LightDirection> from_grey =
      LightsFromMatteSphere(grey, FitSphereToMask(grey_mask));
  const std::vector<LightDirection> shipped = ReadLightList(folder / "lights.txt");
  const AngleStats chrome_to_grey = CompareLights(from_chrome, from_grey);
  const AngleStats file_to_grey = CompareLights(shipped, from_grey);
  std::printf(
      "uw-psm matte sphere: chrome lights %.3f mean (%.3f max), lights.txt %.3f mean "
      "(%.3f max) degrees from it\n",
      chrome_to_grey.mean, chrome_to_grey.max, file_to_grey.mean, file_to_grey.max);
  RecordProperty("chrome_to_matte_deg", std::to_string(chrome_to_grey.mean));
  RecordProperty("file_to_matte_deg", std::to_string(file_to_grey.mean));
  EXPECT_LT(chrome_to_grey.mean, 2.0);
  EXPECT_LT(chrome_to_grey.mean, 0.7 * file_to_grey.mean);
}

}  // namespace
}  // namespace photomat
