#pragma once

#include <cstddef>
#include <filesystem>
#include <optional>
#include <span>
#include <vector>

#include "capture/io/streamed_set.h"
#include "core/image_io.h"
#include "core/progress.h"
#include "represent/fitting/pbr_fit_summary.h"
#include "represent/fitting/robust_fit.h"
#include "represent/model/method.h"
#include "represent/stack/map_stack.h"
#include "represent/stack/stack_band_writer.h"

namespace photomat {

// Streamed fitting (README, "Streamed fitting"): every method fitted to a set in bands of rows,
// so that memory follows the band, not the image. Every image is held open (StreamedSet) and a
// band of rows is decoded from each, in parallel; the band is fitted by the in-memory fits
// (fit.h, robust_fit.h: every method is per pixel once its light basis is known) and its maps go
// straight into each method's map stack (StackBandWriter). Global passes stream too: Eigen-k,
// rbf and bilinear accumulate the Gram matrix and the column sums of the profiles they fit
// over one pass (RowGram: the same sum for any band; robust: of the imputed profiles,
// RobustFit::EigenStart), which fixes Eigen-k's basis and the light-profile models (kernel
// width by leave-one-out, PCA axes, plane signs); robust Eigen-k makes one such pass more per
// further EM iteration (the robust weights recomputed per band: memory stays bounded, at the
// cost of kRobustEigenIterations + 1 robust fits of every band). Every stack is written to a
// temporary name and all are renamed at the end: a fault anywhere (a truncated image mid-way)
// leaves none. The maps equal the in-memory fit's to float rounding for any band height, and are
// the same bits run after run.

struct StreamedFitOptions {
  // Bytes the bands may hold (images, their copy for fitting, the robust weights, one method's
  // maps); 0: DefaultStreamedBudget(set). Sets the band height (StreamedBandRows).
  std::size_t memory_bytes = 0;
  // > 0: exactly this many rows per band, whatever the budget (tests of band independence).
  int band_rows = 0;
  bool robust = false;
  // Fit the sRGB-encoded values (each linear value, its intensity divided out, re-encoded with
  // the sRGB curve), as FitEncoded (relight/formats/interchange.h) does in memory: the domain of
  // the .ptm and .rti files. Least squares only; the stacks' provenance should then say "srgb".
  bool encoded_values = false;
  // For robust fits. `measured` and `progress` are ignored: the measured masks are found per band
  // on the values as captured (MeasuredPixelMasks), before the intensities are applied.
  RobustFitOptions robust_options;
  ExrCompression compression = kDefaultExrCompression;
  StackProvenance provenance;
  // One phase per streamed pass, one step per band.
  Progress* progress = nullptr;
};

struct StreamedFitReport {
  int band_rows = 0;
  int passes = 0;               // streamed passes over the images (the global ones, then maps)
  std::vector<int> map_counts;  // per method, the maps of its stack
  // Robust fits: the weights' summary over the whole set. Each stack's details hold it too
  // ("robust_summary", and a pbr stack its "pbr_summary"), written into its description when the
  // last band is (StackBandWriter's late details).
  std::optional<RobustFitSummary> robust_summary;
  // A pbr fit's summary over the whole set: its bands' summed.
  std::optional<PbrFitSummary> pbr_summary;
  std::vector<std::size_t> saturated_pixels;  // per image, clipped pixels
};

// Fits `methods` to `set` (at its first row) and writes method i's stack to `stacks[i]`. Throws
// Error naming the set's source or the image at fault; nothing is then left at `stacks`.
StreamedFitReport FitStreamed(StreamedSet& set, std::span<const Method> methods,
                              std::span<const std::filesystem::path> stacks,
                              const StreamedFitOptions& options = {});

// DefaultMemoryBudget(kMinimumFitMemory) (core/memory_limits.h: half the physical memory, at
// most half of the process's cgroup and address-space limits).
std::size_t DefaultFitMemory();
inline constexpr std::size_t kMinimumFitMemory = std::size_t{16} << 20;

// The budget a fit of `set` uses when none is given: DefaultBandBudget (core/memory_limits.h:
// kFastBandMemory, at most DefaultFitMemory()) beyond the decoders' chunks.
std::size_t DefaultStreamedBudget(const StreamedSet& set);

// The rows per band that `memory_bytes` allows for `methods` on `set` (at least 1, at most the
// image height), from the bytes per row the band holds (README, "Streamed fitting"), with
// `concurrent_fits` fits of a band in flight at once (prediction folds: one per thread).
int StreamedBandRows(std::size_t memory_bytes, const StreamedSet& set,
                     std::span<const Method> methods, bool robust, int concurrent_fits = 1);

// The bytes the stacks of `methods` fitted to `set` take on disk at most (ImageFileBytes of their
// maps as float, core/disk_space.h): `photomat fit` checks the free space for them first.
std::size_t StreamedStackBytes(const StreamedSet& set, std::span<const Method> methods);

}  // namespace photomat
