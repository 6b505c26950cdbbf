#pragma once

#include <cstdint>
#include <vector>

#include "capture/live/pixel_format.h"
#include "core/colour.h"
#include "core/image.h"

namespace photomat::testing {

// What a camera would put in a buffer for a linear image (1 or 3 channels, values clamped to
// [0, 1]): the inverse of DecodeFrame, for the emulated camera and for tests of the decoders.
// Grey formats take the channel mean; YUYV uses BT.601 limited range with the chroma of each
// pixel pair averaged; MJPEG is a 4:4:4 JPEG of quality `jpeg_quality` from libjpeg-turbo. Rows
// are padded to `layout.bytes_per_line` when it is larger than a packed row.
std::vector<std::uint8_t> EncodeFrame(const FrameLayout& layout, const Image& linear,
                                      ColourSpace eight_bit_encoding, int jpeg_quality = 95);

}  // namespace photomat::testing
