#pragma once

#include <vector>

#include "core/light_direction.h"
#include "core/photometric_set.h"
#include "represent/model/method.h"
#include "represent/model/representation.h"
#include "represent/stack/map_stack.h"

namespace photomat {

// Between photomat's linear data and the interchange files (.ptm, .rti), whose coefficients
// describe sRGB-encoded display values (ptm_file.h). IMPLEMENTER CHOICE: a file is always made
// from a fit in the encoded domain, the domain PTMfitter and RTIBuilder fit in, so a photomat file
// is comparable with theirs; a biquadratic or a few harmonics in linear light are not the same
// function as in encoded values, and storing linear coefficients would darken every viewer.

// Fits `method` to the sRGB-encoded values of `set` (each linear value re-encoded with the sRGB
// curve: for 8-bit sRGB photographs exactly their codes / 255).
Representation FitEncoded(const PhotometricSet& set, const Method& method);

// Lights at which a representation is sampled when it must be refitted and its capture lights are
// unknown: the overhead light and slants 10..80 in steps of 10 degrees, every 15 degrees of tilt.
std::vector<LightDirection> RefitLights();

// `stack` as `method` (ptm, ptm-lrgb, hsh4/9/16) in sRGB-encoded values: the representation itself
// when it already is one (a .ptm or .rti read back), otherwise `method` fitted to the stack's own
// relit images (encoded when the stack is linear) at its capture lights, or RefitLights() when it
// records none. The refit is lossy: it approximates a function that was fitted in another domain
// or basis (on the PTMfitter fixture a linear PTM refitted this way is 3.8 codes RMS from the
// photographs, a direct encoded fit 0.74), so make files from the photographs when you have them.
Representation ConvertToEncoded(const LoadedStack& stack, const Method& method);

}  // namespace photomat
