#include "synthesize/texture/overlap_search.h"

#include <fmt/format.h>
#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <complex>
#include <limits>
#include <mutex>

#include "core/enum_names.h"
#include "core/error.h"
#include "core/fft.h"

namespace photomat {
namespace {

// Unit roundoff of float and double.
constexpr double kFloatEpsilon = 0x1.0p-24;
constexpr double kDoubleEpsilon = 0x1.0p-53;

// Relative slack for the exact sums themselves (double, at most a few thousand terms).
constexpr double kExactSlack = 1e-12;

// The smallest size >= n with no prime factor above 5 (sizes FFTW transforms fastest).
int FftFriendlySize(int n) {
  for (int m = n;; ++m) {
    int r = m;
    for (int p : {2, 3, 5}) {
      while (r % p == 0) r /= p;
    }
    if (r == 1) return m;
  }
}

using Complex = std::complex<double>;

// The smallest value (four running minima break the dependency chain of one).
double Minimum(const std::vector<double>& values) {
  double m[4] = {std::numeric_limits<double>::infinity(), std::numeric_limits<double>::infinity(),
                 std::numeric_limits<double>::infinity(), std::numeric_limits<double>::infinity()};
  std::size_t i = 0;
  for (; i + 4 <= values.size(); i += 4) {
    for (int k = 0; k < 4; ++k) m[k] = std::min(m[k], values[i + k]);
  }
  for (; i < values.size(); ++i) m[0] = std::min(m[0], values[i]);
  return std::min(std::min(m[0], m[1]), std::min(m[2], m[3]));
}

constexpr std::array<NamedValue<SearchMode>, 2> kSearchModeNames = {
    {{SearchMode::kFast, "fast"}, {SearchMode::kBruteForce, "brute"}}};

}  // namespace

std::string_view ToString(SearchMode mode) { return NameOf(mode, kSearchModeNames); }

SearchMode ParseSearchMode(std::string_view name) {
  return ValueNamed(name, kSearchModeNames, "search mode");
}

// SSD by correlation: the sample planes' spectra once, each template's per block. The correlation
// is circular over the padded size; a candidate's window never crosses the edge, so no wrapped
// value enters a candidate's sum.
struct OverlapSearch::Fft {
  // `width` x `height` padded; the template transform reads `block` rows, and its inverse writes
  // the `candidate_rows` rows of candidates.
  Fft(int padded_width, int padded_height, int block, int candidate_rows)
      : correlation(padded_width, padded_height, {block, candidate_rows}) {}

  // The correlation's 2-D transforms split into their row and column passes (core/fft.h,
  // FftRows), so that a template's all-zero rows below the block skip the row pass, and the
  // inverse's row pass stops at the last row of candidates.
  RealFft2d<double> correlation;
  std::vector<FftArray<Complex>> spectra;  // per channel, of the sample
  std::vector<double> plane_norms;
  std::vector<double> squares_integral;  // (H + 1) x (W + 1) of sum_c M_c^2
  double squares_total = 0.0;

