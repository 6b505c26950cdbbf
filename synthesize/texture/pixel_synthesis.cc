#include "synthesize/texture/pixel_synthesis.h"

#include <fmt/format.h>
#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>

#include <algorithm>
#include <atomic>
#include <cmath>
#include <limits>
#include <opencv2/imgproc.hpp>

#include "core/error.h"
#include "core/random.h"
#include "core/wrap.h"

namespace photomat {
namespace {

constexpr int kMaxLevels = 4;
constexpr int kMinCoarsestSide = 16;
constexpr int kMaxOutputSide = 65536;

Image Downsample(const Image& image) {
  const int w = (image.width() + 1) / 2, h = (image.height() + 1) / 2;
  Image out(w, h, image.channels());
  for (int c = 0; c < image.channels(); ++c) {
    const cv::Mat source(image.height(), image.width(), CV_32F,
                         const_cast<float*>(image.plane(c).data()));
    cv::Mat target(h, w, CV_32F, out.plane(c).data());
    cv::pyrDown(source, target, target.size());
  }
  return out;
}

// The parent level repeated 2 x 2, so that the parent of candidate (x, y) shifted by (dx, dy)
// parent pixels is at (x + 2 dx, y + 2 dy): contiguous along candidate rows.
Image Upsample(const Image& parent) {
  Image out(parent.width() * 2, parent.height() * 2, parent.channels());
  for (int c = 0; c < parent.channels(); ++c) {
    for (int y = 0; y < out.height(); ++y) {
      for (int x = 0; x < out.width(); ++x) out.at(x, y, c) = parent.at(x / 2, y / 2, c);
    }
  }
  return out;
}

int AutoLevels(int width, int height, const PixelSynthesisOptions& options) {
  const int needed =
      std::max(kMinCoarsestSide, 3 * std::max(options.neighbourhood, options.parent_neighbourhood));
  int levels = 0;
  while (levels < kMaxLevels) {
    width = (width + 1) / 2;
    height = (height + 1) / 2;
    if (std::min(width, height) < needed) break;
    ++levels;
  }
  return levels;
}

// One entry of a neighbourhood: the output value, and where the same neighbour of a candidate
// lies in a sample plane (offset from the candidate, in that plane's pixels).
struct Term {
  const float* plane;
  int stride;
  int dx;
  int dy;
  float value;
};

struct Range {
  int x_low, x_high, y_low, y_high;
};

struct Best {
  float error = std::numeric_limits<float>::infinity();
  int x = -1;
  int y = -1;
};

// The error of one candidate, summed in the same order and precision as a lane of the rows below
// (so both give bit-identical values).
float CandidateError(const std::vector<Term>& terms, int x, int y, bool squared) {
  float sum = 0.0f;
  for (const Term& term : terms) {
    const float d =
        term.plane[static_cast<std::ptrdiff_t>(y + term.dy) * term.stride + x + term.dx] -
        term.value;
    sum += squared ? d * d : std::fabs(d);
  }
  return sum;
}

// Lowers `bound` to `value` if smaller.
void LowerBound(std::atomic<float>& bound, float value) {
  float current = bound.load(std::memory_order_relaxed);
  while (value < current && !bound.compare_exchange_weak(current, value)) {
  }
}

// The candidate of least error (first in raster order among equals), rows in parallel. Exact
// exhaustive search with partial-distance pruning: the terms are non-negative, so a float partial
// sum never exceeds the full one, and a row is abandoned once all its partial sums exceed the best
// error found so far. A row holding a candidate whose error is at most the final minimum is never
// abandoned, so the result (ties included) does not depend on which rows ran first or on how many
// threads ran them. `hint` (a likely good candidate) seeds the bound.
Best Search(const std::vector<Term>& terms, const Range& range, ErrorMetric metric,
            SamplePixel hint, bool prune) {
  constexpr std::size_t kCheckEvery = 16;  // terms between pruning checks
  const int span = range.x_high - range.x_low + 1;
  const int rows = range.y_high - range.y_low + 1;
  const bool squared = metric == ErrorMetric::kSsd;
  std::atomic<float> bound(std::numeric_limits<float>::infinity());
  if (prune && hint.x >= range.x_low && hint.x <= range.x_high && hint.y >= range.y_low &&
      hint.y <= range.y_high) {
    bound = CandidateError(terms, hint.x, hint.y, squared);
  }
  std::vector<Best> row_best(rows);
  tbb::parallel_for(tbb::blocked_range<int>(0, rows), [&](const tbb::blocked_range<int>& block) {
    std::vector<float> sums(span);
    for (int r = block.begin(); r != block.end(); ++r) {
      const int y = range.y_low + r;
      std::fill(sums.begin(), sums.end(), 0.0f);
      float* acc = sums.data();
      bool abandoned = false;
      for (std::size_t k = 0; k < terms.size(); ++k) {
        const Term& term = terms[k];
        const float* line = term.plane + static_cast<std::ptrdiff_t>(y + term.dy) * term.stride +
                            range.x_low + term.dx;
        AccumulatePairErrors(squared, line, term.value, span, acc);
        if (prune && (k + 1) % kCheckEvery == 0 && k + 1 < terms.size() &&
            *std::min_element(sums.begin(), sums.end()) > bound.load(std::memory_order_relaxed)) {
          abandoned = true;
          break;
        }
      }
      if (abandoned) continue;  // row_best[r] stays at infinity
      const int best = static_cast<int>(std::min_element(sums.begin(), sums.end()) - sums.begin());
      row_best[r] = {sums[best], range.x_low + best, y};
      LowerBound(bound, sums[best]);
    }
  });
  Best best;
  for (const Best& candidate : row_best) {
    if (candidate.error < best.error) best = candidate;
  }
  return best;
}

// Synthesis of one output level; `parent_*` are absent at the coarsest level.
class LevelSynthesizer {
 public:
  LevelSynthesizer(const Image& sample, const Image* parent_sample, const Image* parent_output,
                   int width, int height, bool tileable, const PixelSynthesisOptions& options)
      : sample_(sample),
        parent_output_(parent_output),
        tileable_(tileable),
        options_(options),
        output_(width, height, sample.channels()),
        sources_(static_cast<std::size_t>(width) * height) {
    const int h = options.neighbourhood / 2, hp = options.parent_neighbourhood / 2;
    // A tileable output also matches wrapped neighbours below its last rows: rows below a
    // candidate must then exist too.
    range_ = {h, sample.width() - 1 - h, h, sample.height() - 1 - (tileable ? h : 0)};
    if (parent_sample) {
      parent_up_ = Upsample(*parent_sample);
      range_.x_low = std::max(range_.x_low, 2 * hp);
      range_.y_low = std::max(range_.y_low, 2 * hp);
      range_.x_high = std::min(range_.x_high, 2 * (parent_sample->width() - 1 - hp) + 1);
      range_.y_high = std::min(range_.y_high, 2 * (parent_sample->height() - 1 - hp) + 1);
    }
    if (range_.x_low > range_.x_high || range_.y_low > range_.y_high) {
      throw Error(fmt::format("a {}x{} sample level is too small for {}-pixel neighbourhoods",
                              sample.width(), sample.height(), options.neighbourhood));
    }
  }

