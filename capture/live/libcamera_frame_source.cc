#include "capture/live/libcamera_frame_source.h"

#include <fmt/format.h>
#include <libcamera/libcamera.h>
#include <sys/mman.h>

#include <algorithm>
#include <condition_variable>
#include <cstdlib>
#include <cstring>
#include <deque>
#include <map>
#include <mutex>

#include "core/error.h"

namespace photomat {
namespace {

namespace lc = libcamera;
using Clock = std::chrono::steady_clock;

std::optional<PixelFormat> FromLibcamera(const lc::PixelFormat& format) {
  if (format == lc::formats::R8) return PixelFormat::kGrey;
  if (format == lc::formats::YUYV) return PixelFormat::kYuyv;
  if (format == lc::formats::MJPEG) return PixelFormat::kMjpeg;
  // DRM fourccs name packed words little-endian: BGR888 is R, G, B in memory, RGB888 B, G, R.
  if (format == lc::formats::BGR888) return PixelFormat::kRgb24;
  if (format == lc::formats::RGB888) return PixelFormat::kBgr24;
  return std::nullopt;
}

std::optional<lc::PixelFormat> ToLibcamera(PixelFormat format) {
  switch (format) {
    case PixelFormat::kGrey:
      return lc::formats::R8;
    case PixelFormat::kYuyv:
      return lc::formats::YUYV;
    case PixelFormat::kMjpeg:
      return lc::formats::MJPEG;
    case PixelFormat::kRgb24:
      return lc::formats::BGR888;
    case PixelFormat::kBgr24:
      return lc::formats::RGB888;
    default:
      return std::nullopt;  // no 16-bit grey in libcamera 0.0.x
  }
}

std::optional<double> ToDouble(const lc::ControlValue& value) {
  if (value.isArray()) return std::nullopt;
  switch (value.type()) {
    case lc::ControlTypeBool:
      return value.get<bool>() ? 1.0 : 0.0;
    case lc::ControlTypeByte:
      return value.get<uint8_t>();
    case lc::ControlTypeInteger32:
      return value.get<int32_t>();
    case lc::ControlTypeInteger64:
      return static_cast<double>(value.get<int64_t>());
    case lc::ControlTypeFloat:
      return value.get<float>();
    default:
      return std::nullopt;
  }
}

// libcamera logs INFO and WARN lines to stderr by default (its version, missing IPA modules); a
// capture's terminal is for its progress bar and photomat's own errors. Setting
// LIBCAMERA_LOG_LEVELS (libcamera's own variable) keeps libcamera's logging for diagnosis.
void QuietLogging() {
  if (!std::getenv("LIBCAMERA_LOG_LEVELS")) lc::logSetTarget(lc::LoggingTargetNone);
}

std::unique_ptr<lc::CameraManager> StartManager() {
  QuietLogging();
  auto manager = std::make_unique<lc::CameraManager>();
  if (const int result = manager->start(); result != 0) {
    throw Error(
        fmt::format("libcamera: the camera manager did not start: {}", std::strerror(-result)));
  }
  return manager;
}

std::vector<OfferedFormat> OfferedFormats(lc::Camera& camera, bool raw) {
  std::unique_ptr<lc::CameraConfiguration> config =
      camera.generateConfiguration({raw ? lc::StreamRole::Raw : lc::StreamRole::StillCapture});
  std::vector<OfferedFormat> offered;
  if (!config || config->empty()) return offered;
  const lc::StreamFormats& formats = config->at(0).formats();
  for (const lc::PixelFormat& format : formats.pixelformats()) {
    OfferedFormat entry{format.toString(), "", FromLibcamera(format), {}};
    for (const lc::Size& size : formats.sizes(format)) {
      entry.sizes.emplace_back(size.width, size.height);
    }
    offered.push_back(std::move(entry));
  }
  return offered;
}

std::vector<CameraControl> Controls(const lc::Camera& camera) {
  std::vector<CameraControl> controls;
  for (const auto& [id, info] : camera.controls()) {
    const auto minimum = ToDouble(info.min()), maximum = ToDouble(info.max());
    if (!minimum || !maximum) continue;
    controls.push_back(
        {id->name(), *minimum, *maximum, 0.0, ToDouble(info.def()).value_or(0.0), std::nullopt});
  }
  std::sort(controls.begin(), controls.end(),
            [](const CameraControl& a, const CameraControl& b) { return a.name < b.name; });
  return controls;
}

}  // namespace

class LibcameraFrameSource::Impl {
 public:
  Impl(const std::string& camera, const LibcameraOptions& options) : options_(options) {
    manager_ = StartManager();
    const auto cameras = manager_->cameras();
    camera_ = manager_->get(camera);
    if (!camera_ && !camera.empty() &&
        std::all_of(camera.begin(), camera.end(), [](char c) { return c >= '0' && c <= '9'; })) {
      const std::size_t index = std::stoul(camera);
      if (index < cameras.size()) camera_ = cameras[index];
    }
    if (!camera_) {
      std::string ids;
      for (const auto& c : cameras) ids += (ids.empty() ? "" : ", ") + c->id();
      throw Error("libcamera:" + camera,
                  fmt::format("no such camera (libcamera {} finds {})", LibcameraVersion(),
                              cameras.empty() ? "no camera" : ids));
    }
    if (camera_->acquire() != 0) {
      throw Error(Name(), "the camera is in use by another process");
    }
    camera_->requestCompleted.connect(this, &Impl::OnRequestCompleted);
    camera_->disconnected.connect(this, &Impl::OnDisconnected);
  }

