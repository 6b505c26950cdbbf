#include "calibrate/radiometry/capture_corrections.h"

#include <fmt/format.h>

#include <utility>

#include "calibrate/radiometry/exposure.h"
#include "core/near_light.h"

namespace photomat {
namespace {

// The whole frame's size is checked here: a band's rows of a frame of another height would pass
// the band-sized checks of SubtractDarkFrame and ApplyFlatField.
void CheckFrameSize(const PhotometricSet& band, int height, const Image& frame, const char* what) {
  if (frame.width() != band.width() || frame.height() != height) {
    band.Fail(fmt::format("the {} is {}x{} with {} channels but the images are {}x{} with {}", what,
                          frame.width(), frame.height(), frame.channels(), band.width(), height,
                          band.channels()));
  }
}

}  // namespace

PhotometricSet CorrectCaptureBand(PhotometricSet band, int first_row, int height,
                                  const CaptureCorrections& corrections) {
  const int rows = band.height();
  if (corrections.dark) CheckFrameSize(band, height, *corrections.dark, "dark frame");
  if (corrections.flat_field) {
    CheckFrameSize(band, height, corrections.flat_field->gain(0), "flat-field");
  }
  PhotometricSet corrected = std::move(band);
  if (corrections.response) corrected = LineariseSet(corrected, *corrections.response);
  if (corrections.dark) {
    corrected = SubtractDarkFrame(corrected, Image(corrections.dark->Rows(first_row, rows)));
  }
  if (corrections.flat_field) {
    corrected = ApplyFlatField(corrected, corrections.flat_field->Rows(first_row, rows));
  }
  if (corrections.near_lights) {
    corrected = ApplyFlatField(corrected, corrections.near_lights->Rows(first_row, rows));
    // The lamps travel with the corrected capture (its manifest's "lamp"s): the pbr fit lights
    // each pixel from its own lamp direction (core/near_light.h).
    corrected.set_near_lighting(
        {corrections.near_lights->lights(), corrected.width(), height, first_row});
  }
  return corrected;
}

}  // namespace photomat
