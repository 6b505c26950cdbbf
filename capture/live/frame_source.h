#pragma once

#include <chrono>
#include <cstdint>
#include <optional>
#include <string>
#include <vector>

#include "capture/live/pixel_format.h"
#include "core/image.h"
#include "core/light_direction.h"

namespace photomat {

// A camera (or anything acting as one) that a capture session grabs frames from. Three backends
// implement it: V4L2 (v4l2_frame_source.h), libcamera (libcamera_frame_source.h) and a replay of
// a set on disk (folder_frame_source.h). All report frames as linear float images.

// A format a source can stream.
struct FrameFormat {
  PixelFormat pixel_format = PixelFormat::kGrey;
  int width = 0;
  int height = 0;
  bool operator==(const FrameFormat&) const = default;
};
// "YUYV 640x480".
std::string ToString(const FrameFormat& format);

// What a device offers for one of its format codes, whether photomat decodes it or not (so that
// `photomat devices` shows everything and an error can say what the camera has instead).
struct OfferedFormat {
  std::string code;                         // fourcc or the backend's name ("YUYV", "NV12")
  std::string description;                  // the driver's words, may be empty
  std::optional<PixelFormat> pixel_format;  // set when photomat decodes it
  std::vector<std::pair<int, int>> sizes;   // width x height; empty when the device does not say
};

// A control as the device describes it (exposure, gain, white balance ...).
struct CameraControl {
  std::string name;
  double minimum = 0.0;
  double maximum = 0.0;
  double step = 0.0;
  double default_value = 0.0;
  std::optional<double> current;
};

// The settings a photometric capture needs fixed: automatic exposure, gain and white balance off,
// then the given exposure and gain (unset: the device's current values stay).
struct ManualControls {
  std::optional<double> exposure_us;
  std::optional<double> gain;
};

struct FrameMetadata {
  std::uint64_t sequence = 0;
  // When the frame was captured, on the steady (CLOCK_MONOTONIC) clock: the session drops frames
  // exposed before a light or exposure change had settled.
  std::chrono::steady_clock::time_point timestamp;
  // The exposure this frame really had, as the device reports it per frame (libcamera: the
  // completed request's ExposureTime metadata); unset when the device does not report one (V4L2
  // has no per-frame exposure, and a driver may apply a change a few frames late). The session
  // keeps a frame for a bracket step only when a reported exposure matches the step's.
  std::optional<double> exposure_us;
  std::optional<double> gain;
};

struct Frame {
  Image image;  // linear float, 1 or 3 channels
  FrameMetadata metadata;
};

// One camera as `photomat devices` lists it.
struct DeviceDescription {
  std::string id;           // what --device takes ("/dev/video0", "libcamera:<id>")
  std::string description;  // driver and card name, or the camera model
  std::vector<OfferedFormat> formats;
  std::vector<CameraControl> controls;
  std::string error;  // set when the device exists but could not be queried
};

// The light a session has switched on (number 0: all lights off, for the dark frame).
struct LightState {
  int number = 0;  // 1-based position in the plan; 0 = off
  int count = 0;   // lights in the plan
  std::optional<LightDirection> direction;
  bool off() const { return number == 0; }
};

class FrameSource {
 public:
  virtual ~FrameSource() = default;

  // Names the device in messages ("/dev/video0", "libcamera:<id>", "folder:<path>").
  virtual std::string name() const = 0;
  virtual std::vector<OfferedFormat> ListFormats() = 0;
  virtual std::vector<CameraControl> ListControls() = 0;
  // Sets the stream format; returns what the device actually set (a driver may adjust the size).
  // Throws Error when the device does not offer the pixel format or photomat cannot decode it.
  virtual FrameFormat SetFormat(const FrameFormat& format) = 0;
  // The format that SetFormat chose when the session did not ask for one: the first format the
  // device offers that photomat decodes, in the order of AllPixelFormats(), at its largest size.
  virtual FrameFormat DefaultFormat();
  virtual void SetManualControls(const ManualControls& controls) = 0;
  // Exposure changes between grabs (bracketing); the new value applies to frames captured after
  // it returns.
  virtual void SetExposure(double exposure_us) = 0;
  virtual void Start() = 0;
  virtual void Stop() = 0;
  // The next frame; throws Error naming the device when none comes within `timeout`, when the
  // device is gone, or when the frame cannot be decoded.
  virtual Frame Grab(std::chrono::milliseconds timeout) = 0;
  // Told each light switch. Cameras ignore it; a replay source serves the matching image.
  virtual void LightChanged(const LightState& /*light*/) {}
};

}  // namespace photomat
