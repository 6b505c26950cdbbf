#pragma once

#include <Eigen/Core>
#include <future>
#include <memory>
#include <mutex>
#include <optional>
#include <span>
#include <string>
#include <vector>

#include "capture/io/streamed_set.h"
#include "core/photometric_set.h"
#include "core/progress.h"
#include "represent/fitting/observations.h"
#include "represent/fitting/robust_fit.h"
#include "represent/model/method.h"
#include "represent/streaming/streamed_fit.h"

// Internal to photomat_represent_streaming: the band reading that the streamed fit (FitStreamed)
// and the streamed prediction folds (VisitFoldFits) share. Not part of the library's public
// headers.
namespace photomat::streaming_internal {

// 0, 1, ..., count - 1.
std::vector<int> AllImages(int count);

// rbf and bilinear: the light-profile models, made from the Gram pass alone.
bool IsLightProfile(const Method& method);
// Methods whose fit needs the Gram matrix of the whole set's profiles (a streamed pass first).
bool NeedsGram(const Method& method);

// One band of the set, read and prepared for fitting. Not movable: the observations refer to
// the set and the robust fit to both.
struct Band {
  int first = 0;
  int rows = 0;
  std::optional<PhotometricSet> set;  // empty when the mask selects none of its pixels
  std::optional<Observations> observations;
  std::vector<Mask> measured;
  std::optional<RobustFit> robust;

  Band() = default;
  Band(const Band&) = delete;
  Band& operator=(const Band&) = delete;
  bool empty() const { return !observations.has_value(); }

  // The profiles the Gram-based methods (Eigen-k, rbf, bilinear) fit: least squares the
  // observations' matrix itself, robust that matrix with its down-weighted samples imputed from
  // the robust photometric stereo (RobustFit::EigenStart), made once per band and shared.
  const Eigen::MatrixXf& StartProfiles() {
    if (!robust) return observations->matrix();
    if (!imputed_start) imputed_start = robust->EigenStart();
    return *imputed_start;
  }

 private:
  std::optional<Eigen::MatrixXf> imputed_start;
};

// Reads `set` in bands of `options`' rows (options.band_rows, else StreamedBandRows of the
// budget for `methods`) and hands them to a visitor pass by pass. Robust bands (options.robust)
// carry their measured masks and, with `robust_fit_of_every_image`, the robust fit of all images
// (Band::robust); prediction folds make their own robust fits, of their images.
class Streamer {
 public:
  Streamer(StreamedSet& set, std::span<const Method> methods, const StreamedFitOptions& options,
           bool robust_fit_of_every_image = true);

  int band_rows() const { return band_rows_; }
  int passes() const { return passes_; }
  const std::vector<int>& all() const { return all_; }

  // Reads the next band into `band` (which must be fresh).
  void Read(Band& band);

  // One streamed pass: `visit` sees every band in row order. The next band is decoded (and, for
  // robust fits, its robust start made) on a thread of its own while `visit` fits and writes the
  // current one, so decoding, fitting and EXR writing overlap (README, "Streamed fitting": two
  // bands are in memory at once, StreamedBandRows counts both). Bands are read in order by one
  // thread at a time, so the result does not depend on the overlap. An error in either stops
  // the pass: the reader's from get(), and a visit's only once the reader has finished (the
  // future's destructor waits), so no band outlives the pass.
  template <typename Visit>
  void Pass(const std::string& label, Visit&& visit) {
    if (passes_ > 0 || set_.next_row() != 0) set_.Rewind();
    ++passes_;
    NullProgress none;
    Progress& progress = OrNull(options_.progress, none);
    progress.Start(label, static_cast<std::size_t>(bands_));
    const auto read_band = [this] {
      auto band = std::make_unique<Band>();
      Read(*band);
      return band;
    };
    std::unique_ptr<Band> band = read_band();
    for (int b = 0; b < bands_; ++b) {
      std::future<std::unique_ptr<Band>> next;
      if (b + 1 < bands_) next = std::async(std::launch::async, read_band);
      visit(*band);
      progress.Advance();
      if (band->observations) KeepSpareMatrix(std::move(*band->observations).ReleaseMatrix());
      band.reset();
      if (next.valid()) band = next.get();
    }
    progress.Finish();
  }

 private:
  void ReadLeastSquaresBand(Band& band, std::size_t selected);
  // A fitted band's image data matrix, kept for the next band's (ReadLeastSquaresBand). Its storage
  // is one block larger than malloc's reuse threshold (core/memory_limits.h) as soon as a band
  // holds more than 32 MiB, and a fresh mapping per band would be first touched page by page
  // (system time as large as the fit's own: 6.3 s for a 12 MP PTM fit in bands of 128 MB,
  // measured).
  Eigen::MatrixXf TakeSpareMatrix();
  void KeepSpareMatrix(Eigen::MatrixXf matrix);

  StreamedSet& set_;
  const StreamedFitOptions& options_;
  bool robust_fit_of_every_image_;
  std::vector<int> all_;
  int band_rows_ = 1;
  int bands_ = 1;
  int passes_ = 0;
  std::mutex spare_mutex_;
  Eigen::MatrixXf spare_matrix_;
};

}  // namespace photomat::streaming_internal
