#include "capture/live/v4l2_frame_source.h"

#include <fcntl.h>
#include <fmt/format.h>
#include <linux/videodev2.h>
#include <sys/mman.h>

#include <algorithm>
#include <cerrno>
#include <cmath>
#include <cstring>

#include "core/error.h"
#include "core/image_io.h"

namespace photomat {
namespace {

namespace fs = std::filesystem;
using Clock = std::chrono::steady_clock;

std::string CString(const __u8* text, std::size_t size) {
  return std::string(reinterpret_cast<const char*>(text),
                     strnlen(reinterpret_cast<const char*>(text), size));
}

std::string ErrnoText(int error) {
  return fmt::format("{} ({})", std::strerror(error),
                     strerrorname_np(error) ? strerrorname_np(error) : "?");
}

// V4L2 reports capture time as a timeval on CLOCK_MONOTONIC when it says so in the flags, which is
// the clock std::chrono::steady_clock reads on Linux.
Clock::time_point FrameTime(const v4l2_buffer& buffer) {
  if ((buffer.flags & V4L2_BUF_FLAG_TIMESTAMP_MASK) != V4L2_BUF_FLAG_TIMESTAMP_MONOTONIC) {
    return Clock::now();  // unknown clock: the moment the frame reached us
  }
  const auto since_boot = std::chrono::seconds(buffer.timestamp.tv_sec) +
                          std::chrono::microseconds(buffer.timestamp.tv_usec);
  return Clock::time_point(std::chrono::duration_cast<Clock::duration>(since_boot));
}

}  // namespace

V4l2FrameSource::V4l2FrameSource(fs::path path, V4l2Syscalls& syscalls, const V4l2Options& options)
    : path_(std::move(path)), syscalls_(syscalls), options_(options) {
  OpenDevice();
}

V4l2FrameSource::V4l2FrameSource(fs::path path, const V4l2Options& options)
    : path_(std::move(path)),
      owned_syscalls_(std::make_unique<LinuxV4l2Syscalls>()),
      syscalls_(*owned_syscalls_),
      options_(options) {
  OpenDevice();
}

void V4l2FrameSource::OpenDevice() {
  fd_ = syscalls_.Open(path_.c_str(), O_RDWR | O_NONBLOCK | O_CLOEXEC);
  if (fd_ < 0) {
    throw Error(path_, fmt::format("cannot open the video device: {}", ErrnoText(errno)));
  }
  try {
    v4l2_capability caps{};
    Xioctl(VIDIOC_QUERYCAP, &caps, "VIDIOC_QUERYCAP (is it a V4L2 device?)");
    const std::uint32_t device_caps =
        (caps.capabilities & V4L2_CAP_DEVICE_CAPS) ? caps.device_caps : caps.capabilities;
    description_ = fmt::format("{} ({})", CString(caps.card, sizeof caps.card),
                               CString(caps.driver, sizeof caps.driver));
    if (!(device_caps & V4L2_CAP_VIDEO_CAPTURE)) {
      throw Error(path_, "not a video capture device (no V4L2_CAP_VIDEO_CAPTURE)");
    }
    if (!(device_caps & V4L2_CAP_STREAMING)) {
      throw Error(path_,
                  "the device cannot stream (no V4L2_CAP_STREAMING); photomat needs mmap "
                  "streaming");
    }
  } catch (...) {
    syscalls_.Close(fd_);
    throw;
  }
}

V4l2FrameSource::~V4l2FrameSource() {
  try {
    Stop();
  } catch (const Error&) {
    // The device may be gone; the buffers are released below regardless.
  }
  ReleaseBuffers();
  if (fd_ >= 0) syscalls_.Close(fd_);
}

void V4l2FrameSource::Xioctl(unsigned long request, void* argument, const char* what) {
  if (syscalls_.Ioctl(fd_, request, argument) != 0) {
    const int error = errno;
    if (error == ENODEV) {
      throw Error(path_, fmt::format("device disconnected{} ({} failed)",
                                     streaming_ ? " while streaming" : "", what));
    }
    throw Error(path_, fmt::format("{} failed: {}", what, ErrnoText(error)));
  }
}

std::vector<OfferedFormat> V4l2FrameSource::ListFormats() {
  std::vector<OfferedFormat> formats;
  for (std::uint32_t index = 0;; ++index) {
    v4l2_fmtdesc description{};
    description.index = index;
    description.type = V4L2_BUF_TYPE_VIDEO_CAPTURE;
    if (syscalls_.Ioctl(fd_, VIDIOC_ENUM_FMT, &description) != 0) {
      if (errno == EINVAL) break;  // past the last format
      throw Error(path_, fmt::format("VIDIOC_ENUM_FMT failed: {}", ErrnoText(errno)));
    }
    OfferedFormat format;
    format.code = FourCcToString(description.pixelformat);
    format.description = CString(description.description, sizeof description.description);
    format.pixel_format = PixelFormatFromV4l2(description.pixelformat);
    for (std::uint32_t size_index = 0;; ++size_index) {
      v4l2_frmsizeenum size{};
      size.index = size_index;
      size.pixel_format = description.pixelformat;
      if (syscalls_.Ioctl(fd_, VIDIOC_ENUM_FRAMESIZES, &size) != 0) break;
      if (size.type == V4L2_FRMSIZE_TYPE_DISCRETE) {
        format.sizes.emplace_back(size.discrete.width, size.discrete.height);
      } else {  // stepwise or continuous: the largest is what a photometric capture wants
        format.sizes.emplace_back(size.stepwise.max_width, size.stepwise.max_height);
        break;
      }
    }
    formats.push_back(std::move(format));
  }
  return formats;
}

std::vector<CameraControl> V4l2FrameSource::ListControls() {
  std::vector<CameraControl> controls;
  v4l2_queryctrl query{};
  query.id = V4L2_CTRL_FLAG_NEXT_CTRL;
  while (syscalls_.Ioctl(fd_, VIDIOC_QUERYCTRL, &query) == 0) {
    if (!(query.flags & V4L2_CTRL_FLAG_DISABLED) && query.type != V4L2_CTRL_TYPE_CTRL_CLASS) {
      CameraControl control{
          CString(query.name, sizeof query.name),   static_cast<double>(query.minimum),
          static_cast<double>(query.maximum),       static_cast<double>(query.step),
          static_cast<double>(query.default_value), std::nullopt};
      if (auto value = GetControl(query.id)) control.current = *value;
      controls.push_back(std::move(control));
    }
    query.id |= V4L2_CTRL_FLAG_NEXT_CTRL;
  }
  return controls;
}

FrameFormat V4l2FrameSource::SetFormat(const FrameFormat& wanted) {
  if (streaming_) throw Error(path_, "cannot change the format while streaming");
  const std::vector<OfferedFormat> offered = ListFormats();
  const std::string code = FourCcToString(V4l2FourCc(wanted.pixel_format));
  if (std::none_of(offered.begin(), offered.end(),
                   [&](const OfferedFormat& f) { return f.pixel_format == wanted.pixel_format; })) {
    std::string codes;
    for (const OfferedFormat& f : offered) codes += (codes.empty() ? "" : ", ") + f.code;
    throw Error(path_,
                fmt::format("unsupported format: the device does not offer {} (it offers "
                            "{}; photomat decodes {})",
                            code, codes.empty() ? "nothing" : codes, SupportedPixelFormatList()));
  }
  v4l2_format format{};
  format.type = V4L2_BUF_TYPE_VIDEO_CAPTURE;
  Xioctl(VIDIOC_G_FMT, &format, "VIDIOC_G_FMT");
  if (wanted.width > 0 && wanted.height > 0) {
    format.fmt.pix.width = wanted.width;
    format.fmt.pix.height = wanted.height;
  }
  format.fmt.pix.pixelformat = V4l2FourCc(wanted.pixel_format);
  format.fmt.pix.field = V4L2_FIELD_NONE;
  format.fmt.pix.bytesperline = 0;  // let the driver choose its row padding
  Xioctl(VIDIOC_S_FMT, &format, "VIDIOC_S_FMT");
  // Drivers answer an impossible request with the nearest format they have instead of failing.
  if (format.fmt.pix.pixelformat != V4l2FourCc(wanted.pixel_format)) {
    throw Error(path_, fmt::format("unsupported format: asked for {}, the driver set {}", code,
                                   FourCcToString(format.fmt.pix.pixelformat)));
  }
  if (format.fmt.pix.field != V4L2_FIELD_NONE && format.fmt.pix.field != V4L2_FIELD_ANY) {
    throw Error(path_, "unsupported format: the device delivers interlaced fields");
  }
  layout_ = {wanted.pixel_format, static_cast<int>(format.fmt.pix.width),
             static_cast<int>(format.fmt.pix.height),
             static_cast<int>(format.fmt.pix.bytesperline)};
  format_set_ = true;
  return {layout_.format, layout_.width, layout_.height};
}

std::optional<std::int32_t> V4l2FrameSource::GetControl(std::uint32_t id) {
  v4l2_control control{};
  control.id = id;
  if (syscalls_.Ioctl(fd_, VIDIOC_G_CTRL, &control) != 0) return std::nullopt;
  return control.value;
}

bool V4l2FrameSource::SetControlIfPresent(std::uint32_t id, std::int32_t value, const char* what) {
  v4l2_queryctrl query{};
  query.id = id;
  if (syscalls_.Ioctl(fd_, VIDIOC_QUERYCTRL, &query) != 0) {
    if (errno == ENODEV) throw Error(path_, "device disconnected");
    return false;
  }
  if (query.flags & V4L2_CTRL_FLAG_DISABLED) return false;
  if (value < query.minimum || value > query.maximum) {
    throw Error(path_, fmt::format("{} {} is out of the device's range [{}, {}]", what, value,
                                   query.minimum, query.maximum));
  }
  v4l2_control control{};
  control.id = id;
  control.value = value;
  Xioctl(VIDIOC_S_CTRL, &control, what);
  // Some drivers accept a value and keep another; a photometric capture must know.
  if (auto now = GetControl(id); now && *now != value) {
    throw Error(path_, fmt::format("{}: set {}, the device kept {}", what, value, *now));
  }
  return true;
}

void V4l2FrameSource::SetManualControls(const ManualControls& controls) {
  SetControlIfPresent(V4L2_CID_EXPOSURE_AUTO, V4L2_EXPOSURE_MANUAL, "turning auto exposure off");
  SetControlIfPresent(V4L2_CID_EXPOSURE_AUTO_PRIORITY, 0, "turning exposure priority off");
  SetControlIfPresent(V4L2_CID_AUTOGAIN, 0, "turning auto gain off");
  SetControlIfPresent(V4L2_CID_AUTO_WHITE_BALANCE, 0, "turning auto white balance off");
  if (controls.exposure_us) SetExposure(*controls.exposure_us);
  if (controls.gain) {
    const auto gain = static_cast<std::int32_t>(std::lround(*controls.gain));
    if (!SetControlIfPresent(V4L2_CID_GAIN, gain, "setting the gain")) {
      throw Error(path_, "the device has no gain control (V4L2_CID_GAIN)");
    }
    gain_ = gain;
  }
}

void V4l2FrameSource::SetExposure(double exposure_us) {
  // V4L2_CID_EXPOSURE_ABSOLUTE counts 100 us units.
  const auto units = static_cast<std::int32_t>(std::lround(exposure_us / 100.0));
  if (units < 1) {
    throw Error(path_, fmt::format("exposure {} us is below the V4L2 unit of 100 us", exposure_us));
  }
  if (!SetControlIfPresent(V4L2_CID_EXPOSURE_ABSOLUTE, units, "setting the exposure")) {
    throw Error(path_, "the device has no exposure control (V4L2_CID_EXPOSURE_ABSOLUTE)");
  }
}

void V4l2FrameSource::Start() {
  if (streaming_) return;
  if (!format_set_) SetFormat(DefaultFormat());
  v4l2_requestbuffers request{};
  request.count = options_.buffer_count;
  request.type = V4L2_BUF_TYPE_VIDEO_CAPTURE;
  request.memory = V4L2_MEMORY_MMAP;
  Xioctl(VIDIOC_REQBUFS, &request, "VIDIOC_REQBUFS");
  if (request.count < 2) {
    throw Error(path_, fmt::format("the driver granted {} buffers, streaming needs at least 2",
                                   request.count));
  }
  try {
    for (std::uint32_t i = 0; i < request.count; ++i) {
      v4l2_buffer buffer{};
      buffer.type = V4L2_BUF_TYPE_VIDEO_CAPTURE;
      buffer.memory = V4L2_MEMORY_MMAP;
      buffer.index = i;
      Xioctl(VIDIOC_QUERYBUF, &buffer, "VIDIOC_QUERYBUF");
      void* address =
          syscalls_.Mmap(buffer.length, PROT_READ | PROT_WRITE, MAP_SHARED, fd_, buffer.m.offset);
      if (address == MAP_FAILED) {
        throw Error(path_, fmt::format("mmap of buffer {} failed: {}", i, ErrnoText(errno)));
      }
      buffers_.push_back({address, buffer.length});
    }
    for (std::uint32_t i = 0; i < buffers_.size(); ++i) {
      v4l2_buffer buffer{};
      buffer.type = V4L2_BUF_TYPE_VIDEO_CAPTURE;
      buffer.memory = V4L2_MEMORY_MMAP;
      buffer.index = i;
      Xioctl(VIDIOC_QBUF, &buffer, "VIDIOC_QBUF");
    }
    int type = V4L2_BUF_TYPE_VIDEO_CAPTURE;
    Xioctl(VIDIOC_STREAMON, &type, "VIDIOC_STREAMON");
  } catch (...) {
    ReleaseBuffers();
    throw;
  }
  streaming_ = true;
}

void V4l2FrameSource::Stop() {
  if (!streaming_) return;
  streaming_ = false;
  int type = V4L2_BUF_TYPE_VIDEO_CAPTURE;
  Xioctl(VIDIOC_STREAMOFF, &type, "VIDIOC_STREAMOFF");
  ReleaseBuffers();
}

void V4l2FrameSource::ReleaseBuffers() {
  for (const MappedBuffer& buffer : buffers_) syscalls_.Munmap(buffer.address, buffer.length);
  const bool had_buffers = !buffers_.empty();
  buffers_.clear();
  if (had_buffers) {
    v4l2_requestbuffers request{};
    request.count = 0;  // frees the driver's buffers
    request.type = V4L2_BUF_TYPE_VIDEO_CAPTURE;
    request.memory = V4L2_MEMORY_MMAP;
    syscalls_.Ioctl(fd_, VIDIOC_REQBUFS, &request);
  }
}

void V4l2FrameSource::FailStreaming(const std::string& what, int error) {
  if (error == ENODEV || error == EIO) {
    throw Error(
        path_, fmt::format("device disconnected while streaming ({}: {})", what, ErrnoText(error)));
  }
  throw Error(path_, fmt::format("{} failed: {}", what, ErrnoText(error)));
}

Frame V4l2FrameSource::Grab(std::chrono::milliseconds timeout) {
  if (pending_error_) {
    const Error error = *pending_error_;
    pending_error_.reset();
    throw error;
  }
  if (!streaming_) Start();
  const Clock::time_point deadline = Clock::now() + timeout;
  while (true) {
    const auto left =
        std::chrono::duration_cast<std::chrono::milliseconds>(deadline - Clock::now()).count();
    pollfd request{fd_, POLLIN, 0};
    const int ready = syscalls_.Poll(&request, 1, static_cast<int>(std::max<long>(left, 0)));
    if (ready < 0) {
      if (errno == EINTR) continue;
      FailStreaming("poll", errno);
    }
    if (ready == 0) {
      throw Error(path_, fmt::format("frame time-out: no frame within {} ms", timeout.count()));
    }
    if (request.revents & (POLLERR | POLLHUP | POLLNVAL)) {
      throw Error(path_, "device disconnected while streaming (poll reported an error)");
    }
    v4l2_buffer buffer{};
    buffer.type = V4L2_BUF_TYPE_VIDEO_CAPTURE;
    buffer.memory = V4L2_MEMORY_MMAP;
    if (syscalls_.Ioctl(fd_, VIDIOC_DQBUF, &buffer) != 0) {
      if (errno == EAGAIN || errno == EINTR) continue;
      FailStreaming("VIDIOC_DQBUF", errno);
    }
    if (buffer.index >= buffers_.size()) {
      throw Error(path_,
                  fmt::format("driver returned buffer {} of {}", buffer.index, buffers_.size()));
    }
    Frame frame;
    // No exposure: V4L2 reports none per frame, and the control's value is not what this frame
    // had when the driver applies a change some frames late.
    frame.metadata = {buffer.sequence, FrameTime(buffer), std::nullopt, gain_};
    const bool corrupt = buffer.flags & V4L2_BUF_FLAG_ERROR;
    std::optional<Error> decode_error;
    if (!corrupt) {
      const auto* bytes = static_cast<const std::uint8_t*>(buffers_[buffer.index].address);
      const std::size_t used =
          std::min<std::size_t>(buffer.bytesused, buffers_[buffer.index].length);
      try {
        frame.image = DecodeFrame(layout_, {bytes, used}, options_.eight_bit_encoding);
      } catch (const Error& error) {
        decode_error = error.InFile(path_);
      }
    }
    // The buffer goes back to the driver before anything else can throw. A good frame is
    // returned even if that fails (the device vanished just after it); the next Grab reports it.
    if (syscalls_.Ioctl(fd_, VIDIOC_QBUF, &buffer) != 0) {
      const int error = errno;
      try {
        FailStreaming("VIDIOC_QBUF", error);
      } catch (const Error& failure) {
        if (decode_error || corrupt) throw failure;
        pending_error_ = failure;
      }
    }
    if (decode_error) throw *decode_error;
    if (corrupt) {
      if (Clock::now() >= deadline) {
        throw Error(path_, fmt::format("frame time-out: only corrupt frames within {} ms",
                                       timeout.count()));
      }
      continue;  // the driver flagged a damaged frame: take the next one
    }
    return frame;
  }
}

std::vector<DeviceDescription> ListV4l2Devices(V4l2Syscalls& syscalls, const fs::path& dev) {
  std::vector<fs::path> paths;
  std::error_code ec;
  for (const auto& entry : fs::directory_iterator(dev, ec)) {
    const std::string name = entry.path().filename().string();
    if (name.rfind("video", 0) == 0) paths.push_back(entry.path());
  }
  std::sort(paths.begin(), paths.end(), [](const fs::path& a, const fs::path& b) {
    return NaturalLess(a.filename().string(), b.filename().string());  // video2 before video10
  });
  std::vector<DeviceDescription> devices;
  for (const fs::path& path : paths) {
    DeviceDescription device{path.string(), "", {}, {}, ""};
    try {
      V4l2FrameSource source(path, syscalls);
      device.description = source.description();
      device.formats = source.ListFormats();
      device.controls = source.ListControls();
    } catch (const Error& error) {
      if (error.fault().find("not a video capture device") != std::string::npos) continue;
      device.error = error.fault();
    }
    devices.push_back(std::move(device));
  }
  return devices;
}

}  // namespace photomat
