#pragma once

#include <filesystem>
#include <optional>
#include <string>
#include <vector>

#include "capture/live/frame_source.h"
#include "core/photometric_set.h"

namespace photomat {

// A photometric set on disk acting as a camera, for dry runs of a capture (plan, controller,
// output, resume) without hardware. When the session switches a light, the source serves the
// set's image whose light is nearest to it (within `max_light_error_degrees`, else an Error: the
// set was not taken under this plan); with all lights off it serves a black frame. Its one format
// is FLOAT at the set's size. Exposure and gain are recorded in the frame metadata but do not
// change the images.
class FolderFrameSource final : public FrameSource {
 public:
  // Loads the set (any input LoadPhotometricSet reads); throws Error naming it.
  explicit FolderFrameSource(std::filesystem::path path, double max_light_error_degrees = 0.5);

  std::string name() const override { return "folder:" + path_.string(); }
  std::vector<OfferedFormat> ListFormats() override;
  std::vector<CameraControl> ListControls() override { return {}; }
  FrameFormat SetFormat(const FrameFormat& format) override;
  FrameFormat DefaultFormat() override;
  void SetManualControls(const ManualControls& controls) override;
  void SetExposure(double exposure_us) override { exposure_us_ = exposure_us; }
  void Start() override {}
  void Stop() override {}
  Frame Grab(std::chrono::milliseconds timeout) override;
  void LightChanged(const LightState& light) override;

 private:
  std::filesystem::path path_;
  double max_light_error_degrees_;
  PhotometricSet set_;
  std::optional<int> current_;  // image index; nullopt = lights off
  std::uint64_t sequence_ = 0;
  std::optional<double> exposure_us_;
  std::optional<double> gain_;
};

}  // namespace photomat
