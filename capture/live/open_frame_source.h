#pragma once

#include <memory>
#include <string>

#include "capture/live/frame_source.h"
#include "core/colour.h"

namespace photomat {

struct FrameSourceOptions {
  // How 8-bit camera samples encode light (see DecodeFrame).
  ColourSpace eight_bit_encoding = ColourSpace::kSrgb;
  // libcamera: the raw sensor stream instead of the processed still-capture stream.
  bool raw = false;
};

// A frame source from its command-line form:
//   "/dev/video0" or "v4l2:/dev/video0"   a V4L2 device
//   "libcamera:ID" or "libcamera:0"        a libcamera camera by id or index
//   "folder:PATH"                          a set on disk replayed as a camera (dry runs)
// Throws Error naming the device when it cannot be opened.
std::unique_ptr<FrameSource> OpenFrameSource(const std::string& spec,
                                             const FrameSourceOptions& options = {});

}  // namespace photomat