  void Run(Random& random, Progress& progress) {
    for (int y = 0; y < output_.height(); ++y) {
      for (int x = 0; x < output_.width(); ++x) {
        const bool forced = random.Uniform() < options_.forced_search_rate;
        SamplePixel source;
        const SamplePixel previous = x > 0 ? sources_[Index(x - 1, y)] : SamplePixel{};
        if (x > 0 && !forced && previous.x + 1 < sample_.width()) {
          source = {previous.x + 1, previous.y};
        } else {
          source = Match(x, y, random);
        }
        sources_[Index(x, y)] = source;
        for (int c = 0; c < sample_.channels(); ++c) {
          output_.at(x, y, c) = sample_.at(source.x, source.y, c);
        }
      }
      progress.Advance(static_cast<std::size_t>(output_.width()));
    }
  }

  const Image& output() const { return output_; }
  const std::vector<SamplePixel>& sources() const { return sources_; }

 private:
  std::size_t Index(int x, int y) const {
    return static_cast<std::size_t>(y) * output_.width() + x;
  }

  // Wraps (tileable) or rejects (-1) a coordinate outside [0, size).
  int Place(int coordinate, int size) const {
    if (coordinate >= 0 && coordinate < size) return coordinate;
    if (!tileable_) return -1;
    return Wrap(coordinate, size);
  }

