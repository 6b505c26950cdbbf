#pragma once

#include <chrono>
#include <cstdint>
#include <filesystem>
#include <optional>
#include <string>
#include <vector>

#include "capture/live/frame_source.h"
#include "capture/live/light_controller.h"
#include "capture/live/light_plan.h"
#include "core/progress.h"

namespace photomat {

// A capture session records a photometric set from a camera (FrameSource) while a light
// controller switches the lights of a plan. For each light: switch, wait the settle time, grab K
// frames exposed after it and average them; with exposure bracketing, do that at each exposure
// and merge to one linear HDR image; subtract the dark frame taken with all lights off at the
// start. Each image is written as soon as it is taken, then the session state and the manifest,
// every file whole (temporary name, fsync, rename): an interrupted session loses at most the
// light in progress, and ResumeCaptureSession continues after the last light on disk.
//
// The output folder then holds:
//   img_000.exr ...          one linear float image per light (or 16-bit PNG), dark-subtracted
//   dark.exr                 the dark frame (dark_0.exr, dark_1.exr ... with bracketing)
//   manifest.json            the set so far (photomat's manifest; loadable at every moment)
//   capture_session.json     the session state: device, camera format, plan, settings, and per
//                            light the frames it averaged (README, "Capture")

enum class CaptureImageFormat { kExr, kPng16 };

// Exposure check, IMPLEMENTER CHOICE. When the camera reports each frame's exposure
// (FrameMetadata::exposure_us; libcamera does, V4L2 does not) and the session asked for one, a
// frame is kept only when its reported exposure matches the requested one within
// max(1 % of it, 50 us): sensors quantise exposure to whole line times (about 10 to 30 us), which
// stays under 1 % above a few milliseconds, and 50 us covers a line below that and V4L2's
// rounding to its 100 us unit; bracket steps differ by far more. A frame that does not match
// (a driver applying the change late) is dropped and counted; after
// kMaxExposureMismatchFrames such frames for one bracket step the capture fails naming the light,
// the requested and the last reported exposure. A camera that reports no exposure is trusted to
// have applied the change within the settle time, as before.
inline constexpr double kExposureMatchRelative = 0.01;
inline constexpr double kExposureMatchAbsoluteUs = 50.0;
// A driver applies a change within a few frames; 30 frames is a second at 30 fps.
inline constexpr int kMaxExposureMismatchFrames = 30;
bool ExposureMatches(double requested_us, double reported_us);

struct CaptureSettings {
  // Unset: the device's default (FrameSource::DefaultFormat).
  std::optional<FrameFormat> format;
  int frames_per_light = 1;
  // After a light switch or an exposure change, frames exposed earlier than this are dropped.
  std::chrono::milliseconds settle{200};
  std::chrono::milliseconds frame_timeout{5000};
  // Auto exposure, gain and white balance are always turned off; these set the values.
  ManualControls controls;
  // Exposure bracketing: factors of controls.exposure_us (e.g. {0.25, 1, 4}); empty: one
  // exposure. The HDR image is in units of the base exposure (factor 1).
  std::vector<double> bracket;
  bool dark_frame = true;
  CaptureImageFormat image_format = CaptureImageFormat::kExr;
  // Raw frame values at or above this are clipped: not measurements. Bracketing leaves them out
  // of the merge; the session counts them per light.
  double clip_level = 0.98;
};

struct CapturedLight {
  int number = 0;  // 1-based position in the plan
  std::string file;
  // Sequence numbers of the frames averaged, per exposure, in order (for audits: a frame is
  // never used twice).
  std::vector<std::uint64_t> frames;
  std::size_t clipped_pixels = 0;  // pixels with a channel clipped at every exposure
  // Frames dropped because their reported exposure was not the requested one (cameras that
  // report a per-frame exposure only).
  std::size_t exposure_mismatches = 0;
};

struct CaptureSessionState {
  std::string device;
  FrameFormat format;
  LightPlan plan;
  CaptureSettings settings;
  std::vector<std::string> dark_files;  // one per exposure when taken
  std::vector<CapturedLight> captured;  // in plan order, lights 1..captured.size()
  bool complete() const { return captured.size() == plan.lights.size(); }
};

inline constexpr const char* kCaptureSessionName = "capture_session.json";
inline constexpr const char* kCaptureSessionFormat = "photomat-capture-session";

// Throws Error naming the file and the JSON path of any fault.
CaptureSessionState ReadCaptureSession(const std::filesystem::path& path);
void WriteCaptureSession(const std::filesystem::path& path, const CaptureSessionState& state);

struct CaptureSummary {
  int lights_total = 0;
  int lights_before = 0;  // already on disk when this run started (resume)
  int lights_taken = 0;   // taken by this run
  FrameFormat format;
  std::size_t clipped_pixels = 0;       // over the lights taken by this run
  std::size_t exposure_mismatches = 0;  // frames dropped, over the lights taken by this run
};

// Starts a session in `out` (created if needed). Refuses a folder that already holds a session
// (resume it instead) or a set. Throws Error naming the device, controller or file at fault; the
// folder then stays resumable.
CaptureSummary RunCaptureSession(FrameSource& source, LightController& controller,
                                 const std::filesystem::path& out, const LightPlan& plan,
                                 const CaptureSettings& settings, Progress* progress = nullptr);

// Continues the session in `out` with its recorded plan and settings. The camera must deliver
// the recorded format: a different `requested_format`, or a device that now sets another format,
// is refused (a set is one format). A `plan` that differs from the recorded one is refused too.
CaptureSummary ResumeCaptureSession(FrameSource& source, LightController& controller,
                                    const std::filesystem::path& out,
                                    const std::optional<FrameFormat>& requested_format,
                                    const std::optional<LightPlan>& plan = std::nullopt,
                                    Progress* progress = nullptr);

}  // namespace photomat
