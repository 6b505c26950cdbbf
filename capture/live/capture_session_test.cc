#include "capture/live/capture_session.h"

#include <fmt/format.h>
#include <gmock/gmock.h>
#include <gtest/gtest.h>
#include <linux/videodev2.h>
#include <signal.h>
#include <unistd.h>

#include <cmath>
#include <functional>

#include "capture/io/capture_manifest.h"
#include "capture/io/load_photometric_set.h"
#include "capture/live/testing/emulated_v4l2_device.h"
#include "capture/live/testing/reported_exposure_source.h"
#include "capture/live/testing/synthetic_studio.h"
#include "capture/live/v4l2_frame_source.h"
#include "core/error.h"
#include "core/image_io.h"
#include "tests/support/test_support.h"

namespace photomat {
namespace {

namespace fs = std::filesystem;
using testing::EmulatedCameraOptions;
using testing::EmulatedV4l2Device;
using ::testing::HasSubstr;
using testing::SyntheticStudio;

constexpr int kSize = 48;
constexpr const char* kDevice = "/dev/video-emulated";

SyntheticMaterial Material() {
  SyntheticMaterialOptions options;
  options.width = kSize;
  options.height = kSize;
  options.seed = 11;
  return MakeSyntheticMaterial(options);
}

// A dome with the thesis's 36 lights, a command light controller that writes the light number to
// a file, and the emulated camera looking at a synthetic sample lit by the light in that file.
// The death tests run "threadsafe": their child is a fresh run of the test binary (a forked copy
// of a process that already wrote an EXR would wait forever on OpenEXR's pool threads, which a
// fork does not copy) that re-runs the test up to the death statement. The rig's folder comes
// through the environment so that parent and child share it.
constexpr const char* kRigFolderVariable = "PHOTOMAT_CAPTURE_TEST_RIG";

fs::path RigFolder(std::optional<testing::TempDir>& owned) {
  if (const char* inherited = std::getenv(kRigFolderVariable)) return inherited;
  owned.emplace();
  setenv(kRigFolderVariable, owned->path().c_str(), 1);
  return owned->path();
}

struct Rig {
  ~Rig() {
    if (owned) unsetenv(kRigFolderVariable);
  }

  std::optional<testing::TempDir> owned;
  fs::path dir = RigFolder(owned);
  fs::path out = dir / "set";
  fs::path light_file = dir / "light";
  SyntheticStudio studio{Material(), ThesisLightGrid()};

  EmulatedCameraOptions Camera(std::uint32_t fourcc = V4L2_PIX_FMT_RGB24) {
    return studio.Camera(light_file, fourcc);
  }
  std::string Command() const { return "echo {n} > " + light_file.string(); }
  CaptureSettings Settings() const { return testing::QuickCaptureSettings(); }
  LightPlan Plan() const { return {ThesisLightGrid(), "thesis"}; }