  SamplePixel Match(int x, int y, Random& random) const {
    std::vector<Term> terms;
    const int n = sample_.channels();
    const int h = options_.neighbourhood / 2;
    // The parent level first: it constrains most, so partial sums rise fastest (pruning).
    if (parent_output_) {
      const int hp = options_.parent_neighbourhood / 2;
      for (int dy = -hp; dy <= hp; ++dy) {
        for (int dx = -hp; dx <= hp; ++dx) {
          const int px = Place(x / 2 + dx, parent_output_->width());
          const int py = Place(y / 2 + dy, parent_output_->height());
          if (px < 0 || py < 0) continue;
          for (int c = 0; c < n; ++c) {
            terms.push_back({parent_up_.plane(c).data(), parent_up_.width(), 2 * dx, 2 * dy,
                             parent_output_->at(px, py, c)});
          }
        }
      }
    }
    // The square around the pixel, of which only the pixels already synthesised at this level
    // count: the causal half (rows above, the left part of this row) and, when the output wraps,
    // the first rows and columns met again past its last ones.
    const int below = tileable_ ? h : 0;
    for (int dy = -h; dy <= below; ++dy) {
      for (int dx = -h; dx <= h; ++dx) {
        const int xx = Place(x + dx, output_.width()), yy = Place(y + dy, output_.height());
        if (xx < 0 || yy < 0 || yy > y || (yy == y && xx >= x)) continue;
        for (int c = 0; c < n; ++c) {
          terms.push_back(
              {sample_.plane(c).data(), sample_.width(), dx, dy, output_.at(xx, yy, c)});
        }
      }
    }
    if (terms.empty()) {  // the very first pixel: nothing to match yet
      const int columns = range_.x_high - range_.x_low + 1;
      const int rows = range_.y_high - range_.y_low + 1;
      const auto pick = static_cast<int>(random.Index(static_cast<std::uint64_t>(columns) * rows));
      return {range_.x_low + pick % columns, range_.y_low + pick / columns};
    }
    // The previous pixel's continuation is usually a good match: it seeds the pruning bound.
    const SamplePixel previous = x > 0 ? sources_[Index(x - 1, y)] : SamplePixel{};
    const Best best = Search(terms, range_, options_.matching.metric, {previous.x + 1, previous.y},
                             options_.search == SearchMode::kFast);
    return {best.x, best.y};
  }

  const Image& sample_;
  const Image* parent_output_;
  bool tileable_;
  const PixelSynthesisOptions& options_;
  Image parent_up_;
  Range range_{};
  Image output_;
  std::vector<SamplePixel> sources_;
};

void CheckOptions(const Image& guide, const SynthesisTarget& target,
                  const PixelSynthesisOptions& options) {
  if (guide.empty() || guide.channels() < 1) throw Error("synthesis needs a non-empty sample");
  if (target.width < 1 || target.height < 1 || target.width > kMaxOutputSide ||
      target.height > kMaxOutputSide) {
    throw Error(fmt::format("output size {}x{} is out of range (1..{})", target.width,
                            target.height, kMaxOutputSide));
  }
  for (int side : {options.neighbourhood, options.parent_neighbourhood}) {
    if (side < 1 || side % 2 == 0 || side > 31) {
      throw Error(fmt::format("neighbourhood size {} is not an odd number in 1..31", side));
    }
  }
  if (options.levels < -1 || options.levels > 8) {
    throw Error(
        fmt::format("pyramid levels {} is outside 0..8 (or -1 for automatic)", options.levels));
  }
  if (!(options.forced_search_rate >= 0.0 && options.forced_search_rate <= 1.0)) {
    throw Error(fmt::format("forced-search rate {} is outside [0, 1]", options.forced_search_rate));
  }
}

}  // namespace

SourceMap PlanPixelSynthesis(const Image& guide, const SynthesisTarget& target,
                             const PixelSynthesisOptions& options, Progress* progress) {
  CheckOptions(guide, target, options);
  const int levels =
      options.levels >= 0 ? options.levels : AutoLevels(guide.width(), guide.height(), options);
  std::vector<Image> pyramid;
  pyramid.push_back(ChannelTransform::Fit(guide, options.matching).Apply(guide));
  for (int l = 0; l < levels; ++l) pyramid.push_back(Downsample(pyramid.back()));
  std::vector<std::pair<int, int>> sizes{{target.width, target.height}};
  std::size_t total = static_cast<std::size_t>(target.width) * target.height;
  for (int l = 0; l < levels; ++l) {
    sizes.emplace_back((sizes.back().first + 1) / 2, (sizes.back().second + 1) / 2);
    total += static_cast<std::size_t>(sizes.back().first) * sizes.back().second;
  }

  NullProgress null_progress;
  Progress& report = OrNull(progress, null_progress);
  report.Start("pixel synthesis", total);
  Random random(target.seed);
  Image parent_output;
  std::vector<SamplePixel> finest;
  for (int l = levels; l >= 0; --l) {
    const bool has_parent = l < levels;
    LevelSynthesizer level(pyramid[l], has_parent ? &pyramid[l + 1] : nullptr,
                           has_parent ? &parent_output : nullptr, sizes[l].first, sizes[l].second,
                           target.tileable, options);
    level.Run(random, report);
    parent_output = level.output();
    if (l == 0) finest = level.sources();
  }
  report.Finish();

  SourceMap map(target.width, target.height, guide.width(), guide.height());
  for (int y = 0; y < target.height; ++y) {
    for (int x = 0; x < target.width; ++x) {
      map.Set(x, y, finest[static_cast<std::size_t>(y) * target.width + x]);
    }
  }
  return map;
}

}  // namespace photomat