  ~Impl() {
    StopStreaming();
    camera_->requestCompleted.disconnect(this);
    camera_->disconnected.disconnect(this);
    requests_.clear();
    Unmap();
    allocator_.reset();
    camera_->release();
    camera_.reset();
    manager_->stop();
  }

  std::string Name() const { return "libcamera:" + (camera_ ? camera_->id() : std::string()); }

  std::vector<OfferedFormat> ListFormats() { return OfferedFormats(*camera_, options_.raw); }
  std::vector<CameraControl> ListControls() { return Controls(*camera_); }

  FrameFormat SetFormat(const FrameFormat& wanted) {
    if (streaming_) throw Error(Name(), "cannot change the format while streaming");
    const auto format = ToLibcamera(wanted.pixel_format);
    if (!format) {
      throw Error(Name(), fmt::format("unsupported format: libcamera has no {} format",
                                      ToString(wanted.pixel_format)));
    }
    config_ = camera_->generateConfiguration(
        {options_.raw ? lc::StreamRole::Raw : lc::StreamRole::StillCapture});
    if (!config_ || config_->empty()) {
      throw Error(Name(), "the camera offers no stream for this role");
    }
    lc::StreamConfiguration& stream = config_->at(0);
    stream.pixelFormat = *format;
    if (wanted.width > 0 && wanted.height > 0) stream.size = lc::Size(wanted.width, wanted.height);
    stream.bufferCount = options_.buffer_count;
    if (config_->validate() == lc::CameraConfiguration::Invalid) {
      throw Error(Name(), fmt::format("unsupported format: {} is not a valid configuration",
                                      ToString(wanted)));
    }
    if (stream.pixelFormat != *format) {
      throw Error(Name(),
                  fmt::format("unsupported format: asked for {}, the camera set {}",
                              ToString(wanted.pixel_format), stream.pixelFormat.toString()));
    }
    if (camera_->configure(config_.get()) != 0) {
      throw Error(Name(), fmt::format("cannot configure {}", stream.toString()));
    }
    layout_ = {wanted.pixel_format, static_cast<int>(stream.size.width),
               static_cast<int>(stream.size.height), static_cast<int>(stream.stride)};
    return {layout_.format, layout_.width, layout_.height};
  }

  void SetManualControls(const ManualControls& controls) {
    manual_ = true;
    if (controls.exposure_us) SetExposure(*controls.exposure_us);
    if (controls.gain) {
      RequireControl(lc::controls::AnalogueGain.id(), "AnalogueGain");
      gain_ = *controls.gain;
    }
  }

  void SetExposure(double exposure_us) {
    RequireControl(lc::controls::ExposureTime.id(), "ExposureTime");
    std::lock_guard lock(mutex_);
    exposure_us_ = exposure_us;
  }

