#pragma once

#include <cstddef>
#include <filesystem>
#include <string>
#include <vector>

#include "capture/io/streamed_set.h"
#include "represent/streaming/streamed_fit.h"

namespace photomat::app {

// What the commands that read a photometric set streamed instead of whole share (`export` and
// `evaluate` of a set, README "From the photographs").

// Whether holding `set` whole (kWholeSetBytesPerPixelImage per pixel and image,
// capture/io/load_photometric_set.h) would exceed `budget_bytes`: then a command streams it.
bool HoldingSetExceeds(const StreamedSet& set, std::size_t budget_bytes);

// The stacks of `methods` in `folder` (a scratch folder the command reads them back from), named
// by method, with `options`' compression (lossless, as `fit` compresses by default) and
// provenance (`set`'s lights, `source` and the encoding `options.encoded_values` fits: "srgb",
// else "linear") set; the folder's free space checked for them first. Returns the stacks in the
// order of `methods`.
std::vector<std::filesystem::path> PlanScratchStacks(const StreamedSet& set,
                                                     const std::vector<Method>& methods,
                                                     const std::filesystem::path& folder,
                                                     const std::string& source,
                                                     StreamedFitOptions& options);

// `methods` fitted to `set` in bands (FitStreamed) into map stacks in `folder` (a scratch folder
// the command reads them back from), named by method: the folder's free space checked for them
// first, lossless EXR compressed as `fit` compresses by default, the provenance `set`'s lights,
// `source` and the encoding `options.encoded_values` fits ("srgb", else "linear"), and one line
// printed saying what was fitted in what bands. With `warn_clipped`, clipped pixels are warned
// about as `fit` warns. Returns the stacks in the order of `methods`.
std::vector<std::filesystem::path> FitIntoFolder(StreamedSet& set,
                                                 const std::vector<Method>& methods,
                                                 const std::filesystem::path& folder,
                                                 const std::string& source,
                                                 StreamedFitOptions options, bool warn_clipped);

}  // namespace photomat::app
