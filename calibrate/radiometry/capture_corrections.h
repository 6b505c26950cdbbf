#pragma once

#include <optional>

#include "calibrate/radiometry/flat_field.h"
#include "calibrate/radiometry/response_curve.h"
#include "core/image.h"
#include "core/photometric_set.h"

namespace photomat {

// The radiometric corrections of `photomat calibrate apply`, made in this order: linearise the
// codes with a camera response curve (the images read as codes, ColourSpace::kLinear), subtract
// a dark frame, divide by a flat-field's gains: a target's (one gain map per light, read band by
// band from its folder) or near lamps' fall-off (computed band by band). Dividing by the light
// intensities comes after them, outside (semi-calibrated intensities are estimated from the
// corrected images).
struct CaptureCorrections {
  std::optional<ResponseCurve> response;
  std::optional<Image> dark;
  std::optional<FlatFieldBandReader> flat_field;
  std::optional<NearLightGains> near_lights;
};

// Corrects rows [first_row, first_row + band.height()) of a capture `height` rows high: `band`
// as StreamedSet::ReadBand gives them (raw; its intensities are kept). Every correction acts on a
// pixel alone, so the rows equal those of the whole capture corrected at once, bit for bit, for
// any band. With near lamps the band gets their NearLighting (the whole frame, first_row). A
// target's flat-field is read in order: the bands must come in row order, each starting where the
// last ended (as a StreamedSet gives them). Throws Error naming the band's source when a dark
// frame or flat-field does not fit the capture's size, channels or lights (as SubtractDarkFrame
// and ApplyFlatField do), or a band comes out of order.
PhotometricSet CorrectCaptureBand(PhotometricSet band, int first_row, int height,
                                  CaptureCorrections& corrections);

}  // namespace photomat
