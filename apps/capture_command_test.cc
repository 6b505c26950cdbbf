// End-to-end tests of `photomat capture` and `photomat devices`: each runs the built executable.
// The camera is a set on disk replayed as one (folder:PATH); the V4L2 backend on its emulated
// device is tested in capture/capture_session_test.cc.
#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include <filesystem>

#include "capture/io/load_photometric_set.h"
#include "capture/live/capture_session.h"
#include "core/atomic_file.h"
#include "tests/support/test_support.h"

namespace photomat {
namespace {

using testing::RunPhotomat;
using testing::RunResult;

using ::testing::HasSubstr;

TEST(CaptureCommandTest, DryRunKilledMidwayResumesToTheSameSet) {
  testing::TempDir dir;
  const std::string source = (dir / "source").string();
  const std::string out = (dir / "out").string();
  const std::string log = (dir / "switches.log").string();
  ASSERT_EQ(RunPhotomat("generate --size 24x16 --pattern bumps --out " + source).exit_code, 0);
  // The thesis's slant-45 ring: 12 of the generated set's 36 lights.
  std::string ring;
  for (int tilt = 0; tilt < 360; tilt += 30) ring += "45," + std::to_string(tilt) + ";";

  // The light command kills photomat when asked for light 5.
  const RunResult killed = RunPhotomat("capture --device folder:" + source + " --lights '" + ring +
                                       "' --frames 2 --settle-ms 0 --out " + out +
                                       " --controller 'command:echo {n} >> " + log +
                                       "; [ {n} -ne 5 ] || kill -KILL $PPID'");
  EXPECT_EQ(killed.exit_code, 128 + 9) << killed.output;  // the shell reports SIGKILL
  EXPECT_EQ(ReadCaptureSession(dir / "out" / kCaptureSessionName).captured.size(), 4u);

  // Starting over in the same folder is refused; resuming finishes.
  const RunResult again = RunPhotomat("capture --device folder:" + source +
                                      " --lights thesis --controller command:true --out " + out);
  EXPECT_EQ(again.exit_code, 1);
  EXPECT_THAT(again.output, HasSubstr("holds a capture session (4 of 12 lights taken)"));
  const RunResult resumed =
      RunPhotomat("capture --device folder:" + source + " --controller 'command:echo {n} >> " +
                  log + "' --out " + out + " --resume");
  ASSERT_EQ(resumed.exit_code, 0) << resumed.output;
  EXPECT_THAT(
      resumed.output,
      HasSubstr("captured 12 of 12 lights (4 already on disk) in FLOAT 24x16 from folder:"));

  // The switches: dark (0), lights 1..5 (killed at 5), then 5..12 and all off again.
  std::string expected = "0\n";
  for (int n = 1; n <= 5; ++n) expected += std::to_string(n) + "\n";
  for (int n = 5; n <= 12; ++n) expected += std::to_string(n) + "\n";
  expected += "0\n";
  EXPECT_EQ(ReadTextFile(log), expected);

  // The captured set is the replayed ring (images 12..23 of the thesis grid), image for image.
  const PhotometricSet original = LoadPhotometricSet(source).set;
  const PhotometricSet captured = LoadPhotometricSet(out).set;
  ASSERT_EQ(captured.size(), 12);
  for (int i = 0; i < 12; ++i) {
    const int j = 12 + i;
    EXPECT_LT(captured.light(i).AngleToDegrees(original.light(j)), 1e-6);
    for (std::size_t k = 0; k < original.image(j).values().size(); ++k) {
      ASSERT_EQ(captured.image(i).values()[k], original.image(j).values()[k]) << "image " << i;
    }
  }
}

TEST(CaptureCommandTest, ErrorsAreOneLine) {
  testing::TempDir dir;
  const std::string source = (dir / "source").string();
  ASSERT_EQ(RunPhotomat("generate --size 16x16 --out " + source).exit_code, 0);
  const RunResult missing = RunPhotomat(
      "capture --device /dev/video-nope --lights thesis "
      "--controller command:true --out " +
      (dir / "a").string());
  EXPECT_EQ(missing.exit_code, 1);
  EXPECT_THAT(missing.output, HasSubstr("photomat: error: /dev/video-nope: cannot open the video "
                                        "device: No such file or directory"));
  const RunResult format = RunPhotomat("capture --device folder:" + source +
                                       " --lights thesis --controller command:true --format YUYV "
                                       "--out " +
                                       (dir / "b").string());
  EXPECT_EQ(format.exit_code, 1);
  EXPECT_THAT(format.output, HasSubstr("unsupported format YUYV 0x0"));
  const RunResult controller = RunPhotomat("capture --device folder:" + source +
                                           " --lights thesis --controller 'command:exit 1' "
                                           "--controller-retries 1 --out " +
                                           (dir / "c").string());
  EXPECT_EQ(controller.exit_code, 1);
  EXPECT_THAT(controller.output, HasSubstr("light controller not answering: command `exit 1` for "
                                           "all lights off failed: exit status 1 (after 2 "
                                           "attempts)"));
  const RunResult resume = RunPhotomat("capture --device folder:" + source +
                                       " --controller command:true --format FLOAT:8x8 --resume "
                                       "--out " +
                                       (dir / "c").string());
  EXPECT_EQ(resume.exit_code, 1);
  EXPECT_THAT(resume.output, HasSubstr("camera format changed: the session was captured in FLOAT "
                                       "16x16, resuming asked for FLOAT 8x8"));
  const RunResult plan = RunPhotomat("capture --device folder:" + source +
                                     " --controller manual --out " + (dir / "d").string());
  EXPECT_EQ(plan.exit_code, 1);
  EXPECT_THAT(plan.output, HasSubstr("--lights is required (except with --resume)"));
}

TEST(CaptureCommandTest, DevicesListsBothBackends) {
  const RunResult devices = RunPhotomat("devices");
  ASSERT_EQ(devices.exit_code, 0) << devices.output;
  EXPECT_THAT(devices.output, HasSubstr("V4L2 (--device /dev/videoN):"));
  EXPECT_THAT(devices.output, HasSubstr("libcamera v0."));
  std::error_code ec;
  bool has_video = false;
  for (const auto& entry : std::filesystem::directory_iterator("/dev", ec)) {
    has_video |= entry.path().filename().string().rfind("video", 0) == 0;
  }
  if (!has_video) {
    EXPECT_THAT(devices.output, HasSubstr("no video capture device under /dev"));
  }
  for (const char* command : {"capture", "devices"}) {
    const RunResult help = RunPhotomat(std::string(command) + " --help");
    EXPECT_EQ(help.exit_code, 0);
    EXPECT_THAT(help.output, HasSubstr("Usage"));
  }
}

}  // namespace
}  // namespace photomat
