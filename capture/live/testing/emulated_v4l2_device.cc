#include "capture/live/testing/emulated_v4l2_device.h"

#include <linux/videodev2.h>
#include <sys/mman.h>

#include <algorithm>
#include <cerrno>
#include <cmath>
#include <cstring>
#include <thread>

#include "capture/live/testing/frame_encoding.h"
#include "core/error.h"

namespace photomat::testing {
namespace {

constexpr off_t kBufferOffsetStep = 1 << 24;

void CopyName(const char* text, __u8* out, std::size_t size) {
  std::memset(out, 0, size);
  std::memcpy(out, text, std::min(std::strlen(text), size - 1));
}

int Fail(int error) {
  errno = error;
  return -1;
}

}  // namespace

EmulatedV4l2Device::EmulatedV4l2Device(EmulatedCameraOptions options)
    : options_(std::move(options)), random_(options_.noise_seed) {
  if (options_.fourccs.empty()) options_.fourccs = {V4L2_PIX_FMT_RGB24};
  fourcc_ = options_.fourccs.front();
  // Controls as a UVC camera has them (ids in increasing order for V4L2_CTRL_FLAG_NEXT_CTRL).
  controls_[V4L2_CID_AUTO_WHITE_BALANCE] = {
      V4L2_CTRL_TYPE_BOOLEAN, "White Balance, Auto", 0, 1, 1, 1, 1};
  controls_[V4L2_CID_GAIN] = {V4L2_CTRL_TYPE_INTEGER, "Gain", 0, 400, 1, 100, 100};
  controls_[V4L2_CID_AUTOGAIN] = {V4L2_CTRL_TYPE_BOOLEAN, "Gain, Automatic", 0, 1, 1, 1, 1};
  controls_[V4L2_CID_EXPOSURE_AUTO] = {V4L2_CTRL_TYPE_MENU,
                                       "Auto Exposure",
                                       0,
                                       3,
                                       1,
                                       V4L2_EXPOSURE_APERTURE_PRIORITY,
                                       V4L2_EXPOSURE_APERTURE_PRIORITY};
  if (options_.has_exposure_control) {
    controls_[V4L2_CID_EXPOSURE_ABSOLUTE] = {
        V4L2_CTRL_TYPE_INTEGER, "Exposure Time, Absolute", 1, 20000, 1, 100, 100};
  }
  if (options_.has_exposure_control) {
    applied_exposure_us_ = controls_.at(V4L2_CID_EXPOSURE_ABSOLUTE).value * 100.0;
  }
  // A fixed dark pattern: what a dark frame measures and subtraction must remove.
  dark_ = Image(options_.width, options_.height, 1);
  for (int y = 0; y < options_.height; ++y) {
    for (int x = 0; x < options_.width; ++x) {
      const double pattern = 0.5 + 0.5 * std::sin(0.37 * x + 0.11 * y * y + 0.05 * x * y);
      dark_.at(x, y, 0) = static_cast<float>(options_.dark_level + options_.dark_pattern * pattern);
    }
  }
}

bool EmulatedV4l2Device::Gone() const {
  return disconnected_ || (options_.disconnect_after_frames &&
                           frames_dequeued_ >= *options_.disconnect_after_frames);
}

bool EmulatedV4l2Device::Stalled() const {
  return options_.stall_after_frames && frames_dequeued_ >= *options_.stall_after_frames;
}

int EmulatedV4l2Device::Open(const char* path, int /*flags*/) {
  if (std::filesystem::path(path) != options_.path) return Fail(ENOENT);
  if (Gone()) return Fail(ENODEV);
  open_fds_.push_back(next_fd_);
  return next_fd_++;
}

int EmulatedV4l2Device::Close(int fd) {
  const auto it = std::find(open_fds_.begin(), open_fds_.end(), fd);
  if (it == open_fds_.end()) return Fail(EBADF);
  open_fds_.erase(it);
  if (open_fds_.empty()) {  // the last close frees the driver's buffers
    streaming_ = false;
    buffers_.clear();
    done_.clear();
  }
  return 0;
}

std::size_t EmulatedV4l2Device::FrameBytes() const {
  const auto format = PixelFormatFromV4l2(fourcc_);
  if (format == PixelFormat::kMjpeg) {
    return static_cast<std::size_t>(options_.width) * options_.height * 3 + 4096;
  }
  const int bpp = format ? BytesPerPixel(*format) : 2;
  return static_cast<std::size_t>(options_.width * bpp + options_.row_padding) * options_.height;
}

std::optional<double> EmulatedV4l2Device::FrameExposureUs(std::uint64_t sequence) const {
  const auto it = frame_exposures_us_.find(sequence);
  if (it == frame_exposures_us_.end()) return std::nullopt;
  return it->second;
}

double EmulatedV4l2Device::ExposureOfNextFrame() {
  while (!pending_exposures_.empty() && pending_exposures_.front().first <= sequence_) {
    applied_exposure_us_ = pending_exposures_.front().second;
    pending_exposures_.pop_front();
  }
  return options_.max_applied_exposure_us
             ? std::min(applied_exposure_us_, *options_.max_applied_exposure_us)
             : applied_exposure_us_;
}

Image EmulatedV4l2Device::SensorImage(const Image& scene, double exposure_us) {
  double scale = controls_.at(V4L2_CID_GAIN).value / 100.0;
  if (options_.has_exposure_control) scale *= exposure_us / options_.reference_exposure_us;
  // Each auto mode varies from frame to frame, with its own rhythm so that they never cancel.
  const auto wobble = [&](double rate) { return std::sin(rate * sequence_ + 0.3); };
  if (controls_.at(V4L2_CID_EXPOSURE_AUTO).value != V4L2_EXPOSURE_MANUAL) {
    scale *= 0.8 + 0.15 * wobble(0.9);
  }
  if (controls_.at(V4L2_CID_AUTOGAIN).value != 0) scale *= 1.0 + 0.1 * wobble(1.7);
  const bool auto_white = controls_.at(V4L2_CID_AUTO_WHITE_BALANCE).value != 0;
  const double white_wobble = wobble(2.3);
  std::normal_distribution<double> noise(0.0, options_.noise_sigma);
  Image sensor(options_.width, options_.height, scene.channels());
  for (int y = 0; y < options_.height; ++y) {
    for (int x = 0; x < options_.width; ++x) {
      for (int c = 0; c < scene.channels(); ++c) {
        const double white = auto_white ? 1.0 + 0.1 * white_wobble * (c - 1) : 1.0;
        double v = scene.at(x, y, c) * scale * white + dark_.at(x, y, 0);
        if (options_.noise_sigma > 0) v += noise(random_);
        sensor.at(x, y, c) = static_cast<float>(std::clamp(v, 0.0, 1.0));
      }
    }
  }
  return sensor;
}

void EmulatedV4l2Device::Expose(int index) {
  Buffer& buffer = buffers_[index];
  buffer.sequence = sequence_;
  buffer.time = std::chrono::steady_clock::now();
  buffer.flags = V4L2_BUF_FLAG_TIMESTAMP_MONOTONIC | V4L2_BUF_FLAG_DONE;
  const double exposure_us = ExposureOfNextFrame();
  if (options_.has_exposure_control) frame_exposures_us_[sequence_] = exposure_us;
  const auto format = PixelFormatFromV4l2(fourcc_);
  if (!format) {  // a format photomat does not decode: fill with a constant
    std::fill(buffer.bytes.begin(), buffer.bytes.end(), 0x80);
    buffer.bytes_used = static_cast<std::uint32_t>(buffer.bytes.size());
  } else {
    Image scene = options_.scene ? options_.scene() : Image(options_.width, options_.height, 3);
    if (ChannelCount(*format) == 1 && scene.channels() > 1) {
      // A monochrome sensor integrates all colours in one photosite, which is what clips.
      Image grey(scene.width(), scene.height(), 1);
      for (std::size_t p = 0; p < scene.pixel_count(); ++p) {
        float sum = 0.0f;
        for (float v : scene.pixel(p)) sum += v;
        grey.pixel(p)[0] = sum / static_cast<float>(scene.channels());
      }
      scene = std::move(grey);
    }
    const FrameLayout layout{*format, options_.width, options_.height,
                             options_.width * BytesPerPixel(*format) + options_.row_padding};
    const std::vector<std::uint8_t> bytes =
        EncodeFrame(layout, SensorImage(scene, exposure_us), options_.eight_bit_encoding);
    if (bytes.size() > buffer.bytes.size()) {
      buffer.flags |= V4L2_BUF_FLAG_ERROR;
      buffer.bytes_used = 0;
    } else {
      std::copy(bytes.begin(), bytes.end(), buffer.bytes.begin());
      buffer.bytes_used = static_cast<std::uint32_t>(bytes.size());
    }
  }
  ++sequence_;
  done_.push_back(index);
}

int EmulatedV4l2Device::Ioctl(int fd, unsigned long request, void* argument) {
  if (std::find(open_fds_.begin(), open_fds_.end(), fd) == open_fds_.end()) return Fail(EBADF);
  if (Gone()) return Fail(ENODEV);
  return HandleIoctl(request, argument);
}

int EmulatedV4l2Device::HandleIoctl(unsigned long request, void* argument) {
  switch (request) {
    case VIDIOC_QUERYCAP:
      return QueryCapability(static_cast<v4l2_capability*>(argument));
    case VIDIOC_ENUM_FMT:
      return EnumerateFormat(static_cast<v4l2_fmtdesc*>(argument));
    case VIDIOC_ENUM_FRAMESIZES:
      return EnumerateFrameSizes(static_cast<v4l2_frmsizeenum*>(argument));
    case VIDIOC_G_FMT:
    case VIDIOC_S_FMT:
      return GetOrSetFormat(request, static_cast<v4l2_format*>(argument));
    case VIDIOC_REQBUFS:
      return RequestBuffers(static_cast<v4l2_requestbuffers*>(argument));
    case VIDIOC_QUERYBUF:
    case VIDIOC_QBUF:
      return QueryOrQueueBuffer(request, static_cast<v4l2_buffer*>(argument));
    case VIDIOC_DQBUF:
      return DequeueBuffer(static_cast<v4l2_buffer*>(argument));
    case VIDIOC_STREAMON:
      return StreamOn(*static_cast<int*>(argument));
    case VIDIOC_STREAMOFF:
      return StreamOff(*static_cast<int*>(argument));
    case VIDIOC_QUERYCTRL:
      return QueryControl(static_cast<v4l2_queryctrl*>(argument));
    case VIDIOC_G_CTRL:
    case VIDIOC_S_CTRL:
      return GetOrSetControl(request, static_cast<v4l2_control*>(argument));
    default:
      return Fail(ENOTTY);
  }
}

int EmulatedV4l2Device::QueryCapability(v4l2_capability* caps) {
  std::memset(caps, 0, sizeof *caps);
  CopyName("photomat-emul", caps->driver, sizeof caps->driver);
  CopyName("Emulated Camera", caps->card, sizeof caps->card);
  CopyName("emulated", caps->bus_info, sizeof caps->bus_info);
  caps->device_caps = V4L2_CAP_VIDEO_CAPTURE | V4L2_CAP_STREAMING;
  caps->capabilities = caps->device_caps | V4L2_CAP_DEVICE_CAPS;
  return 0;
}

int EmulatedV4l2Device::EnumerateFormat(v4l2_fmtdesc* description) {
  if (description->type != V4L2_BUF_TYPE_VIDEO_CAPTURE ||
      description->index >= options_.fourccs.size()) {
    return Fail(EINVAL);
  }
  const std::uint32_t fourcc = options_.fourccs[description->index];
  description->pixelformat = fourcc;
  description->flags = fourcc == V4L2_PIX_FMT_MJPEG ? V4L2_FMT_FLAG_COMPRESSED : 0;
  CopyName(FourCcToString(fourcc).c_str(), description->description,
           sizeof description->description);
  return 0;
}

int EmulatedV4l2Device::EnumerateFrameSizes(v4l2_frmsizeenum* size) {
  if (size->index != 0 || std::find(options_.fourccs.begin(), options_.fourccs.end(),
                                    size->pixel_format) == options_.fourccs.end()) {
    return Fail(EINVAL);
  }
  size->type = V4L2_FRMSIZE_TYPE_DISCRETE;
  size->discrete.width = options_.width;
  size->discrete.height = options_.height;
  return 0;
}

int EmulatedV4l2Device::GetOrSetFormat(unsigned long request, v4l2_format* format) {
  if (format->type != V4L2_BUF_TYPE_VIDEO_CAPTURE) return Fail(EINVAL);
  if (request == VIDIOC_S_FMT) {
    if (!buffers_.empty()) return Fail(EBUSY);
    const bool offered = std::find(options_.fourccs.begin(), options_.fourccs.end(),
                                   format->fmt.pix.pixelformat) != options_.fourccs.end();
    // Drivers do not fail on an unknown format: they pick one they have.
    fourcc_ = offered ? format->fmt.pix.pixelformat : options_.fourccs.front();
  }
  const auto decoded = PixelFormatFromV4l2(fourcc_);
  std::memset(&format->fmt.pix, 0, sizeof format->fmt.pix);
  format->fmt.pix.width = options_.width;
  format->fmt.pix.height = options_.height;
  format->fmt.pix.pixelformat = fourcc_;
  format->fmt.pix.field = V4L2_FIELD_NONE;
  format->fmt.pix.bytesperline =
      decoded == PixelFormat::kMjpeg
          ? 0
          : options_.width * (decoded ? BytesPerPixel(*decoded) : 2) + options_.row_padding;
  format->fmt.pix.sizeimage = static_cast<std::uint32_t>(FrameBytes());
  format->fmt.pix.colorspace = V4L2_COLORSPACE_SRGB;
  return 0;
}

int EmulatedV4l2Device::RequestBuffers(v4l2_requestbuffers* request_buffers) {
  if (request_buffers->type != V4L2_BUF_TYPE_VIDEO_CAPTURE ||
      request_buffers->memory != V4L2_MEMORY_MMAP) {
    return Fail(EINVAL);
  }
  if (streaming_ || mapped_ > 0) return Fail(EBUSY);
  buffers_.clear();
  done_.clear();
  const std::uint32_t count = std::min<std::uint32_t>(request_buffers->count, 8);
  buffers_.resize(count);
  for (Buffer& buffer : buffers_) buffer.bytes.assign(FrameBytes(), 0);
  request_buffers->count = count;
  return 0;
}

int EmulatedV4l2Device::QueryOrQueueBuffer(unsigned long request, v4l2_buffer* buffer) {
  if (buffer->type != V4L2_BUF_TYPE_VIDEO_CAPTURE || buffer->memory != V4L2_MEMORY_MMAP ||
      buffer->index >= buffers_.size()) {
    return Fail(EINVAL);
  }
  Buffer& ours = buffers_[buffer->index];
  if (request == VIDIOC_QUERYBUF) {
    buffer->length = static_cast<std::uint32_t>(ours.bytes.size());
    buffer->m.offset = static_cast<std::uint32_t>(buffer->index * kBufferOffsetStep);
    buffer->flags = ours.queued ? V4L2_BUF_FLAG_QUEUED : 0;
    return 0;
  }
  if (ours.queued) return Fail(EINVAL);
  ours.queued = true;
  if (streaming_ && !Stalled()) Expose(static_cast<int>(buffer->index));
  return 0;
}

int EmulatedV4l2Device::DequeueBuffer(v4l2_buffer* buffer) {
  if (!streaming_) return Fail(EINVAL);
  if (done_.empty()) return Fail(EAGAIN);
  const int index = done_.front();
  done_.pop_front();
  Buffer& ours = buffers_[index];
  ours.queued = false;
  buffer->index = index;
  buffer->bytesused = ours.bytes_used;
  buffer->flags = ours.flags;
  buffer->field = V4L2_FIELD_NONE;
  buffer->sequence = ours.sequence;
  const auto since = ours.time.time_since_epoch();
  const auto seconds = std::chrono::duration_cast<std::chrono::seconds>(since);
  buffer->timestamp.tv_sec = seconds.count();
  buffer->timestamp.tv_usec =
      std::chrono::duration_cast<std::chrono::microseconds>(since - seconds).count();
  buffer->length = static_cast<std::uint32_t>(ours.bytes.size());
  buffer->m.offset = static_cast<std::uint32_t>(index * kBufferOffsetStep);
  ++frames_dequeued_;
  return 0;
}

int EmulatedV4l2Device::StreamOn(int type) {
  if (type != V4L2_BUF_TYPE_VIDEO_CAPTURE) return Fail(EINVAL);
  if (buffers_.empty()) return Fail(EINVAL);
  streaming_ = true;
  for (std::size_t i = 0; i < buffers_.size(); ++i) {
    if (buffers_[i].queued && !Stalled()) Expose(static_cast<int>(i));
  }
  return 0;
}

int EmulatedV4l2Device::StreamOff(int type) {
  if (type != V4L2_BUF_TYPE_VIDEO_CAPTURE) return Fail(EINVAL);
  streaming_ = false;
  done_.clear();
  for (Buffer& buffer : buffers_) buffer.queued = false;
  return 0;
}

int EmulatedV4l2Device::QueryControl(v4l2_queryctrl* query) {
  auto it = controls_.end();
  if (query->id & V4L2_CTRL_FLAG_NEXT_CTRL) {
    it = controls_.upper_bound(query->id &
                               ~(V4L2_CTRL_FLAG_NEXT_CTRL | V4L2_CTRL_FLAG_NEXT_COMPOUND));
  } else {
    it = controls_.find(query->id);
  }
  if (it == controls_.end()) return Fail(EINVAL);
  const Control& control = it->second;
  std::memset(query, 0, sizeof *query);
  query->id = it->first;
  query->type = control.type;
  CopyName(control.name, query->name, sizeof query->name);
  query->minimum = control.minimum;
  query->maximum = control.maximum;
  query->step = control.step;
  query->default_value = control.default_value;
  return 0;
}

int EmulatedV4l2Device::GetOrSetControl(unsigned long request, v4l2_control* control) {
  const auto it = controls_.find(control->id);
  if (it == controls_.end()) return Fail(EINVAL);
  if (request == VIDIOC_G_CTRL) {
    control->value = it->second.value;
    return 0;
  }
  if (control->value < it->second.minimum || control->value > it->second.maximum) {
    return Fail(ERANGE);
  }
  it->second.value = control->value;
  if (control->id == V4L2_CID_EXPOSURE_ABSOLUTE) {
    // The sensor takes the new value from the frame `exposure_delay_frames` after the next.
    pending_exposures_.emplace_back(sequence_ + options_.exposure_delay_frames,
                                    control->value * 100.0);
  }
  return 0;
}

void* EmulatedV4l2Device::Mmap(std::size_t length, int /*protection*/, int flags, int fd,
                               off_t offset) {
  if (std::find(open_fds_.begin(), open_fds_.end(), fd) == open_fds_.end()) {
    errno = EBADF;
    return MAP_FAILED;
  }
  const std::size_t index = static_cast<std::size_t>(offset / kBufferOffsetStep);
  if (!(flags & MAP_SHARED) || offset % kBufferOffsetStep != 0 || index >= buffers_.size() ||
      length != buffers_[index].bytes.size()) {
    errno = EINVAL;
    return MAP_FAILED;
  }
  ++mapped_;
  return buffers_[index].bytes.data();
}

int EmulatedV4l2Device::Munmap(void* address, std::size_t length) {
  for (const Buffer& buffer : buffers_) {
    if (buffer.bytes.data() == address && buffer.bytes.size() == length) {
      --mapped_;
      return 0;
    }
  }
  // Buffers freed by the last close stay "mapped" in a real process until munmap.
  if (mapped_ > 0) {
    --mapped_;
    return 0;
  }
  return Fail(EINVAL);
}

int EmulatedV4l2Device::Poll(pollfd* fds, nfds_t count, int timeout_ms) {
  int ready = 0;
  for (nfds_t i = 0; i < count; ++i) {
    fds[i].revents = 0;
    if (std::find(open_fds_.begin(), open_fds_.end(), fds[i].fd) == open_fds_.end()) {
      fds[i].revents = POLLNVAL;
    } else if (Gone()) {
      fds[i].revents = POLLERR | POLLHUP;
    } else if (streaming_ && !done_.empty()) {
      fds[i].revents = fds[i].events & (POLLIN | POLLRDNORM);
    }
    if (fds[i].revents) ++ready;
  }
  if (ready == 0 && timeout_ms > 0) {  // nothing will come: the time-out runs out
    std::this_thread::sleep_for(std::chrono::milliseconds(timeout_ms));
  }
  return ready;
}

}  // namespace photomat::testing
