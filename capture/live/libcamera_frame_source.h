#pragma once

#include <memory>
#include <string>
#include <vector>

#include "capture/live/frame_source.h"
#include "core/colour.h"

namespace photomat {

struct LibcameraOptions {
  // The stream role: a still-capture stream (processed, e.g. RGB888 / YUYV / MJPEG), or the raw
  // sensor stream. photomat decodes R8 (GREY), YUYV, MJPEG, RGB888 and BGR888; a raw stream works
  // when the sensor delivers one of them (monochrome sensors give R8), otherwise the configuration
  // is refused naming the formats the camera has.
  bool raw = false;
  int buffer_count = 4;
  ColourSpace eight_bit_encoding = ColourSpace::kSrgb;
};

// A camera through libcamera (CSI and machine-vision cameras): its own CameraManager, the camera
// acquired for the source's lifetime, one stream configured from the role, buffers from a
// FrameBufferAllocator mapped once, one request per buffer requeued after each frame, and the
// controls AeEnable and AwbEnable off with ExposureTime and AnalogueGain set when asked.
// libcamera allows one CameraManager per process: do not keep two sources (or a source and
// ListLibcameraCameras) alive at once.
class LibcameraFrameSource final : public FrameSource {
 public:
  // `camera` is a libcamera camera id or an index into the manager's list ("0"). Throws Error when
  // the manager cannot start, when there is no such camera (listing those there are), or when it
  // is in use.
  explicit LibcameraFrameSource(const std::string& camera, const LibcameraOptions& options = {});
  ~LibcameraFrameSource() override;
  LibcameraFrameSource(const LibcameraFrameSource&) = delete;
  LibcameraFrameSource& operator=(const LibcameraFrameSource&) = delete;

  std::string name() const override;
  std::vector<OfferedFormat> ListFormats() override;
  std::vector<CameraControl> ListControls() override;
  FrameFormat SetFormat(const FrameFormat& format) override;
  void SetManualControls(const ManualControls& controls) override;
  void SetExposure(double exposure_us) override;
  void Start() override;
  void Stop() override;
  Frame Grab(std::chrono::milliseconds timeout) override;

 private:
  class Impl;
  std::unique_ptr<Impl> impl_;
};

// Starts a camera manager and describes every camera it finds (empty when there is none). Throws
// Error when the manager cannot start.
std::vector<DeviceDescription> ListLibcameraCameras(const LibcameraOptions& options = {});

// The version of the libcamera library in use ("v0.0.3").
std::string LibcameraVersion();

}  // namespace photomat
