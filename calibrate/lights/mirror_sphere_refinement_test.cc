// The mirror-sphere calibration with its Ceres refinement (built with PHOTOMAT_WITH_CERES): the
// outline's geometric fit and the joint refinement of the sphere with the lights.
#include "calibrate/lights/mirror_sphere_refinement.h"

#include <fmt/format.h>
#include <gtest/gtest.h>

#include <Eigen/Dense>
#include <algorithm>
#include <cmath>
#include <filesystem>
#include <numeric>

#include "calibrate/lights/calibration_report.h"
#include "calibrate/lights/light_list.h"
#include "calibrate/lights/mirror_sphere.h"
#include "calibrate/testing/synthetic_calibration.h"
#include "core/error.h"
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
  // Measured errors (the joint refinement weighing each residual by its noise): centre 0.0083,
  // 0.102 px, radius 0.0044 px, edge RMS 0.166 px, lights 0.234 degrees mean; bounds
  // 0.017 = 0.0083 * 2, 0.155 = 0.102 * 1.5, 0.0088 = 0.0044 * 2, 0.25 = 0.166 * 1.5,
  // 0.35 = 0.234 * 1.5.
  EXPECT_NEAR(result.sphere.centre.x(), 110.2, 0.017);
  EXPECT_NEAR(result.sphere.centre.y(), 72.6, 0.155);
  EXPECT_NEAR(result.sphere.radius, 55.0, 0.0088);
  EXPECT_LT(result.edge_rms_pixels, 0.25);
  EXPECT_LT(CompareLights(result.lights, lights).mean, 0.35);
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

std::vector<Eigen::Vector3d> NearLamps() { return NearLampRing(); }

std::vector<LightDirection> DirectionsFromTheCentre(const std::vector<Eigen::Vector3d>& lamps) {
  std::vector<LightDirection> directions;
  for (const auto& lamp : lamps) directions.push_back(LightDirection::FromVector(lamp));
  return directions;
}

struct NearLampCalibration {
  MirrorSphereCalibration refined, unrefined;
};

NearLampCalibration CalibrateNearLamps(const std::vector<Eigen::Vector3d>& lamps) {
  const MirrorSphereRender render = RenderMirrorSpheresUnderLamps(lamps, TwoSphereRenderOptions());
  MirrorSphereOptions options;
  options.light_model = LightModel::kNear;
  NearLampCalibration result;
  result.refined = CalibrateLightsFromMirrorSphere(render.images, SphereImageNames(lamps.size()),
                                                   render.coverage, options);
  options.refine = false;
  result.unrefined = CalibrateLightsFromMirrorSphere(render.images, SphereImageNames(lamps.size()),
                                                     render.coverage, options);
  return result;
}

// The refinement that earns its name: one sphere sees each lamp in one direction, two see where
// it is. The unrefined lights (the mean of the two spheres' directions, the distant-light
// assumption) are off by the parallax between the spheres and the sample's centre; the lamps
// triangulated jointly with the spheres give the direction from the centre.
TEST(MirrorSphereRefinementTest, NearLampsTriangulatedFromTwoSpheresBeatTheUnrefinedLights) {
  const std::vector<Eigen::Vector3d> lamps = NearLamps();
  const NearLampCalibration result = CalibrateNearLamps(lamps);
  const std::vector<LightDirection> truth = DirectionsFromTheCentre(lamps);
  const AngleStats refined = CompareLights(result.refined.lights, truth);
  const AngleStats unrefined = CompareLights(result.unrefined.lights, truth);
  ASSERT_EQ(result.refined.lamp_positions.size(), lamps.size());
  double position_error = 0.0;
  for (std::size_t i = 0; i < lamps.size(); ++i) {
    position_error += (result.refined.lamp_positions[i] - lamps[i]).norm() / lamps[i].norm() /
                      static_cast<double>(lamps.size());
  }
  std::printf(
      "near lamps, two spheres: refined mean %.3f (max %.3f), unrefined mean %.3f (max %.3f) "
      "degrees; lamp positions %.2f %% of their distance; highlight noise %.3f px (%s); %s\n",
      refined.mean, refined.max, unrefined.mean, unrefined.max, 100 * position_error,
      result.refined.refinement.highlight_sigma_pixels,
      result.refined.refinement.highlight_sigma_measured ? "measured" : "assumed",
      result.refined.refinement.status.c_str());
  RecordProperty("refined_mean_deg", std::to_string(refined.mean));
  RecordProperty("unrefined_mean_deg", std::to_string(unrefined.mean));
  EXPECT_TRUE(result.refined.refinement.used);
  EXPECT_EQ(result.refined.refinement.status, "converged");
  EXPECT_TRUE(result.refined.refinement.highlight_sigma_measured);
  EXPECT_TRUE(result.unrefined.lamp_positions.empty());
  // Measured: refined mean 0.079, max 0.186 degrees; unrefined mean 3.314 (42 x worse); lamp
  // positions 0.45 % of their distance. Bounds: 0.12 = 0.079 * 1.5, 0.28 = 0.186 * 1.5,
  // 2.2 = 3.314 / 1.5, 0.0068 = 0.0045 * 1.5.
  EXPECT_LT(refined.mean, 0.12);
  EXPECT_LT(refined.max, 0.28);
  EXPECT_GT(unrefined.mean, 2.2);
  EXPECT_LT(position_error, 0.0068);
}

