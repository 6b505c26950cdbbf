#include "capture/live/open_frame_source.h"

#include <fmt/format.h>

#include "capture/live/folder_frame_source.h"
#include "capture/live/libcamera_frame_source.h"
#include "capture/live/v4l2_frame_source.h"
#include "core/error.h"

namespace photomat {

std::unique_ptr<FrameSource> OpenFrameSource(const std::string& spec,
                                             const FrameSourceOptions& options) {
  const auto starts = [&](const char* prefix) { return spec.rfind(prefix, 0) == 0; };
  if (starts("folder:")) return std::make_unique<FolderFrameSource>(spec.substr(7));
  if (starts("libcamera:")) {
    LibcameraOptions camera;
    camera.raw = options.raw;
    camera.eight_bit_encoding = options.eight_bit_encoding;
    return std::make_unique<LibcameraFrameSource>(spec.substr(10), camera);
  }
  const std::string path = starts("v4l2:") ? spec.substr(5) : spec;
  if (path.rfind("/dev/", 0) != 0 && !starts("v4l2:")) {
    throw Error(
        fmt::format("unknown device \"{}\": expected /dev/videoN (or v4l2:PATH), "
                    "libcamera:ID or folder:PATH",
                    spec));
  }
  V4l2Options v4l2;
  v4l2.eight_bit_encoding = options.eight_bit_encoding;
  return std::make_unique<V4l2FrameSource>(path, v4l2);
}

}  // namespace photomat
