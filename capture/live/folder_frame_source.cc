#include "capture/live/folder_frame_source.h"

#include <fmt/format.h>

#include "capture/io/load_photometric_set.h"
#include "core/error.h"

namespace photomat {

FolderFrameSource::FolderFrameSource(std::filesystem::path path, double max_light_error_degrees)
    : path_(std::move(path)),
      max_light_error_degrees_(max_light_error_degrees),
      set_(LoadPhotometricSet(path_).set) {}

std::vector<OfferedFormat> FolderFrameSource::ListFormats() {
  return {{"FLOAT",
           fmt::format("linear float replay of {} images", set_.size()),
           PixelFormat::kFloat,
           {{set_.width(), set_.height()}}}};
}

FrameFormat FolderFrameSource::DefaultFormat() {
  return {PixelFormat::kFloat, set_.width(), set_.height()};
}

FrameFormat FolderFrameSource::SetFormat(const FrameFormat& format) {
  const bool size_ok = (format.width == 0 && format.height == 0) ||
                       (format.width == set_.width() && format.height == set_.height());
  if (format.pixel_format != PixelFormat::kFloat || !size_ok) {
    throw Error(name(), fmt::format("unsupported format {}: a replayed set offers only {}",
                                    ToString(format), ToString(DefaultFormat())));
  }
  return DefaultFormat();
}

void FolderFrameSource::SetManualControls(const ManualControls& controls) {
  if (controls.exposure_us) exposure_us_ = controls.exposure_us;
  if (controls.gain) gain_ = controls.gain;
}

void FolderFrameSource::LightChanged(const LightState& light) {
  if (light.off() || !light.direction) {
    current_.reset();
    return;
  }
  int nearest = 0;
  for (int i = 1; i < set_.size(); ++i) {
    if (set_.light(i).AngleToDegrees(*light.direction) <
        set_.light(nearest).AngleToDegrees(*light.direction)) {
      nearest = i;
    }
  }
  const double error = set_.light(nearest).AngleToDegrees(*light.direction);
  if (error > max_light_error_degrees_) {
    throw Error(name(), fmt::format("no image for light {} (slant {:.2f}, tilt {:.2f}): the "
                                    "nearest light of the set is {:.2f} degrees away",
                                    light.number, light.direction->SlantDegrees(),
                                    light.direction->TiltDegrees(), error));
  }
  current_ = nearest;
}

Frame FolderFrameSource::Grab(std::chrono::milliseconds /*timeout*/) {
  Frame frame;
  frame.image =
      current_ ? set_.image(*current_) : Image(set_.width(), set_.height(), set_.channels());
  frame.metadata = {sequence_++, std::chrono::steady_clock::now(), exposure_us_, gain_};
  return frame;
}

}  // namespace photomat
