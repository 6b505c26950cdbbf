#include "capture/live/frame_source.h"

#include <fmt/format.h>

#include <algorithm>

#include "core/error.h"

namespace photomat {

std::string ToString(const FrameFormat& format) {
  return fmt::format("{} {}x{}", ToString(format.pixel_format), format.width, format.height);
}

FrameFormat FrameSource::DefaultFormat() {
  const std::vector<OfferedFormat> offered = ListFormats();
  for (PixelFormat wanted : AllPixelFormats()) {
    for (const OfferedFormat& format : offered) {
      if (format.pixel_format != wanted) continue;
      FrameFormat chosen{wanted, 0, 0};
      for (const auto& [width, height] : format.sizes) {
        if (static_cast<long>(width) * height > static_cast<long>(chosen.width) * chosen.height) {
          chosen.width = width;
          chosen.height = height;
        }
      }
      return chosen;
    }
  }
  std::string codes;
  for (const OfferedFormat& format : offered) codes += (codes.empty() ? "" : ", ") + format.code;
  throw Error(name(), fmt::format("unsupported format: the device offers {} and photomat decodes "
                                  "only {}",
                                  codes.empty() ? "no format" : codes, SupportedPixelFormatList()));
}

}  // namespace photomat
