#include "synthesize/overlap_search.h"

#include <fmt/format.h>
#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>

#include <algorithm>
#include <cmath>
#include <limits>
#include <opencv2/core.hpp>
#include <opencv2/imgproc.hpp>

#include "core/error.h"

namespace photomat {
namespace {

// Unit roundoff of float and double.
constexpr double kFloatEpsilon = 0x1.0p-24;
constexpr double kDoubleEpsilon = 0x1.0p-53;

// Relative slack for the exact sums themselves (double, at most a few thousand terms).
constexpr double kExactSlack = 1e-12;

double SumOfBox(const cv::Mat& integral, int x, int y, int width, int height) {
  if (width <= 0 || height <= 0) return 0.0;
  return integral.at<double>(y + height, x + width) - integral.at<double>(y, x + width) -
         integral.at<double>(y + height, x) + integral.at<double>(y, x);
}

}  // namespace

std::string_view ToString(SearchMode mode) {
  return mode == SearchMode::kBruteForce ? "brute" : "fast";
}

SearchMode ParseSearchMode(std::string_view name) {
  if (name == "brute") return SearchMode::kBruteForce;
  if (name == "fast") return SearchMode::kFast;
  throw Error(fmt::format("unknown search mode '{}' (fast or brute)", name));
}

struct OverlapSearch::Fft {
  cv::Size padded;
  std::vector<cv::Mat> spectra;
  std::vector<double> plane_norms;
  cv::Mat squares_integral;
  double squares_total = 0.0;
};

// Buffers one search needs, kept between searches (allocating them anew would page-fault).
struct OverlapSearch::Workspace {
  std::vector<cv::Mat> template_planes;  // padded, zero outside the block
  std::vector<cv::Mat> spectra;
  std::vector<cv::Mat> products;
  cv::Mat sum;
  cv::Mat correlation;
  std::vector<double> low, high;
};

OverlapTemplate::OverlapTemplate(const OverlapShape& overlap, int channel_count)
    : shape(overlap),
      channels(channel_count),
      values(static_cast<std::size_t>(channel_count) * overlap.block * overlap.block, 0.0f) {}

OverlapSearch::OverlapSearch(const PlanarImage& space, int block_size, ErrorMetric metric,
                             int stride)
    : space_(space), block_(block_size), metric_(metric), stride_(stride) {
  if (block_size < 2 || block_size > space.width() || block_size > space.height()) {
    throw Error(fmt::format("a {}-pixel block does not fit in the {}x{} sample", block_size,
                            space.width(), space.height()));
  }
  if (stride < 1) throw Error(fmt::format("candidate stride {} is not positive", stride));
  columns_ = (space.width() - block_size) / stride + 1;
  rows_ = (space.height() - block_size) / stride + 1;
  if (metric != ErrorMetric::kSsd) return;
  fft_ = std::make_unique<Fft>();

  // SSD by correlation: the sample planes' spectra once, each template's per block. The
  // correlation is circular over the padded size; a candidate's window never crosses the edge,
  // so no wrapped value enters a candidate's sum.
  fft_->padded = {cv::getOptimalDFTSize(space.width()), cv::getOptimalDFTSize(space.height())};
  const int n = space.channels();
  cv::Mat squares(space.height(), space.width(), CV_64F, cv::Scalar(0.0));
  for (int c = 0; c < n; ++c) {
    cv::Mat plane(fft_->padded, CV_64F, cv::Scalar(0.0));
    double norm2 = 0.0;
    for (int y = 0; y < space.height(); ++y) {
      for (int x = 0; x < space.width(); ++x) {
        const double v = space.at(x, y, c);
        plane.at<double>(y, x) = v;
        squares.at<double>(y, x) += v * v;
        norm2 += v * v;
      }
    }
    cv::Mat spectrum;
    cv::dft(plane, spectrum);
    fft_->spectra.push_back(spectrum);
    fft_->plane_norms.push_back(std::sqrt(norm2));
  }
  cv::integral(squares, fft_->squares_integral, CV_64F);
  fft_->squares_total = cv::sum(squares)[0];
}

OverlapSearch::~OverlapSearch() = default;

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
    const int n = space_.channels();
    for (int c = 0; c < n; ++c) {
      workspace->template_planes.emplace_back(fft_->padded, CV_64F, cv::Scalar(0.0));
    }
    workspace->spectra.resize(n);
    workspace->products.resize(n);
  }
  return workspace;
}

void OverlapSearch::Return(std::unique_ptr<Workspace> workspace) const {
  const std::lock_guard<std::mutex> lock(pool_mutex_);
  pool_.push_back(std::move(workspace));
}

