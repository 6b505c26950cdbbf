#include "calibrate/lights/mirror_sphere.h"

#include <fmt/format.h>
#include <gtest/gtest.h>

#include <Eigen/Dense>
#include <algorithm>
#include <numeric>

#include "calibrate/lights/mirror_sphere_refinement.h"
#include "calibrate/testing/synthetic_calibration.h"
#include "core/error.h"
#include "core/image_io.h"
#include "tests/support/test_support.h"

namespace photomat {
namespace {

TEST(MirrorSphereTest, ReflectionFormulaRoundTrips) {
  const SphereCircle sphere{Eigen::Vector2d(100.3, 80.7), 55.5};
  for (const LightDirection& light : ThesisLightGrid()) {
    const Eigen::Vector2d highlight = HighlightFromLight(sphere, light);
    EXPECT_LT(LightFromHighlight(sphere, highlight).AngleToDegrees(light), 1e-9);
  }
  // The highlight of a light on the camera axis is at the centre; a light to the right (+x) puts
  // it right of the centre, a light above (+y) above it (smaller row).
  EXPECT_LT(
      (HighlightFromLight(sphere, LightDirection::FromVector(0, 0, 1)) - sphere.centre).norm(),
      1e-12);
  EXPECT_GT(HighlightFromLight(sphere, LightDirection::FromSlantTilt(40, 0)).x(),
            sphere.centre.x());
  EXPECT_LT(HighlightFromLight(sphere, LightDirection::FromSlantTilt(40, 90)).y(),
            sphere.centre.y());
}

// The calibration without its refinement (what a build without Ceres gives): the lights from the
// highlights on the outline's circle. Measured: mean 0.065, max 0.128 degrees, alike with Ceres's
// geometric outline fit and with the algebraic fit alone (no Ceres); bounds 0.098 = 0.065 * 1.5
// and 0.19 = 0.128 * 1.5.
TEST(MirrorSphereTest, UnrefinedSyntheticSphereWithMaskRecoversLights) {
  const std::vector<LightDirection> lights = ThesisLightGrid();
  MirrorSphereRenderOptions options = SmallSphereRenderOptions();
  options.noise_sigma = 0.005;
  const MirrorSphereRender render = RenderMirrorSphere(lights, options);
  MirrorSphereOptions unrefined;
  unrefined.refine = false;
  const MirrorSphereCalibration result = CalibrateLightsFromMirrorSphere(
      render.images, SphereImageNames(lights.size()), render.coverage, unrefined);
  const AngleStats stats = CompareLights(result.lights, lights);
  std::printf("synthetic sphere with mask, unrefined: mean %.3f, max %.3f degrees\n", stats.mean,
              stats.max);
  EXPECT_LT(stats.mean, 0.098);
  EXPECT_LT(stats.max, 0.19);
  EXPECT_EQ(result.sphere.radius, result.initial.radius);
}

// The refinement is there exactly when the build has Ceres (PHOTOMAT_TEST_WITH_CERES, from
// calibrate/lights/CMakeLists.txt); without it, asking for it is an Error that says why.
TEST(MirrorSphereTest, RefinementIsAvailableExactlyWhenBuiltWithCeres) {
  EXPECT_EQ(MirrorSphereRefinementAvailable(), PHOTOMAT_TEST_WITH_CERES != 0);
  const std::vector<LightDirection> lights = {LightDirection::FromSlantTilt(30, 0),
                                              LightDirection::FromSlantTilt(40, 90),
                                              LightDirection::FromSlantTilt(35, 200)};
  const MirrorSphereRender render = RenderMirrorSphere(lights, SmallSphereRenderOptions());
  if (MirrorSphereRefinementAvailable()) {
    EXPECT_NO_THROW(
        CalibrateLightsFromMirrorSphere(render.images, SphereImageNames(3), render.coverage, {}));
    return;
  }
  try {
    CalibrateLightsFromMirrorSphere(render.images, SphereImageNames(3), render.coverage, {});
    FAIL() << "expected an error";
  } catch (const Error& error) {
    EXPECT_NE(std::string(error.what())
                  .find("this photomat was built without the Ceres mirror-sphere refinement "
                        "(PHOTOMAT_WITH_CERES=OFF: "),
              std::string::npos)
        << error.what();
  }
}

TEST(MirrorSphereTest, EachFailingImageIsNamedWithItsFault) {
  std::vector<LightDirection> lights = {LightDirection::FromSlantTilt(30, 0),
                                        LightDirection::FromSlantTilt(40, 90),
                                        LightDirection::FromSlantTilt(35, 200)};
  MirrorSphereRenderOptions options = SmallSphereRenderOptions();
  MirrorSphereRender render = RenderMirrorSphere(lights, options);
  // Image 1: the lamp is off (only the room's reflection).
  MirrorSphereRenderOptions dark = options;
  dark.lamp_peak = 0.0;
  render.images[1] = RenderMirrorSphere({lights[1]}, dark).images[0];
  // Image 2: a big clipped blob (a wide lamp, heavily over-exposed).
  MirrorSphereRenderOptions bright = options;
  bright.lamp_sigma_degrees = 8.0;
  bright.lamp_peak = 50.0;
  render.images[2] = RenderMirrorSphere({lights[2]}, bright).images[0];
  for (float& v : render.images[2].values()) v = std::min(v, 1.0f);
  // Without Ceres, asking for the refinement is itself the error (the test above); the faults
  // of the images are then found without it.
  MirrorSphereOptions calibration;
  calibration.refine = MirrorSphereRefinementAvailable();
  try {
    CalibrateLightsFromMirrorSphere(render.images, SphereImageNames(3), render.coverage,
                                    calibration);
    FAIL() << "expected an error";
  } catch (const Error& error) {
    const std::string message = error.what();
    EXPECT_NE(message.find("2 of 3"), std::string::npos) << message;
    EXPECT_NE(message.find("sphere_1.png: highlight too weak"), std::string::npos) << message;
    EXPECT_NE(message.find("sphere_2.png: saturated highlight"), std::string::npos) << message;
    EXPECT_EQ(message.find("sphere_0.png"), std::string::npos) << message;
  }
}

TEST(MirrorSphereTest, HighlightAtTheRimIsRejected) {
  const LightDirection behind = LightDirection::FromSlantTilt(172, 30);
  const MirrorSphereRender render = RenderMirrorSphere({behind}, SmallSphereRenderOptions());
  const SphereCircle circle = FitSphereToMask(render.coverage);
  try {
    LocateHighlight(render.images[0], circle, HighlightOptions{}, "rim.png");
    FAIL() << "expected an error";
  } catch (const Error& error) {
    EXPECT_NE(std::string(error.what()).find("rim.png: highlight at the sphere's rim"),
              std::string::npos)
        << error.what();
  }
}

TEST(MirrorSphereTest, NoSphereIsAClearError) {
  const Image empty(64, 48, 1);
  EXPECT_THROW(
      {
        try {
          FitSphereToMask(empty, "mask.png");
        } catch (const Error& error) {
          EXPECT_NE(std::string(error.what()).find("mask.png: sphere not found"),
                    std::string::npos);
          throw;
        }
      },
      Error);
  std::vector<Image> images(3, Image(64, 48, 3));
  EXPECT_THROW(
      CalibrateLightsFromMirrorSphere(images, SphereImageNames(3), std::nullopt, {}, "dark"),
      Error);
}

TEST(MirrorSphereTest, CameraIntrinsicsFile) {
  testing::TempDir dir;
  testing::WriteFile(dir / "K.txt", "3772.077 0 305.875\n0 3759.005 255.125\n0 0 1\n");
  const CameraIntrinsics k = ReadCameraIntrinsics(dir / "K.txt");
  EXPECT_DOUBLE_EQ(k.fx, 3772.077);
  EXPECT_DOUBLE_EQ(k.fy, 3759.005);
  EXPECT_DOUBLE_EQ(k.cx, 305.875);
  EXPECT_DOUBLE_EQ(k.cy, 255.125);
  testing::WriteFile(dir / "bad.txt", "1 0 2\n0 x 3\n");
  EXPECT_THROW(ReadCameraIntrinsics(dir / "bad.txt"), Error);
}

// Without its mask, the chrome sphere's dark body gives Hough a faint outline: the calibration
// must refuse it rather than return lights from a wrong circle.
TEST(MirrorSphereRealTest, UwChromeWithoutMaskIsRefusedNotWrong) {
  PHOTOMAT_TEST_DATA_OR_SKIP(folder, "uw-psm");
  std::vector<Image> images;
  for (int i = 0; i < 12; ++i) {
    images.push_back(ReadImage(folder / "chrome" / fmt::format("chrome.{}.png", i)).image);
  }
  try {
    CalibrateLightsFromMirrorSphere(images, SphereImageNames(12), std::nullopt, {}, "chrome");
    FAIL() << "expected an error";
  } catch (const Error& error) {
    EXPECT_NE(std::string(error.what()).find("chrome: sphere not found reliably"),
              std::string::npos)
        << error.what();
  }
}

}  // namespace
}  // namespace photomat
