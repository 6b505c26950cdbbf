#include "capture/live/v4l2_frame_source.h"

#include <gmock/gmock.h>
#include <gtest/gtest.h>
#include <linux/videodev2.h>

#include <chrono>
#include <cmath>

#include "capture/live/testing/emulated_v4l2_device.h"
#include "core/error.h"
#include "tests/support/test_support.h"

namespace photomat {
namespace {

using testing::EmulatedCameraOptions;
using testing::EmulatedV4l2Device;
using ::testing::HasSubstr;

// A smooth colour ramp, the same for every frame.
Image Ramp(int width, int height, double scale = 0.6) {
  Image image(width, height, 3);
  for (int y = 0; y < height; ++y) {
    for (int x = 0; x < width; ++x) {
      image.at(x, y, 0) = static_cast<float>(scale * x / (width - 1));
      image.at(x, y, 1) = static_cast<float>(scale * y / (height - 1));
      image.at(x, y, 2) = static_cast<float>(scale * 0.5);
    }
  }
  return image;
}

EmulatedCameraOptions Camera(std::vector<std::uint32_t> fourccs) {
  EmulatedCameraOptions options;
  options.fourccs = std::move(fourccs);
  options.width = 32;
  options.height = 24;
  options.dark_level = 0.0;
  options.dark_pattern = 0.0;
  options.scene = [] { return Ramp(32, 24); };
  return options;
}

std::string ErrorOf(const std::function<void()>& f) {
  try {
    f();
  } catch (const Error& e) {
    return e.what();
  }
  return "no error";
}

TEST(V4l2FrameSourceTest, ListsFormatsSizesAndControls) {
  EmulatedV4l2Device device(Camera({V4L2_PIX_FMT_YUYV, V4L2_PIX_FMT_NV12, V4L2_PIX_FMT_MJPEG}));
  V4l2FrameSource source("/dev/video-emulated", device);
  EXPECT_EQ(source.description(), "Emulated Camera (photomat-emul)");
  const auto formats = source.ListFormats();
  ASSERT_EQ(formats.size(), 3u);
  EXPECT_EQ(formats[0].code, "YUYV");
  EXPECT_EQ(formats[0].pixel_format, PixelFormat::kYuyv);
  EXPECT_EQ(formats[1].code, "NV12");
  EXPECT_EQ(formats[1].pixel_format, std::nullopt);  // listed, not decoded
  EXPECT_EQ(formats[2].sizes, (std::vector<std::pair<int, int>>{{32, 24}}));
  const auto controls = source.ListControls();
  std::vector<std::string> names;
  for (const auto& c : controls) names.push_back(c.name);
  EXPECT_THAT(names, ::testing::Contains("Exposure Time, Absolute"));
  EXPECT_THAT(names, ::testing::Contains("Gain"));
  EXPECT_EQ(source.DefaultFormat(), (FrameFormat{PixelFormat::kYuyv, 32, 24}));
}

class V4l2FormatTest : public ::testing::TestWithParam<PixelFormat> {};

TEST_P(V4l2FormatTest, StreamsFramesThatDecodeToTheScene) {
  auto options = Camera({V4l2FourCc(GetParam())});
  options.row_padding = 8;
  EmulatedV4l2Device device(options);
  {
    V4l2FrameSource source("/dev/video-emulated", device);
    EXPECT_EQ(source.SetFormat({GetParam(), 32, 24}), (FrameFormat{GetParam(), 32, 24}));
    source.SetManualControls({});
    source.Start();
    EXPECT_TRUE(device.streaming());
    const Image truth = Ramp(32, 24);
    std::uint64_t last_sequence = 0;
    for (int i = 0; i < 6; ++i) {  // more frames than buffers: they are requeued
      const Frame frame = source.Grab(std::chrono::milliseconds(500));
      if (i > 0) {
        EXPECT_EQ(frame.metadata.sequence, last_sequence + 1);
      }
      last_sequence = frame.metadata.sequence;
      ASSERT_EQ(frame.image.channels(), ChannelCount(GetParam()));
      double worst = 0.0;
      for (int y = 0; y < 24; ++y) {
        for (int x = 0; x < 32; ++x) {
          for (int c = 0; c < frame.image.channels(); ++c) {
            const double expected =
                frame.image.channels() == 1
                    ? (truth.at(x, y, 0) + truth.at(x, y, 1) + truth.at(x, y, 2)) / 3
                    : truth.at(x, y, c);
            worst = std::max(worst, std::abs(frame.image.at(x, y, c) - expected));
          }
        }
      }
      // YUYV shares chroma between the pixels of a pair: on this ramp, up to 0.05.
      EXPECT_LT(worst, GetParam() == PixelFormat::kY16 ? 1e-4 : 0.05);
      EXPECT_LE(frame.metadata.timestamp, std::chrono::steady_clock::now());
    }
  }
  // Destroying the source stops streaming, unmaps every buffer and closes the device.
  EXPECT_FALSE(device.streaming());
  EXPECT_EQ(device.mapped_buffers(), 0);
  EXPECT_EQ(device.open_handles(), 0);
}

INSTANTIATE_TEST_SUITE_P(SupportedFormats, V4l2FormatTest,
                         ::testing::Values(PixelFormat::kGrey, PixelFormat::kY16,
                                           PixelFormat::kYuyv, PixelFormat::kMjpeg,
                                           PixelFormat::kRgb24),
                         [](const auto& param_info) {
                           return std::string(ToString(param_info.param));
                         });

TEST(V4l2FrameSourceTest, ManualControlsTurnAutoModesOffAndSetExposureAndGain) {
  EmulatedV4l2Device device(Camera({V4L2_PIX_FMT_Y16}));
  V4l2FrameSource source("/dev/video-emulated", device);
  source.SetFormat({PixelFormat::kY16, 32, 24});
  EXPECT_NE(device.control(V4L2_CID_EXPOSURE_AUTO), V4L2_EXPOSURE_MANUAL);
  source.SetManualControls({5000.0, 150.0});
  EXPECT_EQ(device.control(V4L2_CID_EXPOSURE_AUTO), V4L2_EXPOSURE_MANUAL);
  EXPECT_EQ(device.control(V4L2_CID_AUTOGAIN), 0);
  EXPECT_EQ(device.control(V4L2_CID_AUTO_WHITE_BALANCE), 0);
  EXPECT_EQ(device.control(V4L2_CID_EXPOSURE_ABSOLUTE), 50);  // 100 us units
  EXPECT_EQ(device.control(V4L2_CID_GAIN), 150);
  // The signal follows: half the reference exposure times 1.5 gain = 0.75 of the scene.
  const Frame frame = source.Grab(std::chrono::milliseconds(500));
  // V4L2 reports no per-frame exposure: the control's value is not what a frame had.
  EXPECT_FALSE(frame.metadata.exposure_us.has_value());
  const double scene = (0.6 * 31 / 31 + 0.6 * 0 + 0.3) / 3;  // pixel (31, 0)
  EXPECT_NEAR(frame.image.at(31, 0, 0), 0.75 * scene, 1e-4);
  EXPECT_THAT(ErrorOf([&] {
                source.SetManualControls({20.0, std::nullopt});
              }),
              HasSubstr("below the V4L2 unit of 100 us"));
  EXPECT_THAT(ErrorOf([&] {
                source.SetManualControls({std::nullopt, 900.0});
              }),
              HasSubstr("setting the gain 900 is out of the device's range [0, 400]"));
}

TEST(V4l2FrameSourceTest, FramesAreSteadyOnlyWithTheAutoModesOff) {
  // The emulated camera rescales each frame while auto exposure, gain or white balance are on.
  const auto spread = [](V4l2FrameSource& source) {
    double low = 1e9, high = -1e9;
    for (int i = 0; i < 6; ++i) {
      const double v = source.Grab(std::chrono::milliseconds(500)).image.at(20, 10, 0);
      low = std::min(low, v);
      high = std::max(high, v);
    }
    return high - low;
  };
  EmulatedV4l2Device automatic(Camera({V4L2_PIX_FMT_Y16}));
  V4l2FrameSource wobbly("/dev/video-emulated", automatic);
  EXPECT_GT(spread(wobbly), 0.01);
  EmulatedV4l2Device manual(Camera({V4L2_PIX_FMT_Y16}));
  V4l2FrameSource steady("/dev/video-emulated", manual);
  steady.SetManualControls({});
  EXPECT_LT(spread(steady), 1e-6);
}

TEST(V4l2FrameSourceTest, MissingExposureControlIsAnError) {
  auto options = Camera({V4L2_PIX_FMT_GREY});
  options.has_exposure_control = false;
  EmulatedV4l2Device device(options);
  V4l2FrameSource source("/dev/video-emulated", device);
  EXPECT_THAT(ErrorOf([&] {
                source.SetManualControls({10000.0, std::nullopt});
              }),
              HasSubstr("no exposure control"));
}

TEST(V4l2FrameSourceTest, UnsupportedFormatsAreRefusedNamingWhatTheDeviceHas) {
  EmulatedV4l2Device device(Camera({V4L2_PIX_FMT_NV12, V4L2_PIX_FMT_H264}));
  V4l2FrameSource source("/dev/video-emulated", device);
  EXPECT_THAT(ErrorOf([&] { source.DefaultFormat(); }),
              HasSubstr("/dev/video-emulated: unsupported format: the device offers NV12, H264"));
  EXPECT_THAT(ErrorOf([&] {
                source.SetFormat({PixelFormat::kYuyv, 32, 24});
              }),
              HasSubstr("does not offer YUYV (it offers NV12, H264"));
  EXPECT_THAT(ErrorOf([&] { source.Start(); }), HasSubstr("unsupported format"));
}

TEST(V4l2FrameSourceTest, DeviceGoneMidStreamIsAnError) {
  auto options = Camera({V4L2_PIX_FMT_RGB24});
  options.disconnect_after_frames = 3;
  EmulatedV4l2Device device(options);
  V4l2FrameSource source("/dev/video-emulated", device);
  // The third frame comes whole (the device goes right after it); the next grab fails.
  for (int i = 0; i < 3; ++i) source.Grab(std::chrono::milliseconds(500));
  EXPECT_THAT(ErrorOf([&] { source.Grab(std::chrono::milliseconds(500)); }),
              HasSubstr("/dev/video-emulated: device disconnected while streaming"));
  EXPECT_THAT(ErrorOf([&] { source.Grab(std::chrono::milliseconds(500)); }),
              HasSubstr("/dev/video-emulated: device disconnected while streaming"));
}

TEST(V4l2FrameSourceTest, FrameTimeOutIsAnError) {
  auto options = Camera({V4L2_PIX_FMT_RGB24});
  options.stall_after_frames = 2;
  EmulatedV4l2Device device(options);
  V4l2FrameSource source("/dev/video-emulated", device);
  source.Grab(std::chrono::milliseconds(500));
  source.Grab(std::chrono::milliseconds(500));
  // The buffers exposed before the stall still come; then nothing does.
  std::string error;
  const auto start = std::chrono::steady_clock::now();
  for (int i = 0; i < 10 && error.empty(); ++i) {
    try {
      source.Grab(std::chrono::milliseconds(150));
    } catch (const Error& e) {
      error = e.what();
    }
  }
  EXPECT_THAT(error, HasSubstr("frame time-out: no frame within 150 ms"));
  EXPECT_LT(std::chrono::steady_clock::now() - start, std::chrono::seconds(2));
}

TEST(V4l2FrameSourceTest, OpeningWhatIsNotThereIsAnError) {
  EmulatedV4l2Device device(Camera({V4L2_PIX_FMT_RGB24}));
  EXPECT_THAT(ErrorOf([&] { V4l2FrameSource("/dev/video-missing", device); }),
              HasSubstr("/dev/video-missing: cannot open the video device: No such file or "
                        "directory"));
  LinuxV4l2Syscalls linux_calls;
  testing::TempDir dir;
  testing::WriteFile(dir / "video0", "not a device");
  EXPECT_THAT(ErrorOf([&] { V4l2FrameSource(dir / "video0", linux_calls); }),
              HasSubstr("VIDIOC_QUERYCAP (is it a V4L2 device?) failed"));
}

TEST(V4l2FrameSourceTest, ListsDevicesInAFolder) {
  testing::TempDir dir;
  LinuxV4l2Syscalls linux_calls;
  EXPECT_TRUE(ListV4l2Devices(linux_calls, dir.path()).empty());
  testing::WriteFile(dir / "video3", "");
  auto options = Camera({V4L2_PIX_FMT_GREY, V4L2_PIX_FMT_Y16});
  options.path = dir / "video3";
  EmulatedV4l2Device device(options);
  const auto devices = ListV4l2Devices(device, dir.path());
  ASSERT_EQ(devices.size(), 1u);
  EXPECT_EQ(devices[0].id, (dir / "video3").string());
  EXPECT_EQ(devices[0].error, "");
  ASSERT_EQ(devices[0].formats.size(), 2u);
  EXPECT_EQ(devices[0].formats[1].code, "Y16");
  EXPECT_EQ(device.open_handles(), 0);
}

}  // namespace
}  // namespace photomat