double OverlapSearch::ExactError(const OverlapTemplate& pattern, SamplePixel candidate) const {
  double sum = 0.0;
  const int n = space_.channels();
  for (int v = 0; v < block_; ++v) {
    for (int u = 0; u < block_; ++u) {
      if (!pattern.shape.Contains(u, v)) continue;
      for (int c = 0; c < n; ++c) {
        sum +=
            PairError(metric_, space_.at(candidate.x + u, candidate.y + v, c), pattern.at(u, v, c));
      }
    }
  }
  return sum;
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
  // One forward transform per channel (only the template's B rows are non-zero) and its product
  // with the sample's spectrum, channels in parallel; summed in channel order.
  tbb::parallel_for(0, n, [&](int c) {
    cv::Mat& plane = workspace.template_planes[c];
    for (int v = 0; v < block_; ++v) {
      double* row = plane.ptr<double>(v);
      for (int u = 0; u < block_; ++u) row[u] = pattern.at(u, v, c);
    }
    cv::dft(plane, workspace.spectra[c], 0, block_);
    cv::mulSpectrums(fft_->spectra[c], workspace.spectra[c], workspace.products[c], 0,
                     /*conjB=*/true);
  });
  cv::Mat& sum = workspace.sum;
  workspace.products[0].copyTo(sum);
  for (int c = 1; c < n; ++c) sum += workspace.products[c];
  const int needed_rows = (rows_ - 1) * stride_ + 1;
  cv::Mat& correlation = workspace.correlation;
  cv::dft(sum, correlation, cv::DFT_INVERSE | cv::DFT_SCALE | cv::DFT_REAL_OUTPUT, needed_rows);

  // Rounding of the FFT correlation, per channel and output value, is at most of the order of
  // u log2(N) |M|_2 (|T|_1 + sqrt(N) |T|_2): the transforms are normwise stable (error
  // ~ u log2(N) times the transformed norm), the error of FFT(M) is weighted by
  // max|FFT(T)| <= |T|_1, the error of FFT(T) by |FFT(M)|_2 = sqrt(N) |M|_2, and the inverse
  // maps a 2-norm error e to at most e / sqrt(N) in any value. The integral image adds
  // ~ (W + H) u sum(M^2). Both are inflated a thousandfold (IMPLEMENTER CHOICE): the bound only
  // decides which candidates are re-scored exactly, so generosity costs a few exact sums while a
  // bound that failed would break equality with brute force.
  const double size = static_cast<double>(fft_->padded.area());
  double correlation_bound = 0.0;
  for (int c = 0; c < n; ++c) {
    correlation_bound += fft_->plane_norms[c] * (template_l1[c] + std::sqrt(size * template_l2[c]));
  }
  correlation_bound *= 2.0 * std::log2(size) * kDoubleEpsilon;
  const double integral_bound =
      4.0 * (space_.width() + space_.height()) * kDoubleEpsilon * fft_->squares_total;
  const double slack = 1000.0 * (correlation_bound + integral_bound);

  const int inner_width = block_ - shape.left - shape.right;
  const int inner_height = block_ - shape.top - shape.bottom;
  tbb::parallel_for(0, rows_, [&](int row) {
    const int y = row * stride_;
    const double* correlation_row = correlation.ptr<double>(y);
    for (int column = 0; column < columns_; ++column) {
      const int x = column * stride_;
      const double squares = SumOfBox(fft_->squares_integral, x, y, block_, block_) -
                             SumOfBox(fft_->squares_integral, x + shape.left, y + shape.top,
                                      inner_width, inner_height);
      const double estimate = squares - 2.0 * correlation_row[x] + template_energy;
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
        const float t = term.value;
        if (squared) {
          for (int x = 0; x < span; ++x) {
            const float d = line[x] - t;
            acc[x] += d * d;
          }
        } else {
          for (int x = 0; x < span; ++x) acc[x] += std::fabs(line[x] - t);
        }
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
  std::vector<int> rescore;
  if (mode == SearchMode::kBruteForce) {
    rescore.resize(count);
    for (int i = 0; i < count; ++i) rescore[i] = i;
  } else {
    std::unique_ptr<Workspace> workspace = Borrow();
    if (metric_ == ErrorMetric::kSsd) {
      BoundFft(pattern, *workspace);
    } else {
      BoundDirect(pattern, *workspace);
    }
    // Whatever the exact errors are, the best is at most min(high), so no candidate whose error
    // is above (1 + tolerance) * max(min(high), floor) can qualify.
    const std::vector<double>& low = workspace->low;
    const std::vector<double>& high = workspace->high;
    const double best_high = *std::min_element(high.begin(), high.end());
    const double reach = (1.0 + tolerance) * std::max(best_high, floor);
    for (int i = 0; i < count; ++i) {
      if (low[i] <= reach) rescore.push_back(i);
    }
    Return(std::move(workspace));
  }
  std::vector<double> exact(rescore.size());
  tbb::parallel_for(std::size_t{0}, rescore.size(),
                    [&](std::size_t k) { exact[k] = ExactError(pattern, Candidate(rescore[k])); });
  QualifyingBlocks result;
  result.rescored = static_cast<int>(rescore.size());
  result.min_error = *std::min_element(exact.begin(), exact.end());
  result.threshold = (1.0 + tolerance) * std::max(result.min_error, floor);
  for (std::size_t k = 0; k < rescore.size(); ++k) {
    if (exact[k] <= result.threshold) {
      result.positions.push_back(Candidate(rescore[k]));
      result.errors.push_back(exact[k]);
    }
  }
  return result;
}

}  // namespace photomat
