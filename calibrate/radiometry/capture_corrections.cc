#include "calibrate/radiometry/capture_corrections.h"

#include <fmt/format.h>

#include <utility>

#include "calibrate/radiometry/exposure.h"
#include "core/near_light.h"

namespace photomat {
namespace {

// The whole frame's size is checked here: a band's rows of a frame of another height would pass
// the band-sized checks of SubtractDarkFrame and ApplyFlatField.
void CheckFrameSize(const PhotometricSet& band, int height, int frame_width, int frame_height,
                    int frame_channels, const char* what) {
  if (frame_width != band.width() || frame_height != height) {
    band.Fail(fmt::format("the {} is {}x{} with {} channels but the images are {}x{} with {}", what,
                          frame_width, frame_height, frame_channels, band.width(), height,
                          band.channels()));
  }
}

}  // namespace

PhotometricSet CorrectCaptureBand(PhotometricSet band, int first_row, int height,
                                  CaptureCorrections& corrections) {
  const int rows = band.height();
  if (corrections.dark) {
    const Image& dark = *corrections.dark;
    CheckFrameSize(band, height, dark.width(), dark.height(), dark.channels(), "dark frame");
  }
  if (corrections.flat_field) {
    const FlatFieldBandReader& gains = *corrections.flat_field;
    CheckFrameSize(band, height, gains.width(), gains.height(), gains.channels(), "flat-field");
    if (gains.next_row() != first_row) {
      band.Fail(
          fmt::format("rows from {} corrected after the flat-field's rows up to {}: the "
                      "bands must come in row order",
                      first_row, gains.next_row()));
    }
  }
  PhotometricSet corrected = std::move(band);
  if (corrections.response) corrected = LineariseSet(corrected, *corrections.response);
  if (corrections.dark) {
    corrected = SubtractDarkFrame(corrected, Image(corrections.dark->Rows(first_row, rows)));
  }
  if (corrections.flat_field) {
    corrected = ApplyFlatField(corrected, corrections.flat_field->ReadNext(rows));
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
