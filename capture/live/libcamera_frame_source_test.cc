#include "capture/live/libcamera_frame_source.h"

#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include <filesystem>

#include "core/error.h"

namespace photomat {
namespace {

using ::testing::HasSubstr;

// No camera exists on the build and CI machines, so these tests cover what libcamera allows
// without one: the camera manager starts and stops, lists cameras, and a camera that is not there
// is a clear error. Streaming from a real camera is not covered here (see README, "Capture").

bool MachineHasMediaDevices() {
  std::error_code ec;
  for (const auto& entry : std::filesystem::directory_iterator("/dev", ec)) {
    if (entry.path().filename().string().rfind("media", 0) == 0) return true;
  }
  return false;
}

TEST(LibcameraFrameSourceTest, ManagerStartsAndListsCameras) {
  EXPECT_EQ(LibcameraVersion().rfind("v0.", 0), 0u) << LibcameraVersion();
  const std::vector<DeviceDescription> cameras = ListLibcameraCameras();
  for (const DeviceDescription& camera : cameras) {
    EXPECT_EQ(camera.id.rfind("libcamera:", 0), 0u);
  }
  if (!MachineHasMediaDevices()) {
    EXPECT_TRUE(cameras.empty());
  }
  // Twice in a row: the manager is stopped and destroyed cleanly each time.
  EXPECT_EQ(ListLibcameraCameras().size(), cameras.size());
}

TEST(LibcameraFrameSourceTest, AMissingCameraIsAClearError) {
  try {
    LibcameraFrameSource source("no-such-camera");
    FAIL() << "opened a camera that does not exist";
  } catch (const Error& e) {
    EXPECT_THAT(e.what(), HasSubstr("libcamera:no-such-camera: no such camera (libcamera v0."));
    if (!MachineHasMediaDevices()) {
      EXPECT_THAT(e.what(), HasSubstr("finds no camera)"));
    }
  }
  if (!MachineHasMediaDevices()) {
    EXPECT_THROW(LibcameraFrameSource("0"), Error);  // index 0 of an empty list
  }
}

}  // namespace
}  // namespace photomat