  // Resumes with a healthy camera and controller.
  CaptureSummary Resume() {
    EmulatedV4l2Device device(Camera());
    V4l2FrameSource source(kDevice, device);
    CommandLightController controller(Command());
    return ResumeCaptureSession(source, controller, out, std::nullopt);
  }
};

double Rms(const Image& a, const Image& b) {
  double sum = 0.0;
  for (std::size_t i = 0; i < a.values().size(); ++i) {
    const double d = a.values()[i] - b.values()[i];
    sum += d * d;
  }
  return std::sqrt(sum / a.values().size());
}

// Every light of the plan is on disk exactly once, in order, and each image shows its own light
// (dark-subtracted): nothing lost, duplicated or taken under the wrong light.
void ExpectCompleteSet(Rig& rig) {
  const CaptureManifest manifest = ReadCaptureManifest(rig.out / kCaptureManifestName);
  const CaptureSessionState state = ReadCaptureSession(rig.out / kCaptureSessionName);
  const auto lights = ThesisLightGrid();
  ASSERT_EQ(manifest.images.size(), lights.size());
  ASSERT_TRUE(state.complete());
  for (std::size_t i = 0; i < lights.size(); ++i) {
    EXPECT_EQ(manifest.images[i].file, fmt::format("img_{:03}.exr", i));
    EXPECT_LT(manifest.images[i].light.AngleToDegrees(lights[i]), 1e-9);
    EXPECT_EQ(state.captured[i].number, static_cast<int>(i) + 1);
    EXPECT_EQ(state.captured[i].frames.size(), 3u);
    const Image image = ReadImage(rig.out / manifest.images[i].file).image;
    int nearest = 0;
    double best = 1e9;
    for (int n = 1; n <= static_cast<int>(lights.size()); ++n) {
      const double rms = Rms(image, rig.studio.Render(n));
      if (rms < best) best = rms, nearest = n;
    }
    EXPECT_EQ(nearest, static_cast<int>(i) + 1) << "image " << i << " shows light " << nearest;
    EXPECT_LT(best, 0.004) << "image " << i;
  }
  // No other image files and no temporary files are left.
  int files = 0;
  for (const auto& entry : fs::directory_iterator(rig.out)) {
    EXPECT_EQ(entry.path().filename().string().find(".tmp"), std::string::npos) << entry.path();
    ++files;
  }
  EXPECT_EQ(files, 36 + 3);  // images, dark.exr, manifest.json, capture_session.json
}

std::string ErrorOf(const std::function<void()>& f) {
  try {
    f();
  } catch (const Error& e) {
    return e.what();
  }
  return "no error";
}

TEST(CaptureSessionDeathTest, KilledAfterTwentyLightsResumesToTheWholeSet) {
  GTEST_FLAG_SET(death_test_style, "threadsafe");
  Rig rig;
  // The light controller kills the capture process when asked for light 21: a power cut.
  EXPECT_EXIT(
      {
        EmulatedV4l2Device device(rig.Camera());
        V4l2FrameSource source(kDevice, device);
        CommandLightController controller(rig.Command() + "; [ {n} -ne 21 ] || kill -KILL $PPID");
        RunCaptureSession(source, controller, rig.out, rig.Plan(), rig.Settings());
        _exit(0);
      },
      ::testing::KilledBySignal(SIGKILL), "");
  const CaptureSessionState interrupted = ReadCaptureSession(rig.out / kCaptureSessionName);
  EXPECT_EQ(interrupted.captured.size(), 20u);
  EXPECT_EQ(ReadCaptureManifest(rig.out / kCaptureManifestName).images.size(), 20u);
  EXPECT_EQ(LoadPhotometricSet(rig.out).set.size(), 20);  // a loadable set at every moment

  const CaptureSummary resumed = rig.Resume();
  EXPECT_EQ(resumed.lights_before, 20);
  EXPECT_EQ(resumed.lights_taken, 16);
  ExpectCompleteSet(rig);

  // Within each run, every light averaged its own frames: sequence numbers strictly increase.
  const CaptureSessionState state = ReadCaptureSession(rig.out / kCaptureSessionName);
  for (auto [first, last] : {std::pair{0, 20}, std::pair{20, 36}}) {
    std::uint64_t previous = 0;
    bool any = false;
    for (int i = first; i < last; ++i) {
      for (std::uint64_t sequence : state.captured[i].frames) {
        if (any) {
          EXPECT_GT(sequence, previous) << "light " << i + 1;
        }
        previous = sequence;
        any = true;
      }
    }
  }
}

TEST(CaptureSessionTest, DeviceGoneMidStreamIsAnErrorAndTheFolderResumes) {
  Rig rig;
  auto camera = rig.Camera();
  camera.disconnect_after_frames = 60;
  EmulatedV4l2Device device(camera);
  V4l2FrameSource source(kDevice, device);
  CommandLightController controller(rig.Command());
  EXPECT_THAT(
      ErrorOf([&] { RunCaptureSession(source, controller, rig.out, rig.Plan(), rig.Settings()); }),
      HasSubstr("/dev/video-emulated: device disconnected while streaming"));
  const std::size_t taken = ReadCaptureSession(rig.out / kCaptureSessionName).captured.size();
  EXPECT_GT(taken, 0u);
  EXPECT_LT(taken, 36u);
  EXPECT_EQ(rig.Resume().lights_before, static_cast<int>(taken));
  ExpectCompleteSet(rig);
}

TEST(CaptureSessionTest, FrameTimeOutIsAnErrorAndTheFolderResumes) {
  Rig rig;
  auto camera = rig.Camera();
  camera.stall_after_frames = 50;
  EmulatedV4l2Device device(camera);
  V4l2FrameSource source(kDevice, device);
  CommandLightController controller(rig.Command());
  EXPECT_THAT(
      ErrorOf([&] { RunCaptureSession(source, controller, rig.out, rig.Plan(), rig.Settings()); }),
      HasSubstr("/dev/video-emulated: frame time-out: no frame within 300 ms"));
  rig.Resume();
  ExpectCompleteSet(rig);
}

TEST(CaptureSessionTest, UnsupportedFormatIsAnErrorAndAChangedFormatOnResumeIsRefused) {
  Rig rig;
  {
    EmulatedV4l2Device device(rig.Camera(V4L2_PIX_FMT_NV12));
    V4l2FrameSource source(kDevice, device);
    CommandLightController controller(rig.Command());
    EXPECT_THAT(ErrorOf([&] {
                  RunCaptureSession(source, controller, rig.out, rig.Plan(), rig.Settings());
                }),
                HasSubstr("unsupported format: the device offers NV12 and photomat decodes only"));
    EXPECT_FALSE(fs::exists(rig.out / kCaptureSessionName));  // nothing half-started
  }
  {  // Start for real, stopped by a controller that gives up at light 4.
    EmulatedV4l2Device device(rig.Camera());
    V4l2FrameSource source(kDevice, device);
    CommandLightController controller(rig.Command() + "; [ {n} -ne 4 ]",
                                      {std::chrono::milliseconds(1000), 0});
    EXPECT_THROW(RunCaptureSession(source, controller, rig.out, rig.Plan(), rig.Settings()), Error);
  }
  {  // The same camera now streaming another format: refused.
    EmulatedV4l2Device device(rig.Camera(V4L2_PIX_FMT_YUYV));
    V4l2FrameSource source(kDevice, device);
    CommandLightController controller(rig.Command());
    EXPECT_THAT(ErrorOf([&] { ResumeCaptureSession(source, controller, rig.out, std::nullopt); }),
                HasSubstr("camera format changed: the session was captured in RGB3 48x48"));
  }
  {  // Asking for another format on resume: refused.
    EmulatedV4l2Device device(rig.Camera());
    V4l2FrameSource source(kDevice, device);
    CommandLightController controller(rig.Command());
    EXPECT_THAT(ErrorOf([&] {
                  ResumeCaptureSession(source, controller, rig.out,
                                       FrameFormat{PixelFormat::kRgb24, 32, 32});
                }),
                HasSubstr("resuming asked for RGB3 32x32"));
    EXPECT_THAT(ErrorOf([&] {
                  ResumeCaptureSession(source, controller, rig.out, std::nullopt,
                                       ReadLightPlan("30,0;45,0;60,0"));
                }),
                HasSubstr("the light plan differs from the session's"));
  }
  EXPECT_EQ(ReadCaptureSession(rig.out / kCaptureSessionName).captured.size(), 3u);
  EXPECT_EQ(rig.Resume().lights_before, 3);
  ExpectCompleteSet(rig);
}

TEST(CaptureSessionTest, ControllerNotAnsweringIsAnErrorAndTheFolderResumes) {
  Rig rig;
  EmulatedV4l2Device device(rig.Camera());
  V4l2FrameSource source(kDevice, device);
  // The dome hangs at light 6.
  CommandLightController controller(rig.Command() + "; [ {n} -ne 6 ] || sleep 10",
                                    {std::chrono::milliseconds(100), 1});
  EXPECT_THAT(
      ErrorOf([&] { RunCaptureSession(source, controller, rig.out, rig.Plan(), rig.Settings()); }),
      HasSubstr("light controller not answering"));
  EXPECT_EQ(ReadCaptureSession(rig.out / kCaptureSessionName).captured.size(), 5u);
  EXPECT_THAT(
      ErrorOf([&] { RunCaptureSession(source, controller, rig.out, rig.Plan(), rig.Settings()); }),
      HasSubstr("holds a capture session (5 of 36 lights taken): resume it"));
  rig.Resume();
  ExpectCompleteSet(rig);
}

// Calls `hook` before each switch (fault injection).
class HookedController final : public LightController {
 public:
  HookedController(LightController& inner, std::function<void(const LightState&)> hook)
      : inner_(inner), hook_(std::move(hook)) {}
  std::string name() const override { return inner_.name(); }
  void SwitchTo(const LightState& light) override {
    hook_(light);
    inner_.SwitchTo(light);
  }

