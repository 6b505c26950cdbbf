#pragma once

#include <list>
#include <memory>
#include <mutex>
#include <string_view>
#include <utility>
#include <vector>

#include "synthesize/texture/block_placement.h"
#include "synthesize/texture/matching_space.h"

namespace photomat {

// How the overlap error of every candidate block is computed.
//  kBruteForce: the exact error of each candidate, summed pixel by pixel (the reference).
//  kFast: SSD through FFT correlation (FFTW: E = sum M^2 - 2 corr(M, T) + sum T^2, the first term
//    from an integral image), SAD through vectorised, multi-threaded direct sums. Both give each
//    candidate an interval that provably holds its exact error. The exact threshold is found from
//    the few candidates that can be the best, and only candidates whose interval straddles it are
//    re-scored with the same exact sum as brute force (an interval wholly under or over it
//    decides alone). The blocks chosen are therefore identical to brute force for the same seed,
//    on any number of threads.
enum class SearchMode { kBruteForce, kFast };
std::string_view ToString(SearchMode mode);
// "brute" or "fast"; throws Error otherwise.
SearchMode ParseSearchMode(std::string_view name);

// The already-synthesised pixels a candidate block must match: the overlap shape and, per channel,
// a block_size x block_size plane of scaled values (0 outside the overlap).
struct OverlapTemplate {
  OverlapShape shape;
  int channels = 0;
  std::vector<float> values;  // channel-major planes, row-major within a plane

  OverlapTemplate(const OverlapShape& overlap, int channel_count);
  float& at(int u, int v, int c) {
    return values[(static_cast<std::size_t>(c) * shape.block + v) * shape.block + u];
  }
  float at(int u, int v, int c) const {
    return values[(static_cast<std::size_t>(c) * shape.block + v) * shape.block + u];
  }
};

// The candidates whose error lies within the tolerance of the best, in raster order of their
// sample positions, and the threshold they were held to.
struct QualifyingBlocks {
  std::vector<SamplePixel> positions;
  double threshold = 0.0;  // (1 + tolerance) * max(best error, floor)
  int rescored = 0;        // exact evaluations (all candidates for brute force)
};

// Every sample position of a block_size x block_size block (on a grid of `stride`) is a candidate.
// Thread-safe: several blocks can be searched at once (each search borrows its own work buffers).
class OverlapSearch {
 public:
  OverlapSearch(const Image& space, int block_size, ErrorMetric metric, int stride);
  ~OverlapSearch();
  OverlapSearch(const OverlapSearch&) = delete;
  OverlapSearch& operator=(const OverlapSearch&) = delete;

  int candidate_columns() const { return columns_; }
  int candidate_rows() const { return rows_; }
  int candidate_count() const { return columns_ * rows_; }
  SamplePixel Candidate(int index) const {
    return {(index % columns_) * stride_, (index / columns_) * stride_};
  }

  // The exact overlap error of the block at `candidate`: a sum in double over the overlap
  // pixels, row by row and channel by channel, in a fixed order. The reference for every mode.
  double ExactError(const OverlapTemplate& pattern, SamplePixel candidate) const;

  // The candidates with error <= (1 + tolerance) * max(min_error, floor).
  QualifyingBlocks Qualifying(const OverlapTemplate& pattern, double tolerance, double floor,
                              SearchMode mode) const;

 private:
  struct Fft;
  struct Workspace;
  // Lower and upper bounds of every candidate's exact error, into workspace.low / high.
  void BoundFft(const OverlapTemplate& pattern, Workspace& workspace) const;
  void BoundDirect(const OverlapTemplate& pattern, Workspace& workspace) const;
  // sum_c M_c^2 over `shape`'s overlap at every candidate (SSD's first term), computed once per
  // shape.
  const std::vector<double>& SquaresUnder(const OverlapShape& shape) const;
  std::unique_ptr<Workspace> Borrow() const;
  void Return(std::unique_ptr<Workspace> workspace) const;

  const Image& space_;
  int block_;
  ErrorMetric metric_;
  int stride_;
  int columns_ = 0;
  int rows_ = 0;
  // SSD by FFT: the sample planes' spectra, their norms and the integral image of sum_c M_c^2
  // (OpenCV types, kept out of this header).
  std::unique_ptr<Fft> fft_;
  // Work buffers of finished searches, for the next ones, and the overlap sums per shape.
  mutable std::mutex pool_mutex_;
  mutable std::vector<std::unique_ptr<Workspace>> pool_;
  mutable std::list<std::pair<OverlapShape, std::vector<double>>> squares_under_;
};

}  // namespace photomat