  void Start() {
    if (streaming_) return;
    if (!config_) throw Error(Name(), "no format set before starting");
    lc::Stream* stream = config_->at(0).stream();
    allocator_ = std::make_unique<lc::FrameBufferAllocator>(camera_);
    if (allocator_->allocate(stream) < 0) throw Error(Name(), "cannot allocate frame buffers");
    for (const std::unique_ptr<lc::FrameBuffer>& buffer : allocator_->buffers(stream)) {
      Map(*buffer);
      std::unique_ptr<lc::Request> request = camera_->createRequest();
      if (!request || request->addBuffer(stream, buffer.get()) != 0) {
        throw Error(Name(), "cannot create a capture request");
      }
      requests_.push_back(std::move(request));
    }
    lc::ControlList start_controls(camera_->controls());
    ApplyControls(start_controls);
    if (camera_->start(&start_controls) != 0) throw Error(Name(), "cannot start the camera");
    streaming_ = true;
    for (const auto& request : requests_) Queue(request.get());
  }

  void StopStreaming() {
    if (!streaming_) return;
    streaming_ = false;
    camera_->stop();
    std::lock_guard lock(mutex_);
    completed_.clear();
  }

  Frame Grab(std::chrono::milliseconds timeout) {
    if (!streaming_) Start();
    const Clock::time_point deadline = Clock::now() + timeout;
    while (true) {
      lc::Request* request = nullptr;
      {
        std::unique_lock lock(mutex_);
        if (!ready_.wait_until(lock, deadline,
                               [&] { return disconnected_ || !completed_.empty(); })) {
          throw Error(Name(),
                      fmt::format("frame time-out: no frame within {} ms", timeout.count()));
        }
        if (disconnected_) throw Error(Name(), "device disconnected while streaming");
        request = completed_.front();
        completed_.pop_front();
      }
      const lc::FrameBuffer* buffer = request->buffers().begin()->second;
      const lc::FrameMetadata& metadata = buffer->metadata();
      std::optional<Frame> frame;
      std::optional<Error> failure;
      if (request->status() == lc::Request::RequestComplete &&
          metadata.status == lc::FrameMetadata::FrameSuccess) {
        frame.emplace();
        frame->metadata.sequence = metadata.sequence;
        frame->metadata.timestamp = Clock::time_point(std::chrono::duration_cast<Clock::duration>(
            std::chrono::nanoseconds(metadata.timestamp)));
        if (auto t = request->metadata().get(lc::controls::ExposureTime)) {
          frame->metadata.exposure_us = *t;
        }
        if (auto g = request->metadata().get(lc::controls::AnalogueGain)) {
          frame->metadata.gain = *g;
        }
        const std::span<const std::uint8_t> bytes = mappings_.at(buffer);
        const std::size_t used =
            metadata.planes().empty()
                ? bytes.size()
                : std::min<std::size_t>(bytes.size(), metadata.planes()[0].bytesused);
        try {
          frame->image = DecodeFrame(layout_, bytes.first(used), options_.eight_bit_encoding);
        } catch (const Error& error) {
          failure = error.InFile(Name());
        }
      }
      request->reuse(lc::Request::ReuseBuffers);
      Queue(request);
      if (failure) throw *failure;
      if (frame) return std::move(*frame);
      if (Clock::now() >= deadline) {
        throw Error(Name(), fmt::format("frame time-out: only failed frames within {} ms",
                                        timeout.count()));
      }
    }
  }

 private:
  void RequireControl(unsigned int id, const char* name) {
    if (!camera_->controls().count(id)) {
      throw Error(Name(), fmt::format("the camera has no {} control", name));
    }
  }

  void ApplyControls(lc::ControlList& list) {
    if (manual_) {
      if (camera_->controls().count(lc::controls::AeEnable.id())) {
        list.set(lc::controls::AeEnable, false);
      }
      if (camera_->controls().count(lc::controls::AwbEnable.id())) {
        list.set(lc::controls::AwbEnable, false);
      }
    }
    std::lock_guard lock(mutex_);
    if (exposure_us_) list.set(lc::controls::ExposureTime, static_cast<int32_t>(*exposure_us_));
    if (gain_) list.set(lc::controls::AnalogueGain, static_cast<float>(*gain_));
  }

  void Queue(lc::Request* request) {
    ApplyControls(request->controls());
    if (camera_->queueRequest(request) != 0) {
      throw Error(Name(), "cannot queue a capture request (device disconnected?)");
    }
  }