 private:
  LightController& inner_;
  std::function<void(const LightState&)> hook_;
};

TEST(CaptureSessionDeathTest, DiskFullIsAnErrorAndTheFolderResumes) {
  GTEST_FLAG_SET(death_test_style, "threadsafe");
  Rig rig;
  // The disk fills up while light 11 is taken (a file-size limit in the child process).
  EXPECT_EXIT(
      {
        EmulatedV4l2Device device(rig.Camera());
        V4l2FrameSource source(kDevice, device);
        CommandLightController command(rig.Command());
        HookedController controller(command, [](const LightState& light) {
          if (light.number == 11) testing::LimitFileSize(4000);
        });
        try {
          RunCaptureSession(source, controller, rig.out, rig.Plan(), rig.Settings());
        } catch (const Error& e) {
          std::fprintf(stderr, "%s\n", e.what());
          _exit(std::string(e.what()).find("img_010.exr") != std::string::npos ? 0 : 2);
        }
        _exit(1);
      },
      ::testing::ExitedWithCode(0), "img_010.exr");
  EXPECT_EQ(ReadCaptureSession(rig.out / kCaptureSessionName).captured.size(), 10u);
  EXPECT_FALSE(fs::exists(rig.out / "img_010.exr"));
  rig.Resume();
  ExpectCompleteSet(rig);
}

TEST(CaptureSessionTest, ExposureBracketingMergesToLinearHdr) {
  testing::TempDir dir;
  const std::vector<LightDirection> lights = ReadLightPlan("30,0;45,120;60,240").lights;
  // Bright enough to clip at the base exposure.
  SyntheticStudio studio(Material(), lights, 4.0);
  const fs::path light_file = dir / "light";
  EmulatedCameraOptions camera;
  camera.fourccs = {V4L2_PIX_FMT_Y16};
  camera.width = camera.height = kSize;
  camera.scene = studio.SceneFromStateFile(light_file);
  CaptureSettings settings;
  settings.settle = std::chrono::milliseconds(2);
  settings.frame_timeout = std::chrono::milliseconds(300);
  settings.controls.exposure_us = 10000.0;
  CommandLightController controller("echo {n} > " + light_file.string());

  const auto run = [&](const fs::path& out, std::vector<double> bracket) {
    EmulatedV4l2Device device(camera);
    V4l2FrameSource source(kDevice, device);
    settings.bracket = std::move(bracket);
    return RunCaptureSession(source, controller, out, {lights, "list"}, settings);
  };
  const CaptureSummary single = run(dir / "single", {});
  EXPECT_GT(single.clipped_pixels, 100u);  // clipped at one exposure, and counted
  const CaptureSummary hdr = run(dir / "hdr", {0.25, 1.0});
  EXPECT_EQ(hdr.clipped_pixels, 0u);
  EXPECT_TRUE(fs::exists(dir / "hdr" / "dark_0.exr"));
  EXPECT_TRUE(fs::exists(dir / "hdr" / "dark_1.exr"));
  const LoadedSet set = LoadPhotometricSet(dir / "hdr");
  for (int i = 0; i < 3; ++i) {
    const Image& scene = studio.Render(i + 1);
    const Image& image = set.set.image(i);
    double worst = 0.0, brightest = 0.0;
    for (int y = 0; y < kSize; ++y) {
      for (int x = 0; x < kSize; ++x) {
        const double grey = (scene.at(x, y, 0) + scene.at(x, y, 1) + scene.at(x, y, 2)) / 3;
        worst = std::max(worst, std::abs(image.at(x, y, 0) - grey));
        brightest = std::max(brightest, static_cast<double>(image.at(x, y, 0)));
      }
    }
    EXPECT_LT(worst, 1e-3) << "light " << i + 1 << " at (5, 5): " << image.at(5, 5, 0) << " vs "
                           << (scene.at(5, 5, 0) + scene.at(5, 5, 1) + scene.at(5, 5, 2)) / 3;
    EXPECT_GT(brightest, 1.2);  // beyond the base exposure's full scale
  }
}

TEST(CaptureSessionTest, ExposureMatchesWithinOnePercentOrFiftyMicroseconds) {
  EXPECT_TRUE(ExposureMatches(10000, 10000));
  EXPECT_TRUE(ExposureMatches(10000, 10099));  // 1 %: line-time quantisation
  EXPECT_FALSE(ExposureMatches(10000, 10101));
  EXPECT_FALSE(ExposureMatches(10000, 9899));
  EXPECT_TRUE(ExposureMatches(1000, 1049));  // 50 us: one line, V4L2's rounding to 100 us
  EXPECT_FALSE(ExposureMatches(1000, 1051));
  EXPECT_FALSE(ExposureMatches(2500, 10000));  // bracket steps are far apart
}

// The largest difference of the captured grey image of light `number` from the studio's truth
// (the mean of its channels), in units of the base exposure.
double WorstErrorFromTruth(SyntheticStudio& studio, const Image& image, int number) {
  const Image& scene = studio.Render(number);
  double worst = 0.0;
  for (int y = 0; y < kSize; ++y) {
    for (int x = 0; x < kSize; ++x) {
      const double grey = (scene.at(x, y, 0) + scene.at(x, y, 1) + scene.at(x, y, 2)) / 3;
      worst = std::max(worst, std::abs(image.at(x, y, 0) - grey));
    }
  }
  return worst;
}

// A driver that applies each exposure change two frames late, under a bracket {0.25, 1} with two
// frames per exposure: the frames that come after the settle time still have the previous step's
// exposure.
struct LateExposureBracket {
  testing::TempDir dir;
  std::vector<LightDirection> lights = ReadLightPlan("30,0;45,120;60,240").lights;
  SyntheticStudio studio{Material(), lights, 4.0};  // clips at the base exposure
  fs::path light_file = dir / "light";
  EmulatedCameraOptions camera;
  CaptureSettings settings;