  int width() const { return correlation.width(); }
  int height() const { return correlation.height(); }
  double SumOfBox(int sample_width, int x, int y, int w, int h) const {
    if (w <= 0 || h <= 0) return 0.0;
    const std::size_t stride = static_cast<std::size_t>(sample_width) + 1;
    auto at = [&](int xx, int yy) { return squares_integral[yy * stride + xx]; };
    return at(x + w, y + h) - at(x + w, y) - at(x, y + h) + at(x, y);
  }
};

// Buffers one search needs, kept between searches (allocating them anew would page-fault).
struct OverlapSearch::Workspace {
  std::vector<FftArray<double>> template_planes;  // padded, zero outside the block
  std::vector<FftArray<Complex>> spectra;         // per channel: spectrum, then its product
  FftArray<Complex> sum;
  FftArray<double> correlation;
  std::vector<double> low, high;
};

OverlapTemplate::OverlapTemplate(const OverlapShape& overlap, int channel_count)
    : shape(overlap),
      channels(channel_count),
      values(static_cast<std::size_t>(channel_count) * overlap.block * overlap.block, 0.0f) {}

OverlapSearch::OverlapSearch(const Image& space, int block_size, ErrorMetric metric, int stride)
    : space_(space), block_(block_size), metric_(metric), stride_(stride) {
  if (block_size < 2 || block_size > space.width() || block_size > space.height()) {
    throw Error(fmt::format("a {}-pixel block does not fit in the {}x{} sample", block_size,
                            space.width(), space.height()));
  }
  if (stride < 1) throw Error(fmt::format("candidate stride {} is not positive", stride));
  columns_ = (space.width() - block_size) / stride + 1;
  rows_ = (space.height() - block_size) / stride + 1;
  if (metric != ErrorMetric::kSsd) return;
  const int candidate_rows = (rows_ - 1) * stride_ + 1;
  fft_ = std::make_unique<Fft>(FftFriendlySize(space.width()), FftFriendlySize(space.height()),
                               block_size, candidate_rows);
  Fft& fft = *fft_;
  const RealFft2d<double> sample_transform(fft.width(), fft.height());
  FftArray<double> plane(sample_transform.size());
  const int n = space.channels();
  const std::size_t integral_stride = static_cast<std::size_t>(space.width()) + 1;
  fft.squares_integral.assign(integral_stride * (space.height() + 1), 0.0);
  std::vector<double> squares(static_cast<std::size_t>(space.width()) * space.height(), 0.0);
  for (int c = 0; c < n; ++c) {
    double norm2 = 0.0;
    for (int y = 0; y < space.height(); ++y) {
      for (int x = 0; x < space.width(); ++x) {
        const double v = space.at(x, y, c);
        plane[static_cast<std::size_t>(y) * fft.width() + x] = v;
        squares[static_cast<std::size_t>(y) * space.width() + x] += v * v;
        norm2 += v * v;
      }
    }
    FftArray<Complex> channel(sample_transform.spectrum_size());
    sample_transform.Forward(plane, channel);
    fft.spectra.push_back(std::move(channel));
    fft.plane_norms.push_back(std::sqrt(norm2));
  }
  for (int y = 0; y < space.height(); ++y) {
    double row = 0.0;
    for (int x = 0; x < space.width(); ++x) {
      row += squares[static_cast<std::size_t>(y) * space.width() + x];
      fft.squares_integral[(y + 1) * integral_stride + x + 1] =
          fft.squares_integral[y * integral_stride + x + 1] + row;
    }
  }
  fft.squares_total = fft.squares_integral.back();
}

OverlapSearch::~OverlapSearch() = default;

const std::vector<double>& OverlapSearch::SquaresUnder(const OverlapShape& shape) const {
  const std::lock_guard<std::mutex> lock(pool_mutex_);
  for (const auto& [known, squares] : squares_under_) {
    if (known == shape) return squares;
  }
  // sum_c M_c^2 over the overlap of every candidate: the block's box minus its inner box.
  std::vector<double> squares(static_cast<std::size_t>(candidate_count()));
  const int inner_width = block_ - shape.left - shape.right;
  const int inner_height = block_ - shape.top - shape.bottom;
  for (int row = 0; row < rows_; ++row) {
    for (int column = 0; column < columns_; ++column) {
      const int x = column * stride_, y = row * stride_;
      squares[static_cast<std::size_t>(row) * columns_ + column] =
          fft_->SumOfBox(space_.width(), x, y, block_, block_) -
          fft_->SumOfBox(space_.width(), x + shape.left, y + shape.top, inner_width, inner_height);
    }
  }
  // A list keeps references valid as shapes are added (a quilt has a handful of shapes).
  squares_under_.emplace_back(shape, std::move(squares));
  return squares_under_.back().second;
}

std::unique_ptr<OverlapSearch::Workspace> OverlapSearch::Borrow() const {
  {
    const std::lock_guard<std::mutex> lock(pool_mutex_);
    if (!pool_.empty()) {
      std::unique_ptr<Workspace> workspace = std::move(pool_.back());
      pool_.pop_back();
      return workspace;
    }
  }
  auto workspace = std::make_unique<Workspace>();
  const std::size_t count = static_cast<std::size_t>(candidate_count());
  workspace->low.resize(count);
  workspace->high.resize(count);
  if (fft_) {
    const RealFft2d<double>& transform = fft_->correlation;
    for (int c = 0; c < space_.channels(); ++c) {
      workspace->template_planes.emplace_back(transform.size());
      workspace->spectra.emplace_back(transform.spectrum_size());
    }
    workspace->sum = FftArray<Complex>(transform.spectrum_size());
    workspace->correlation = FftArray<double>(transform.size());
  }
  return workspace;
}

void OverlapSearch::Return(std::unique_ptr<Workspace> workspace) const {
  const std::lock_guard<std::mutex> lock(pool_mutex_);
  pool_.push_back(std::move(workspace));
}

double OverlapSearch::ExactError(const OverlapTemplate& pattern, SamplePixel candidate) const {
  // Four partial sums (by column modulo 4) break the dependency chain of one running sum; the
  // order is fixed, so every caller gets the same bits.
  double partial[4] = {0.0, 0.0, 0.0, 0.0};
  const OverlapShape& shape = pattern.shape;
  const int n = space_.channels();
  const bool squared = metric_ == ErrorMetric::kSsd;
  auto add_run = [&](const float* sample, const float* wanted, int first, int last) {
    for (int u = first; u < last; ++u) {
      const double d = static_cast<double>(sample[u]) - wanted[u];
      partial[u & 3] += squared ? d * d : std::abs(d);
    }
  };
  for (int v = 0; v < block_; ++v) {
    const bool full_row = v < shape.top || v >= block_ - shape.bottom;
    for (int c = 0; c < n; ++c) {
      const float* sample = space_.plane(c).data() +
                            static_cast<std::size_t>(candidate.y + v) * space_.width() +
                            candidate.x;
      const float* wanted =
          pattern.values.data() + (static_cast<std::size_t>(c) * block_ + v) * block_;
      if (full_row) {
        add_run(sample, wanted, 0, block_);
      } else {
        add_run(sample, wanted, 0, shape.left);
        add_run(sample, wanted, block_ - shape.right, block_);
      }
    }
  }
  return (partial[0] + partial[1]) + (partial[2] + partial[3]);
}

void OverlapSearch::BoundFft(const OverlapTemplate& pattern, Workspace& workspace) const {
  const int n = space_.channels();
  const OverlapShape& shape = pattern.shape;
  double template_energy = 0.0;
  std::vector<double> template_l1(n, 0.0), template_l2(n, 0.0);  // |T_c|_1 and |T_c|_2^2
  for (int c = 0; c < n; ++c) {
    for (int v = 0; v < block_; ++v) {
      for (int u = 0; u < block_; ++u) {
        const double t = pattern.at(u, v, c);
        template_energy += t * t;
        template_l1[c] += std::abs(t);
        template_l2[c] += t * t;
      }
    }
  }
  // One forward transform per channel and its product with the conjugate of the sample's
  // spectrum, channels in parallel; summed in channel order; one inverse.
  const Fft& fft = *fft_;
  const RealFft2d<double>& transform = fft.correlation;
  const std::size_t spectrum_size = transform.spectrum_size();
  tbb::parallel_for(0, n, [&](int c) {
    double* plane = workspace.template_planes[c].data();
    for (int v = 0; v < block_; ++v) {
      for (int u = 0; u < block_; ++u) plane[v * fft.width() + u] = pattern.at(u, v, c);
    }
    // The rows below the block are zero (the transform skips them).
    transform.Forward(workspace.template_planes[c], workspace.spectra[c]);
    Complex* product = workspace.spectra[c].data();
    const Complex* sample = fft.spectra[c].data();
    for (std::size_t k = 0; k < spectrum_size; ++k) {
      // sample * conj(template), written out (std::complex's product checks for NaN).
      const double re = sample[k].real() * product[k].real() + sample[k].imag() * product[k].imag();
      const double im = sample[k].imag() * product[k].real() - sample[k].real() * product[k].imag();
      product[k] = {re, im};
    }
  });
  Complex* sum = workspace.sum.data();
  std::copy_n(workspace.spectra[0].data(), spectrum_size, sum);
  for (int c = 1; c < n; ++c) {
    const Complex* product = workspace.spectra[c].data();
    for (std::size_t k = 0; k < spectrum_size; ++k) sum[k] += product[k];
  }
  double* correlation = workspace.correlation.data();
  transform.Inverse(workspace.sum, workspace.correlation);  // unscaled: times width * height
  const double unscale = 1.0 / (static_cast<double>(fft.width()) * fft.height());

  // Rounding of the FFT correlation, per channel and output value, is at most of the order of
  // u log2(N) |M|_2 (|T|_1 + sqrt(N) |T|_2): the transforms are normwise stable (error
  // ~ u log2(N) times the transformed norm), the error of FFT(M) is weighted by
  // max|FFT(T)| <= |T|_1, the error of FFT(T) by |FFT(M)|_2 = sqrt(N) |M|_2, and the inverse
  // maps a 2-norm error e to at most e / sqrt(N) in any value. The integral image adds
  // ~ (W + H) u sum(M^2). Both are inflated a thousandfold (IMPLEMENTER CHOICE): the bound only
  // decides which candidates are re-scored exactly, so generosity costs a few exact sums while a
  // bound that failed would break equality with brute force.
  const double size = static_cast<double>(fft.width()) * fft.height();
  double correlation_bound = 0.0;
  for (int c = 0; c < n; ++c) {
    correlation_bound += fft.plane_norms[c] * (template_l1[c] + std::sqrt(size * template_l2[c]));
  }
  correlation_bound *= 2.0 * std::log2(size) * kDoubleEpsilon;
  const double integral_bound =
      4.0 * (space_.width() + space_.height()) * kDoubleEpsilon * fft.squares_total;
  const double slack = 1000.0 * (correlation_bound + integral_bound);

  const std::vector<double>& all_squares = SquaresUnder(shape);
  tbb::parallel_for(0, rows_, [&](int row) {
    const int y = row * stride_;
    const double* correlation_row = correlation + static_cast<std::size_t>(y) * fft.width();
    for (int column = 0; column < columns_; ++column) {
      const int x = column * stride_;
      const double squares = all_squares[static_cast<std::size_t>(row) * columns_ + column];
      const double estimate = squares - 2.0 * unscale * correlation_row[x] + template_energy;
      const double margin = slack + kExactSlack * (squares + template_energy);
      const std::size_t index = static_cast<std::size_t>(row) * columns_ + column;
      workspace.low[index] = estimate - margin;
      workspace.high[index] = estimate + margin;
    }
  });
}

void OverlapSearch::BoundDirect(const OverlapTemplate& pattern, Workspace& workspace) const {
  const int n = space_.channels();
  const int width = space_.width();
  const int span = space_.width() - block_ + 1;  // every x; strided columns are read from it
  struct Term {
    std::size_t offset;  // of the pixel within the block window, in its plane
    int channel;
    float value;
  };
  std::vector<Term> terms;
  for (int v = 0; v < block_; ++v) {
    for (int u = 0; u < block_; ++u) {
      if (!pattern.shape.Contains(u, v)) continue;
      for (int c = 0; c < n; ++c) {
        terms.push_back({static_cast<std::size_t>(v) * width + u, c, pattern.at(u, v, c)});
      }
    }
  }
  // Each candidate's float sum has terms with relative error <= 2u and accumulation error
  // <= (terms) u: its exact value lies within gamma of it (IMPLEMENTER CHOICE: gamma inflated by
  // 5 % and 8 extra terms for the conversions).
  const double gamma = 1.05 * (static_cast<double>(terms.size()) + 8.0) * kFloatEpsilon;
  const bool squared = metric_ == ErrorMetric::kSsd;
  tbb::parallel_for(tbb::blocked_range<int>(0, rows_), [&](const tbb::blocked_range<int>& range) {
    std::vector<float> sums(span);
    for (int row = range.begin(); row != range.end(); ++row) {
      const std::size_t origin = static_cast<std::size_t>(row) * stride_ * width;
      std::fill(sums.begin(), sums.end(), 0.0f);
      float* acc = sums.data();
      for (const Term& term : terms) {
        const float* line = space_.plane(term.channel).data() + origin + term.offset;
        AccumulatePairErrors(squared, line, term.value, span, acc);
      }
      for (int column = 0; column < columns_; ++column) {
        const double estimate = sums[column * stride_];
        const std::size_t index = static_cast<std::size_t>(row) * columns_ + column;
        workspace.low[index] = estimate / (1.0 + gamma) * (1.0 - kExactSlack);
        workspace.high[index] = estimate / (1.0 - gamma) * (1.0 + kExactSlack);
      }
    }
  });
}

QualifyingBlocks OverlapSearch::Qualifying(const OverlapTemplate& pattern, double tolerance,
                                           double floor, SearchMode mode) const {
  if (pattern.shape.block != block_ || pattern.channels != space_.channels()) {
    throw Error("an overlap template of the wrong block size or channel count");
  }
  const int count = candidate_count();
  QualifyingBlocks result;
  // Exact errors of the candidates at `indices`, in parallel.
  auto exact_errors = [&](const std::vector<int>& indices) {
    std::vector<double> exact(indices.size());
    tbb::parallel_for(std::size_t{0}, indices.size(), [&](std::size_t k) {
      exact[k] = ExactError(pattern, Candidate(indices[k]));
    });
    result.rescored += static_cast<int>(indices.size());
    return exact;
  };
  if (mode == SearchMode::kBruteForce) {
    std::vector<int> all(count);
    for (int i = 0; i < count; ++i) all[i] = i;
    const std::vector<double> exact = exact_errors(all);
    const double best = *std::min_element(exact.begin(), exact.end());
    result.threshold = (1.0 + tolerance) * std::max(best, floor);
    for (int i = 0; i < count; ++i) {
      if (exact[i] <= result.threshold) result.positions.push_back(Candidate(i));
    }
    return result;
  }

  std::unique_ptr<Workspace> workspace = Borrow();
  if (metric_ == ErrorMetric::kSsd) {
    BoundFft(pattern, *workspace);
  } else {
    BoundDirect(pattern, *workspace);
  }
  const std::vector<double>& low = workspace->low;
  const std::vector<double>& high = workspace->high;
  // The threshold (1 + tolerance) * max(best, floor) exactly as brute force computes it: when
  // even the best upper bound is under the floor, the floor decides; otherwise the best exact
  // error, which is among the candidates whose lower bound reaches the best upper bound.
  const double best_high = Minimum(high);
  if (best_high <= floor) {
    result.threshold = (1.0 + tolerance) * floor;
  } else {
    std::vector<int> contenders;
    for (int i = 0; i < count; ++i) {
      if (low[i] <= best_high) contenders.push_back(i);
    }
    const std::vector<double> exact = exact_errors(contenders);
    result.threshold =
        (1.0 + tolerance) * std::max(*std::min_element(exact.begin(), exact.end()), floor);
  }
  // Candidates wholly under the threshold qualify, wholly over it do not; the exact error decides
  // only for those whose bounds straddle it (kept in order, encoded as -1 - index).
  std::vector<int> maybe;
  std::vector<int> straddling;
  for (int i = 0; i < count; ++i) {
    if (high[i] <= result.threshold) {
      maybe.push_back(i);
    } else if (low[i] <= result.threshold) {
      maybe.push_back(-1 - i);
      straddling.push_back(i);
    }
  }
  Return(std::move(workspace));
  const std::vector<double> exact = exact_errors(straddling);
  std::size_t next = 0;
  for (int code : maybe) {
    if (code >= 0) {
      result.positions.push_back(Candidate(code));
    } else if (exact[next++] <= result.threshold) {
      result.positions.push_back(Candidate(-1 - code));
    }
  }
  return result;
}

}  // namespace photomat