// The reported per-light uncertainty (the Ceres covariance of the weighed problem) must describe
// the errors the lights really have: the RMS of the actual angular errors over the RMS of the
// reported ones is near 1.
TEST(MirrorSphereRefinementTest, ReportedUncertaintyDescribesTheActualErrors) {
  const std::vector<Eigen::Vector3d> lamps = NearLamps();
  const MirrorSphereCalibration result = CalibrateNearLamps(lamps).refined;
  const std::vector<LightDirection> truth = DirectionsFromTheCentre(lamps);
  ASSERT_EQ(result.light_uncertainty_degrees.size(), lamps.size());
  double actual = 0.0, reported = 0.0;
  for (std::size_t i = 0; i < lamps.size(); ++i) {
    ASSERT_TRUE(std::isfinite(result.light_uncertainty_degrees[i])) << i;
    actual += std::pow(result.lights[i].AngleToDegrees(truth[i]), 2);
    reported += std::pow(result.light_uncertainty_degrees[i], 2);
  }
  const double ratio = std::sqrt(actual / reported);
  std::printf("near lamps: RMS error %.3f against RMS reported uncertainty %.3f degrees (%.2f)\n",
              std::sqrt(actual / lamps.size()), std::sqrt(reported / lamps.size()), ratio);
  // Measured 1.23 (RMS error 0.090, reported 0.073 degrees); bounds 0.82 = 1.23 / 1.5 and
  // 1.85 = 1.23 * 1.5.
  EXPECT_GT(ratio, 0.82);
  EXPECT_LT(ratio, 1.85);
}

// The Cauchy loss on the highlights: with three spheres each lamp is seen three times, so one
// wrong highlight (a bright spurious reflection, 12 px from the lamp's, taken for it on the third
// sphere) is outvoted instead of dragging its lamp.
TEST(MirrorSphereRefinementTest, AWrongHighlightIsOutvotedByTheOtherSpheres) {
  const std::vector<Eigen::Vector3d> lamps = NearLamps();
  MirrorSphereRenderOptions options = TwoSphereRenderOptions();
  const SphereCircle third{Eigen::Vector2d(160.4, 190.3), 38.0};
  options.more_spheres.push_back(third);
  MirrorSphereRender render = RenderMirrorSpheresUnderLamps(lamps, options);
  constexpr std::size_t kSpoiled = 5;
  const Eigen::Vector2d spot = third.centre + Eigen::Vector2d(-14.0, -6.0);
  Image& image = render.images[kSpoiled];
  for (int y = 0; y < image.height(); ++y) {
    for (int x = 0; x < image.width(); ++x) {
      const double d2 = (Eigen::Vector2d(x + 0.5, y + 0.5) - spot).squaredNorm();
      for (int c = 0; c < 3; ++c) image.at(x, y, c) += static_cast<float>(0.8 * std::exp(-d2 / 8));
    }
  }
  MirrorSphereOptions near;
  near.light_model = LightModel::kNear;
  const MirrorSphereCalibration result = CalibrateLightsFromMirrorSphere(
      render.images, SphereImageNames(lamps.size()), render.coverage, near);
  ASSERT_EQ(result.spheres.size(), 3u);
  // The spot was taken for the highlight of the third sphere (the middle one, left to right).
  EXPECT_LT((result.spheres[1].highlights[kSpoiled].position - spot).norm(), 1.0);
  const std::vector<LightDirection> truth = DirectionsFromTheCentre(lamps);
  const double spoiled = result.lights[kSpoiled].AngleToDegrees(truth[kSpoiled]);
  const AngleStats all = CompareLights(result.lights, truth);
  std::printf("wrong highlight: its lamp %.3f degrees off, all lamps %.3f mean; noise %.3f px\n",
              spoiled, all.mean, result.refinement.highlight_sigma_pixels);
  // Measured: the spoiled lamp 0.080 degrees off (all lamps 0.073 mean), the highlight noise
  // 0.026 px (the wrong highlight left out of it); bounds 0.12 = 0.080 * 1.5 and
  // 0.039 = 0.026 * 1.5.
  EXPECT_LT(spoiled, 0.12);
  EXPECT_LT(result.refinement.highlight_sigma_pixels, 0.039);
}

