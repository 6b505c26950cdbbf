#pragma once

#include <cstddef>
#include <filesystem>

#include "core/progress.h"
#include "relight/formats/ptm_file.h"
#include "relight/formats/rti_file.h"
#include "represent/model/method.h"
#include "represent/stack/stack_band_reader.h"

namespace photomat {

// The refit a .ptm or .rti is made from (README, "Streamed relighting and export"):
// ConvertToEncoded(stack, method) made one row of pixels at a time. IMPLEMENTER CHOICE: a fit's
// least squares is one matrix product over all pixels (ParallelProduct), and the kernel that
// computes a pixel's row of it depends on where the row falls in the matrix, so the same pixel
// fitted in another band differs in the last bits of its float coefficients (measured: up to 1.8e-5
// of a coefficient's range, StreamedInterchangeTest), enough to move a quantised byte now and then.
// A row fitted alone gives the same bits wherever it lies, so the in-memory export and the streamed
// one (any band height) write the same file byte for byte. Rows are fitted in parallel.
Representation RefitEncodedByRows(const LoadedStack& stack, const Method& method);

// `photomat export --ptm/--rti` of a stack read band by band (README, "Streamed relighting and
// export"): the same file as the in-memory PtmFromRepresentation / RtiFromRepresentation of
// RefitEncodedByRows(stack, method), byte for byte, without holding the stack, its relit images or
// the file's planes whole. Two passes over the stack, each refitting every band to `method`
// (RefitEncodedByRows of the band: every pixel's coefficients come from its own maps, relit at the
// same lights, so a band's refit is the whole refit's rows): (1) the per-coefficient ranges, which
// give the global scales and biases; (2) the band's bytes, written at their final offsets
// (PtmBandWriter, RtiBandWriter: the files hold rows bottom to top) into a file of full size under
// a temporary name, renamed at the end. IMPLEMENTER CHOICE: the refit is done twice rather than
// kept in a scratch file between the passes: the refit of a band costs about as much as reading it
// back from disk would, and no scratch space is needed.
struct StreamedInterchangeOptions {
  // Bytes the bands may hold; 0: DefaultBandBudget(kMinimumInterchangeMemory).
  std::size_t memory_bytes = 0;
  // > 0: exactly this many rows per band (tests).
  int band_rows = 0;
  // One phase per pass.
  Progress* progress = nullptr;
};
inline constexpr std::size_t kMinimumInterchangeMemory = std::size_t{16} << 20;

struct StreamedInterchangeReport {
  int band_rows = 0;
  int passes = 0;
};

// Writes the .ptm of `method` ("ptm" or "ptm-lrgb") to `path`; returns its header (format, size,
// scales and biases; no planes). Throws Error naming the stack or the file at fault; no file is
// left then.
PtmFile ExportPtmStreamed(StackBandReader& stack, const std::filesystem::path& path,
                          const Method& method, const StreamedInterchangeOptions& options = {},
                          StreamedInterchangeReport* report = nullptr);

// The same for an HSH .rti of `method` ("hsh4", "hsh9", "hsh16").
RtiFile ExportRtiStreamed(StackBandReader& stack, const std::filesystem::path& path,
                          const Method& method, const StreamedInterchangeOptions& options = {},
                          StreamedInterchangeReport* report = nullptr);

// Bytes per pixel of a band: the stack's band, the relit images and the fit's observation matrix
// (float, lights x channels each), the refit's maps and their quantised bytes.
std::size_t StreamedInterchangeBytesPerPixel(const StackBandReader& stack);

}  // namespace photomat
