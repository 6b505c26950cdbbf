// Live capture feeding the fits (capture/live + represent): a set recorded from the emulated V4L2
// camera, looking at a synthetic sample under the thesis's 36 lights, fits with Gradient to the
// generator's normals.
#include <gtest/gtest.h>
#include <linux/videodev2.h>

#include <cstdio>

#include "capture/io/load_photometric_set.h"
#include "capture/live/capture_session.h"
#include "capture/live/light_controller.h"
#include "capture/live/testing/emulated_v4l2_device.h"
#include "capture/live/testing/synthetic_studio.h"
#include "capture/live/v4l2_frame_source.h"
#include "represent/fitting/fit.h"
#include "represent/model/normal_error.h"
#include "tests/support/test_support.h"

namespace photomat {
namespace {

TEST(LiveCaptureFitTest, AnEmulatedCaptureFitsTheTruth) {
  SyntheticMaterialOptions material;
  material.width = material.height = 48;
  material.seed = 11;
  testing::SyntheticStudio studio(MakeSyntheticMaterial(material), ThesisLightGrid());
  testing::TempDir dir;
  const std::filesystem::path light_file = dir / "light";
  testing::EmulatedV4l2Device device(studio.Camera(light_file, V4L2_PIX_FMT_RGB24));
  V4l2FrameSource source("/dev/video-emulated", device);
  CommandLightController controller("echo {n} > " + light_file.string());
  RunCaptureSession(source, controller, dir / "set", {ThesisLightGrid(), "thesis"},
                    testing::QuickCaptureSettings());

  const LoadedSet loaded = LoadPhotometricSet(dir / "set");
  ASSERT_EQ(loaded.set.size(), 36);
  const NormalErrorStats stats =
      CompareNormals(*EstimateNormals(Fit(loaded.set, Method::Parse("gradient"))),
                     studio.material().normals, Mask(48, 48, true));
  RecordProperty("mean_normal_error_degrees", std::to_string(stats.mean_degrees));
  std::printf("gradient normals vs truth: mean %.3f deg, median %.3f deg, max %.3f deg\n",
              stats.mean_degrees, stats.median_degrees, stats.max_degrees);
  // Measured 0.060 degrees mean (seeded noise, deterministic); bound 0.09 = 0.060 * 1.5.
  EXPECT_LT(stats.mean_degrees, 0.09);
}

}  // namespace
}  // namespace photomat
