#pragma once

#include <filesystem>
#include <optional>
#include <string>
#include <vector>

#include "core/image_io.h"
#include "represent/fitting/pbr_fit_summary.h"
#include "represent/fitting/robust_fit.h"
#include "represent/model/representation.h"
#include "represent/stack/map_stack.h"
#include "represent/stack/stack_band_writer.h"

namespace photomat {

// One method's stack written from the fits of its bands (README, "Streamed fitting"): a streamed
// fit's (FitStreamed) and the fit of every image that a streamed evaluation makes beside its
// prediction folds (StreamedPredictionOptions::whole_set_fit). The file is opened at the first
// band fitted, whose representation describes the whole stack; rows no band covers (bands the
// mask leaves empty, which are not fitted) are zero maps. The data summaries of the details
// ("robust_summary", "pbr_summary") are the whole set's, the bands' summed (StackBandWriter's
// late details), not the first band's. Written to a temporary name; Commit() renames it into
// place, and a writer destroyed without Commit() leaves nothing.
class FittedStackWriter {
 public:
  FittedStackWriter(std::filesystem::path path, int width, int height, ExrCompression compression,
                    StackProvenance provenance);

  // The band's fit, its maps rows [first_row, first_row + maps' height) of the stack. Bands come
  // in row order. Throws Error naming the stack for a band before the rows already written or
  // reaching past the stack's height.
  void Write(int first_row, const Representation& band);
  // The rows after the last band as zeros, the summaries, the rename. Throws Error naming the
  // stack when no band was written.
  void Commit();
  // The stack's maps (0 before the first band).
  int maps() const { return static_cast<int>(names_.size()); }

 private:
  void WriteZeros(int rows);

  std::filesystem::path path_;
  int width_, height_;
  ExrCompression compression_;
  StackProvenance provenance_;
  std::vector<std::string> names_;
  std::optional<StackBandWriter> writer_;
  std::optional<RobustFitSummary> robust_summary_;  // the bands' summed
  std::optional<PbrFitSummary> pbr_summary_;
  int next_row_ = 0;
};

}  // namespace photomat