// A solve that stops without converging (here: an iteration budget of one) is not used: the
// result is the unrefined estimate, and the report says why.
TEST(MirrorSphereRefinementTest, ASolveThatDoesNotConvergeIsReportedNotUsed) {
  const std::vector<Eigen::Vector3d> lamps = NearLamps();
  const MirrorSphereRender render = RenderMirrorSpheresUnderLamps(lamps, TwoSphereRenderOptions());
  MirrorSphereOptions options;
  options.light_model = LightModel::kNear;
  options.refine_max_iterations = 1;
  const MirrorSphereCalibration stopped = CalibrateLightsFromMirrorSphere(
      render.images, SphereImageNames(lamps.size()), render.coverage, options);
  options.refine = false;
  const MirrorSphereCalibration unrefined = CalibrateLightsFromMirrorSphere(
      render.images, SphereImageNames(lamps.size()), render.coverage, options);
  EXPECT_TRUE(stopped.refinement.requested);
  EXPECT_FALSE(stopped.refinement.used);
  EXPECT_NE(stopped.refinement.status.find("did not converge (NO_CONVERGENCE"), std::string::npos)
      << stopped.refinement.status;
  EXPECT_TRUE(stopped.lamp_positions.empty());
  EXPECT_TRUE(stopped.light_uncertainty_degrees.empty());
  ASSERT_EQ(stopped.lights.size(), unrefined.lights.size());
  for (std::size_t i = 0; i < lamps.size(); ++i) {
    EXPECT_EQ(stopped.lights[i].vector(), unrefined.lights[i].vector()) << i;
  }
  for (std::size_t s = 0; s < 2; ++s) {
    EXPECT_EQ(stopped.spheres[s].refined.radius, stopped.spheres[s].initial.radius);
  }
  // ... and the report says so, in words and in its JSON.
  const std::vector<std::string> notes = MirrorSphereNotes(stopped);
  ASSERT_EQ(notes.size(), 2u);
  EXPECT_EQ(notes[0], "2 spheres, near lights");
  EXPECT_EQ(notes[1].rfind("refinement: NOT USED, the solver did not converge (NO_CONVERGENCE", 0),
            0u)
      << notes[1];
  const nlohmann::json json = MirrorSphereRefinementJson(stopped.refinement);
  EXPECT_TRUE(json["requested"].get<bool>());
  EXPECT_FALSE(json["used"].get<bool>());
  EXPECT_EQ(json["status"], stopped.refinement.status);
}

// A start the residuals cannot even evaluate (a highlight outside its sphere) fails the solve;
// the estimate handed back is the start, unchanged.
TEST(MirrorSphereRefinementTest, AFailedSolveHandsBackTheStart) {
  const SphereCircle circle{Eigen::Vector2d(50.0, 50.0), 20.0};
  std::vector<Eigen::Vector2d> outline;
  for (int a = 0; a < 90; ++a) {
    outline.push_back(circle.centre +
                      circle.radius * Eigen::Vector2d(std::cos(a * 0.0698), std::sin(a * 0.0698)));
  }
  const std::vector<MirrorSphereObservations> spheres = {
      {outline, {Eigen::Vector2d(52.0, 47.0), Eigen::Vector2d(95.0, 50.0)}}};
  MirrorSphereEstimate start;
  start.spheres = {circle};
  start.lights = {Eigen::Vector3d(0.1, 0.2, 1.0).normalized(), Eigen::Vector3d::UnitZ()};
  const MirrorSphereRefinement refinement =
      RefineMirrorSpheres(spheres, LightModel::kDistant, start, 100, 100, 100);
  EXPECT_FALSE(refinement.usable);
  EXPECT_NE(refinement.status.find("did not converge"), std::string::npos) << refinement.status;
  EXPECT_EQ(refinement.estimate.spheres[0].radius, circle.radius);
  EXPECT_EQ(refinement.estimate.lights[1], Eigen::Vector3d::UnitZ());
}

// With near lights asked of one sphere there is nothing to triangulate: a clear error.
TEST(MirrorSphereRefinementTest, NearLampsNeedTwoSpheres) {
  const MirrorSphereRender render =
      RenderMirrorSphere({LightDirection::FromSlantTilt(30, 0)}, SmallSphereRenderOptions());
  MirrorSphereOptions options;
  options.light_model = LightModel::kNear;
  try {
    CalibrateLightsFromMirrorSphere(render.images, SphereImageNames(1), render.coverage, options,
                                    "one");
    FAIL() << "expected an error";
  } catch (const Error& error) {
    EXPECT_NE(std::string(error.what())
                  .find("one: near lights are triangulated from two or more "
                        "spheres"),
              std::string::npos)
        << error.what();
  }
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

// The target is 2 degrees; measured 3.09 mean, 8.55 max, with the joint refinement as
// before it: uw-psm has one sphere, whose highlights cannot check it (each light has exactly its
// two highlight residuals; mirror_sphere.h, step 4), so the refinement leaves the lights on the
// outline's circle. The shortfall is the file's,
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
      "%.2f) because lights.txt disagrees with the chrome highlights and with the matte sphere, "
      "and one sphere's highlights cannot correct its outline (README \"Calibration\")\n",
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