  LateExposureBracket() {
    camera.fourccs = {V4L2_PIX_FMT_Y16};
    camera.width = camera.height = kSize;
    camera.scene = studio.SceneFromStateFile(light_file);
    camera.exposure_delay_frames = 2;
    settings.frames_per_light = 2;
    settings.settle = std::chrono::milliseconds(2);
    settings.frame_timeout = std::chrono::milliseconds(300);
    settings.controls.exposure_us = 10000.0;
    settings.bracket = {0.25, 1.0};
  }

  struct Result {
    CaptureSummary summary;
    int frames_kept = 0;
    int frames_at_another_exposure = 0;  // kept, by the device's record of what each frame had
    double worst_error = 0.0;            // over the lights, from the truth
  };

  // Captures into `out` from the emulated camera, which reports each frame's exposure or not
  // (plain V4L2: the session settles by timestamp alone).
  Result Run(const fs::path& out, bool reports_exposure) {
    EmulatedV4l2Device device(camera);
    V4l2FrameSource v4l2(kDevice, device);
    testing::ReportedExposureSource reporting(v4l2, device);
    FrameSource& source = reports_exposure ? static_cast<FrameSource&>(reporting) : v4l2;
    CommandLightController controller("echo {n} > " + light_file.string());
    Result result;
    result.summary = RunCaptureSession(source, controller, out, {lights, "list"}, settings);
    const CaptureSessionState state = ReadCaptureSession(out / kCaptureSessionName);
    const LoadedSet set = LoadPhotometricSet(out);
    const std::size_t k = static_cast<std::size_t>(settings.frames_per_light);
    for (std::size_t i = 0; i < state.captured.size(); ++i) {
      const std::vector<std::uint64_t>& frames = state.captured[i].frames;
      for (std::size_t f = 0; f < frames.size(); ++f) {
        const double requested = *settings.controls.exposure_us * settings.bracket[f / k];
        ++result.frames_kept;
        if (device.FrameExposureUs(frames[f]) != requested) ++result.frames_at_another_exposure;
      }
      result.worst_error = std::max(
          result.worst_error,
          WorstErrorFromTruth(studio, set.set.image(static_cast<int>(i)), static_cast<int>(i) + 1));
    }
    return result;
  }
};

TEST(CaptureSessionTest, BracketingKeepsOnlyFramesThatHadTheRequestedExposure) {
  LateExposureBracket bracket;
  // Plain V4L2 reports no exposure: the session settles by timestamp, as before, and with a
  // driver two frames late every frame it keeps has the previous step's exposure.
  const auto settled = bracket.Run(bracket.dir / "by-timestamp", false);
  EXPECT_EQ(settled.frames_kept, 3 * 2 * 2);
  EXPECT_EQ(settled.frames_at_another_exposure, settled.frames_kept);
  EXPECT_EQ(settled.summary.exposure_mismatches, 0u);
  // The merge of wrong exposures is far from the truth: measured 1.71; bound 0.5 = 1.71 / 3.
  EXPECT_GT(settled.worst_error, 0.5);

  // A camera that reports each frame's exposure: the late frames are dropped and counted, two per
  // exposure change (two changes per light), and the HDR image is the truth.
  const auto checked = bracket.Run(bracket.dir / "by-exposure", true);
  EXPECT_EQ(checked.frames_kept, 3 * 2 * 2);
  EXPECT_EQ(checked.frames_at_another_exposure, 0);
  EXPECT_EQ(checked.summary.exposure_mismatches, 3u * 2 * 2);
  EXPECT_EQ(ReadCaptureSession(bracket.dir / "by-exposure" / kCaptureSessionName)
                .captured[0]
                .exposure_mismatches,
            4u);
  // measured 6.1e-5; bound 1e-4 = 6.1e-5 * 1.6
  EXPECT_LT(checked.worst_error, 1e-4);
}

TEST(CaptureSessionTest, ACameraThatNeverReachesTheExposureFailsNamingTheLight) {
  LateExposureBracket bracket;
  bracket.camera.max_applied_exposure_us = 5000.0;  // the frame time caps the exposure
  bracket.settings.dark_frame = false;
  EXPECT_THAT(ErrorOf([&] { bracket.Run(bracket.dir / "capped", true); }),
              HasSubstr("/dev/video-emulated: light 1 of 3, exposure 2 of 2: the camera did not "
                        "reach the requested exposure of 10000 us in 30 frames (the last "
                        "reported 5000 us; tolerance 1 % or 50 us)"));
}

TEST(CaptureSessionTest, RefusesBadSettingsAndFoldersThatHoldASet) {
  Rig rig;
  EmulatedV4l2Device device(rig.Camera());
  V4l2FrameSource source(kDevice, device);
  CommandLightController controller(rig.Command());
  CaptureSettings settings = rig.Settings();
  settings.controls.exposure_us.reset();
  settings.bracket = {1, 4};
  EXPECT_THAT(
      ErrorOf([&] { RunCaptureSession(source, controller, rig.out, rig.Plan(), settings); }),
      HasSubstr("needs a base exposure"));
  settings = rig.Settings();
  settings.frames_per_light = 0;
  EXPECT_THROW(RunCaptureSession(source, controller, rig.out, rig.Plan(), settings), Error);
  testing::WriteFile(rig.out / kCaptureManifestName, "{}");
  EXPECT_THAT(
      ErrorOf([&] { RunCaptureSession(source, controller, rig.out, rig.Plan(), rig.Settings()); }),
      HasSubstr("already holds a photometric set"));
  EXPECT_THAT(ErrorOf([&] { ResumeCaptureSession(source, controller, rig.dir / "x", {}); }),
              HasSubstr("no capture session to resume"));
}

}  // namespace
}  // namespace photomat
