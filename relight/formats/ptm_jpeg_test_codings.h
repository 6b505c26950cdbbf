#pragma once

#include "relight/formats/ptm_jpeg.h"

namespace photomat::testing {

// The coding of the example, a header of HP's JPEG_LRGB files: transforms
// 1 0 0 0 0 1 0 0 0, order 8 4 3 2 1 7 5 0 6, references 5 -1 -1 -1 -1 1 7 -1 7 (a0 from the
// inverted a5, a5 from the inverted a1, R and B from G, G decoded first). Shared by the codec's
// and the file's tests.
inline PtmJpegCoding ExampleLrgbCoding(int quality) {
  const int transforms[9] = {1, 0, 0, 0, 0, 1, 0, 0, 0};
  const int order[9] = {8, 4, 3, 2, 1, 7, 5, 0, 6};
  const int references[9] = {5, -1, -1, -1, -1, 1, 7, -1, 7};
  PtmJpegCoding coding;
  coding.quality = quality;
  for (int s = 0; s < 9; ++s) {
    PtmPlaneCoding plane;
    plane.inverted = (transforms[s] & 1) != 0;
    plane.order = order[s];
    plane.reference = references[s];
    coding.planes.push_back(plane);
  }
  return coding;
}

}  // namespace photomat::testing