  void Map(const lc::FrameBuffer& buffer) {
    if (buffer.planes().size() != 1) {
      throw Error(Name(), fmt::format("multi-planar buffers ({} planes) are not supported",
                                      buffer.planes().size()));
    }
    const lc::FrameBuffer::Plane& plane = buffer.planes()[0];
    const std::size_t offset =
        plane.offset == lc::FrameBuffer::Plane::kInvalidOffset ? 0 : plane.offset;
    void* address = mmap(nullptr, offset + plane.length, PROT_READ, MAP_SHARED, plane.fd.get(), 0);
    if (address == MAP_FAILED) throw Error(Name(), "cannot map a frame buffer");
    mapped_.push_back({address, offset + plane.length});
    mappings_[&buffer] = {static_cast<const std::uint8_t*>(address) + offset, plane.length};
  }

  void Unmap() {
    for (const auto& [address, length] : mapped_) munmap(address, length);
    mapped_.clear();
    mappings_.clear();
  }

  void OnRequestCompleted(lc::Request* request) {
    if (request->status() == lc::Request::RequestCancelled) return;  // stopping
    std::lock_guard lock(mutex_);
    completed_.push_back(request);
    ready_.notify_one();
  }

  void OnDisconnected() {
    std::lock_guard lock(mutex_);
    disconnected_ = true;
    ready_.notify_one();
  }

  LibcameraOptions options_;
  std::unique_ptr<lc::CameraManager> manager_;
  std::shared_ptr<lc::Camera> camera_;
  std::unique_ptr<lc::CameraConfiguration> config_;
  std::unique_ptr<lc::FrameBufferAllocator> allocator_;
  std::vector<std::unique_ptr<lc::Request>> requests_;
  std::vector<std::pair<void*, std::size_t>> mapped_;
  std::map<const lc::FrameBuffer*, std::span<const std::uint8_t>> mappings_;
  FrameLayout layout_;
  bool streaming_ = false;
  bool manual_ = false;
  std::optional<double> exposure_us_;
  std::optional<double> gain_;
  // Filled by libcamera's thread, drained by Grab.
  std::mutex mutex_;
  std::condition_variable ready_;
  std::deque<lc::Request*> completed_;
  bool disconnected_ = false;
};

LibcameraFrameSource::LibcameraFrameSource(const std::string& camera,
                                           const LibcameraOptions& options)
    : impl_(std::make_unique<Impl>(camera, options)) {}
LibcameraFrameSource::~LibcameraFrameSource() = default;
std::string LibcameraFrameSource::name() const { return impl_->Name(); }
std::vector<OfferedFormat> LibcameraFrameSource::ListFormats() { return impl_->ListFormats(); }
std::vector<CameraControl> LibcameraFrameSource::ListControls() { return impl_->ListControls(); }
FrameFormat LibcameraFrameSource::SetFormat(const FrameFormat& format) {
  return impl_->SetFormat(format);
}
void LibcameraFrameSource::SetManualControls(const ManualControls& controls) {
  impl_->SetManualControls(controls);
}
void LibcameraFrameSource::SetExposure(double exposure_us) { impl_->SetExposure(exposure_us); }
void LibcameraFrameSource::Start() { impl_->Start(); }
void LibcameraFrameSource::Stop() { impl_->StopStreaming(); }
Frame LibcameraFrameSource::Grab(std::chrono::milliseconds timeout) { return impl_->Grab(timeout); }

std::vector<DeviceDescription> ListLibcameraCameras(const LibcameraOptions& options) {
  std::unique_ptr<lc::CameraManager> manager = StartManager();
  std::vector<DeviceDescription> devices;
  for (const std::shared_ptr<lc::Camera>& camera : manager->cameras()) {
    DeviceDescription device{"libcamera:" + camera->id(), "", {}, {}, ""};
    if (auto model = camera->properties().get(lc::properties::Model)) device.description = *model;
    device.formats = OfferedFormats(*camera, options.raw);
    device.controls = Controls(*camera);
    devices.push_back(std::move(device));
  }
  manager->stop();
  return devices;
}

std::string LibcameraVersion() { return lc::CameraManager::version(); }

}  // namespace photomat
