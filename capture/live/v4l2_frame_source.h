#pragma once

#include <filesystem>
#include <memory>
#include <string>
#include <vector>

#include "capture/live/frame_source.h"
#include "capture/live/v4l2_syscalls.h"
#include "core/colour.h"
#include "core/error.h"

namespace photomat {

struct V4l2Options {
  // Buffers the driver fills in turn (mmap streaming). Four keep a USB camera streaming while a
  // frame is decoded.
  int buffer_count = 4;
  // How 8-bit samples encode light (see DecodeFrame); UVC cameras deliver gamma-encoded video.
  ColourSpace eight_bit_encoding = ColourSpace::kSrgb;
};

// A V4L2 video-capture device streaming through mmap buffers (VIDIOC_REQBUFS / QUERYBUF / QBUF /
// DQBUF / STREAMON / STREAMOFF), every system call made through `syscalls` so that tests run this
// code unchanged against an emulated device. Formats: GREY, Y16, YUYV, MJPEG, RGB24 (and BGR24).
// Controls: V4L2_CID_EXPOSURE_AUTO set to manual, V4L2_CID_AUTOGAIN and
// V4L2_CID_AUTO_WHITE_BALANCE off; exposure through V4L2_CID_EXPOSURE_ABSOLUTE (100 us units) and
// gain through V4L2_CID_GAIN.
class V4l2FrameSource final : public FrameSource {
 public:
  // Opens the device and checks that it captures video and streams; throws Error naming `path`.
  // `syscalls` must outlive the source.
  V4l2FrameSource(std::filesystem::path path, V4l2Syscalls& syscalls,
                  const V4l2Options& options = {});
  // The same on the real kernel interface.
  explicit V4l2FrameSource(std::filesystem::path path, const V4l2Options& options = {});
  ~V4l2FrameSource() override;
  V4l2FrameSource(const V4l2FrameSource&) = delete;
  V4l2FrameSource& operator=(const V4l2FrameSource&) = delete;

  std::string name() const override { return path_.string(); }
  // The driver and card name from VIDIOC_QUERYCAP.
  const std::string& description() const { return description_; }
  std::vector<OfferedFormat> ListFormats() override;
  std::vector<CameraControl> ListControls() override;
  FrameFormat SetFormat(const FrameFormat& format) override;
  void SetManualControls(const ManualControls& controls) override;
  void SetExposure(double exposure_us) override;
  void Start() override;
  void Stop() override;
  Frame Grab(std::chrono::milliseconds timeout) override;

 private:
  struct MappedBuffer {
    void* address = nullptr;
    std::size_t length = 0;
  };

  // ioctl that throws Error naming the device and `what` on failure.
  void Xioctl(unsigned long request, void* argument, const char* what);
  // Sets a control if the device has it; returns false when it does not.
  bool SetControlIfPresent(std::uint32_t id, std::int32_t value, const char* what);
  std::optional<std::int32_t> GetControl(std::uint32_t id);
  [[noreturn]] void FailStreaming(const std::string& what, int error);
  void ReleaseBuffers();
  void OpenDevice();

  std::filesystem::path path_;
  std::unique_ptr<V4l2Syscalls> owned_syscalls_;  // set by the constructor without `syscalls`
  V4l2Syscalls& syscalls_;
  V4l2Options options_;
  int fd_ = -1;
  std::string description_;
  FrameLayout layout_;
  bool format_set_ = false;
  bool streaming_ = false;
  std::vector<MappedBuffer> buffers_;
  std::optional<double> gain_;
  // A failure to requeue the buffer of a frame that was returned: reported by the next Grab.
  std::optional<Error> pending_error_;
};

// The V4L2 capture devices under /dev (video0, video1, ...), each with its formats and controls.
// Devices that are not video capture devices (metadata nodes of UVC cameras) are left out.
std::vector<DeviceDescription> ListV4l2Devices(V4l2Syscalls& syscalls,
                                               const std::filesystem::path& dev = "/dev");

}  // namespace photomat
