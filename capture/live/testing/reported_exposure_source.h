#pragma once

#include <string>
#include <vector>

#include "capture/live/frame_source.h"
#include "capture/live/testing/emulated_v4l2_device.h"

namespace photomat::testing {

// A camera that reports each frame's real exposure, as libcamera does: `source` (a V4l2FrameSource
// on `device`) with every frame's FrameMetadata::exposure_us filled from what the emulated sensor
// used for it. V4L2 has no per-frame exposure, so the report comes from the device's own record;
// without this wrapper the session sees a plain V4L2 camera. Both must outlive it.
class ReportedExposureSource final : public FrameSource {
 public:
  ReportedExposureSource(FrameSource& source, const EmulatedV4l2Device& device)
      : source_(source), device_(device) {}

  std::string name() const override { return source_.name(); }
  std::vector<OfferedFormat> ListFormats() override { return source_.ListFormats(); }
  std::vector<CameraControl> ListControls() override { return source_.ListControls(); }
  FrameFormat SetFormat(const FrameFormat& format) override { return source_.SetFormat(format); }
  FrameFormat DefaultFormat() override { return source_.DefaultFormat(); }
  void SetManualControls(const ManualControls& controls) override {
    source_.SetManualControls(controls);
  }
  void SetExposure(double exposure_us) override { source_.SetExposure(exposure_us); }
  void Start() override { source_.Start(); }
  void Stop() override { source_.Stop(); }
  Frame Grab(std::chrono::milliseconds timeout) override;
  void LightChanged(const LightState& light) override { source_.LightChanged(light); }

 private:
  FrameSource& source_;
  const EmulatedV4l2Device& device_;
};

}  // namespace photomat::testing
