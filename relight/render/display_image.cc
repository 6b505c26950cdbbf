#include "relight/render/display_image.h"

#include "core/colour.h"
#include "core/image_io.h"

namespace photomat {

void WriteDisplayCodes(const std::filesystem::path& path, const Image& codes) {
  // WriteImage applies the sRGB curve to linear values; its inverse first leaves the codes as they
  // are (to double rounding, far below half a code).
  Image linear = codes;
  for (float& v : linear.values()) v = static_cast<float>(SrgbToLinear(v));
  ImageWriteOptions options;
  options.sample_type = SampleType::kUint8;
  options.encoding = ColourSpace::kSrgb;
  WriteImage(path, linear, options);
}

}  // namespace photomat
