#pragma once

#include <chrono>
#include <cstdint>
#include <deque>
#include <filesystem>
#include <functional>
#include <map>
#include <optional>
#include <random>
#include <utility>
#include <vector>

#include "capture/live/pixel_format.h"
#include "capture/live/v4l2_syscalls.h"
#include "core/colour.h"
#include "core/image.h"

// The requests' structures (linux/videodev2.h), declared so that users of the emulator need not
// include the kernel's header.
struct v4l2_buffer;
struct v4l2_capability;
struct v4l2_control;
struct v4l2_fmtdesc;
struct v4l2_format;
struct v4l2_frmsizeenum;
struct v4l2_queryctrl;
struct v4l2_requestbuffers;

namespace photomat::testing {

// The linear radiance the emulated camera sees at this instant (1 or 3 channels, any scale: the
// camera's exposure maps 1.0 at the reference exposure to full scale). Called for every frame.
using SceneRenderer = std::function<Image()>;

struct EmulatedCameraOptions {
  std::filesystem::path path = "/dev/video-emulated";
  // The fourccs VIDIOC_ENUM_FMT lists, in order; may include codes photomat does not decode
  // (e.g. V4L2_PIX_FMT_NV12) to test refusals.
  std::vector<std::uint32_t> fourccs;
  int width = 64;
  int height = 64;
  // Extra bytes at the end of each row (drivers pad rows to alignment).
  int row_padding = 0;
  ColourSpace eight_bit_encoding = ColourSpace::kSrgb;
  SceneRenderer scene;
  // Sensor model: code = clamp(scene * exposure / reference_exposure * gain / 100 + dark + noise).
  double reference_exposure_us = 10000.0;
  // Dark level: `dark_level` plus a fixed pattern of up to `dark_pattern` (deterministic).
  double dark_level = 0.02;
  double dark_pattern = 0.01;
  double noise_sigma = 0.0;
  std::uint64_t noise_seed = 1;
  bool has_exposure_control = true;
  // A driver that applies an exposure change late: the frames exposed after the change keep the
  // previous exposure for this many frames (the control itself reads back the new value at once).
  int exposure_delay_frames = 0;
  // A sensor whose exposure cannot exceed its frame time: a longer setting is accepted by the
  // control and applied as this.
  std::optional<double> max_applied_exposure_us;
  // Faults. The device vanishes (ENODEV, POLLERR) once this many frames were dequeued.
  std::optional<int> disconnect_after_frames;
  // No frame comes any more once this many frames were dequeued (poll times out).
  std::optional<int> stall_after_frames;
};

// A V4L2 video-capture device in memory behind the V4l2Syscalls seam, so that V4l2FrameSource
// runs unchanged against it. It implements what the backend uses: open/close, VIDIOC_QUERYCAP,
// ENUM_FMT, ENUM_FRAMESIZES, G_FMT/S_FMT (an unknown format is answered with the first offered
// one, as drivers do), REQBUFS, QUERYBUF, mmap/munmap, QBUF, DQBUF, STREAMON/STREAMOFF,
// QUERYCTRL (with V4L2_CTRL_FLAG_NEXT_CTRL), G_CTRL/S_CTRL, and poll. A buffer is exposed when it
// is queued while streaming (or at STREAMON), with the scene and controls of that instant and a
// CLOCK_MONOTONIC timestamp; so frames queued before a light switch show the old light, as on a
// real camera. While auto exposure, auto gain or auto white balance are on, each frame gets a
// different scale (per channel for white balance), so a capture that fails to turn them off
// shows it. An exposure change can reach the sensor some frames late (as on drivers that apply
// controls at a frame boundary), and the device records the exposure each frame really had
// (FrameExposureUs) for a wrapper that reports it. Single-threaded, like the backend.
class EmulatedV4l2Device final : public V4l2Syscalls {
 public:
  explicit EmulatedV4l2Device(EmulatedCameraOptions options);

  int Open(const char* path, int flags) override;
  int Close(int fd) override;
  int Ioctl(int fd, unsigned long request, void* argument) override;
  void* Mmap(std::size_t length, int protection, int flags, int fd, off_t offset) override;
  int Munmap(void* address, std::size_t length) override;
  int Poll(pollfd* fds, nfds_t count, int timeout_ms) override;

  // Observations for tests.
  int frames_dequeued() const { return frames_dequeued_; }
  int open_handles() const { return static_cast<int>(open_fds_.size()); }
  int mapped_buffers() const { return mapped_; }
  bool streaming() const { return streaming_; }
  std::int32_t control(std::uint32_t id) const { return controls_.at(id).value; }
  // The exposure frame `sequence` really had (the delayed, capped value the sensor used), as a
  // device with per-frame metadata reports it; unset for a frame never exposed or without an
  // exposure control.
  std::optional<double> FrameExposureUs(std::uint64_t sequence) const;
  // Unplugs the device now.
  void Disconnect() { disconnected_ = true; }

 private:
  struct Control {
    std::uint32_t type;
    const char* name;
    std::int32_t minimum, maximum, step, default_value, value;
  };
  struct Buffer {
    std::vector<std::uint8_t> bytes;
    std::uint32_t bytes_used = 0;
    std::uint32_t flags = 0;
    std::uint32_t sequence = 0;
    std::chrono::steady_clock::time_point time;
    bool queued = false;
  };

  int HandleIoctl(unsigned long request, void* argument);
  // One handler per request HandleIoctl serves, as the driver's ioctl would.
  int QueryCapability(v4l2_capability* caps);
  int EnumerateFormat(v4l2_fmtdesc* description);
  int EnumerateFrameSizes(v4l2_frmsizeenum* size);
  int GetOrSetFormat(unsigned long request, v4l2_format* format);
  int RequestBuffers(v4l2_requestbuffers* request_buffers);
  int QueryOrQueueBuffer(unsigned long request, v4l2_buffer* buffer);
  int DequeueBuffer(v4l2_buffer* buffer);
  int StreamOn(int type);
  int StreamOff(int type);
  int QueryControl(v4l2_queryctrl* query);
  int GetOrSetControl(unsigned long request, v4l2_control* control);
  bool Gone() const;
  bool Stalled() const;
  void Expose(int index);
  // Applies the exposure changes due at the frame about to be exposed; returns its exposure.
  double ExposureOfNextFrame();
  Image SensorImage(const Image& scene, double exposure_us);
  std::size_t FrameBytes() const;

  EmulatedCameraOptions options_;
  std::map<std::uint32_t, Control> controls_;
  std::vector<int> open_fds_;
  int next_fd_ = 1000;
  std::uint32_t fourcc_;
  std::vector<Buffer> buffers_;
  std::deque<int> done_;  // exposed buffers, in capture order
  int mapped_ = 0;
  bool streaming_ = false;
  bool disconnected_ = false;
  std::uint32_t sequence_ = 0;
  // Exposure changes not applied yet: (first sequence exposed with it, exposure in us).
  std::deque<std::pair<std::uint32_t, double>> pending_exposures_;
  double applied_exposure_us_ = 0.0;
  std::map<std::uint64_t, double> frame_exposures_us_;
  int frames_dequeued_ = 0;
  Image dark_;
  std::mt19937_64 random_;
};

}  // namespace photomat::testing
