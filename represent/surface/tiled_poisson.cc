#include "represent/surface/tiled_poisson.h"

#include <fmt/format.h>
#include <tbb/parallel_for.h>

#include <algorithm>
#include <cmath>
#include <map>
#include <memory>
#include <mutex>
#include <tuple>
#include <utility>
#include <vector>

#include "core/error.h"
#include "represent/surface/surface_integration.h"

namespace photomat {
namespace {

constexpr int kP = 0, kQ = 1, kMask = 2;

// The coarse height: one value per block of factor x factor pixels, in pixel units, at the
// block's centre ((i + 0.5) factor - 0.5), and which blocks hold a masked pixel.
struct CoarseHeight {
  int factor = 1;
  Image height;
  Mask mask;

  // Bilinear interpolation between the masked blocks around pixel (x, y); false where none is.
  bool At(int x, int y, double& value) const {
    const auto axis = [&](int pixel, int blocks, int& i0, int& i1, double& t) {
      const double u = std::clamp((pixel + 0.5) / factor - 0.5, 0.0, blocks - 1.0);
      i0 = static_cast<int>(std::floor(u));
      i1 = std::min(i0 + 1, blocks - 1);
      t = u - i0;
    };
    int x0, x1, y0, y1;
    double tx, ty;
    axis(x, height.width(), x0, x1, tx);
    axis(y, height.height(), y0, y1, ty);
    double sum = 0.0, weights = 0.0;
    for (const auto& [bx, by, w] :
         {std::tuple{x0, y0, (1 - tx) * (1 - ty)}, std::tuple{x1, y0, tx * (1 - ty)},
          std::tuple{x0, y1, (1 - tx) * ty}, std::tuple{x1, y1, tx * ty}}) {
      if (w <= 0.0 || !mask(bx, by)) continue;
      sum += w * height.at(bx, by, 0);
      weights += w;
    }
    if (weights <= 0.0) return false;
    value = sum / weights;
    return true;
  }
};

// Pass 1: block means of the slopes over the masked pixels, times the block side (slopes per
// block), integrated over the blocks that hold a masked pixel by a factorised PoissonIntegrator.
CoarseHeight SolveCoarse(int width, int height, const GradientRows& rows, int factor) {
  const int cw = (width + factor - 1) / factor, ch = (height + factor - 1) / factor;
  std::vector<double> sum_p(static_cast<std::size_t>(cw) * ch), sum_q(sum_p.size()),
      count(sum_p.size());
  rows.rewind();
  // Bands of whole block rows (16 of them), so each band fills its blocks completely.
  const int band_rows = 16 * factor;
  for (int first = 0; first < height; first += band_rows) {
    const Image band = rows.next(std::min(band_rows, height - first));
    for (int y = 0; y < band.height(); ++y) {
      const std::size_t block_row = static_cast<std::size_t>((first + y) / factor) * cw;
      for (int x = 0; x < width; ++x) {
        if (band.at(x, y, kMask) < 0.5f) continue;
        const std::size_t block = block_row + static_cast<std::size_t>(x / factor);
        sum_p[block] += band.at(x, y, kP);
        sum_q[block] += band.at(x, y, kQ);
        count[block] += 1.0;
      }
    }
  }
  Image gradients(cw, ch, std::vector<std::string>{"p", "q"});
  CoarseHeight coarse;
  coarse.factor = factor;
  coarse.mask = Mask(cw, ch, false);
  for (std::size_t b = 0; b < count.size(); ++b) {
    if (count[b] == 0.0) continue;
    coarse.mask.Set(b, true);
    gradients.pixel(b)[0] = static_cast<float>(sum_p[b] / count[b] * factor);
    gradients.pixel(b)[1] = static_cast<float>(sum_q[b] / count[b] * factor);
  }
  if (coarse.mask.CountSet() == 0) throw Error("the mask selects no pixel to integrate");
  coarse.height = PoissonIntegrator(coarse.mask, PoissonSolver::kDirect).Integrate(gradients);
  return coarse;
}

// The 4-connected pieces of `mask` (the pairs IntegratePoisson links): a label per pixel, -1
// outside, and the number of pieces.
int LabelPieces(const Mask& mask, std::vector<int>& labels) {
  const int w = mask.width(), h = mask.height();
  labels.assign(mask.pixel_count(), -1);
  int pieces = 0;
  std::vector<std::size_t> stack;
  for (std::size_t start = 0; start < labels.size(); ++start) {
    if (!mask[start] || labels[start] >= 0) continue;
    labels[start] = pieces;
    stack.push_back(start);
    while (!stack.empty()) {
      const std::size_t p = stack.back();
      stack.pop_back();
      const int x = static_cast<int>(p % w), y = static_cast<int>(p / w);
      const auto visit = [&](int nx, int ny) {
        if (nx < 0 || ny < 0 || nx >= w || ny >= h) return;
        const std::size_t n = static_cast<std::size_t>(ny) * w + nx;
        if (mask[n] && labels[n] < 0) {
          labels[n] = pieces;
          stack.push_back(n);
        }
      };
      visit(x - 1, y);
      visit(x + 1, y);
      visit(x, y - 1);
      visit(x, y + 1);
    }
    ++pieces;
  }
  return pieces;
}

// The integrators of full tiles (every pixel in the mask), by size: every interior tile of an
// unmasked map has the same system, so one factorisation serves them all (PoissonIntegrator).
// Only sizes of the current tile row's height are kept (IMPLEMENTER CHOICE: at most the row's
// left, interior and right tiles, about 40 MB each at 320 x 320). Get is thread-safe; KeepHeight
// is called between rows, when no tile is being solved.
class FullTileIntegrators {
 public:
  const PoissonIntegrator& Get(int width, int height) {
    const std::lock_guard lock(mutex_);
    auto& integrator = integrators_[{width, height}];
    if (!integrator) integrator = std::make_unique<PoissonIntegrator>(Mask(width, height, true));
    return *integrator;
  }
  void KeepHeight(int height) {
    std::erase_if(integrators_,
                  [height](const auto& entry) { return entry.first.second != height; });
  }

 private:
  std::mutex mutex_;
  std::map<std::pair<int, int>, std::unique_ptr<PoissonIntegrator>> integrators_;
};

// One tile's region: columns [x0, x1) of the window's rows, whose first row is image row `top`.
// Its Poisson solution, each piece of the mask moved to the coarse height's level (0 outside).
Image SolveTile(const Image& window, int top, int x0, int x1, const CoarseHeight& coarse,
                FullTileIntegrators& full_tiles) {
  const int w = x1 - x0, h = window.height();
  Image gradients(w, h, std::vector<std::string>{"p", "q"});
  Mask mask(w, h, false);
  for (int y = 0; y < h; ++y) {
    for (int x = 0; x < w; ++x) {
      gradients.at(x, y, 0) = window.at(x0 + x, y, kP);
      gradients.at(x, y, 1) = window.at(x0 + x, y, kQ);
      mask.Set(x, y, window.at(x0 + x, y, kMask) >= 0.5f);
    }
  }
  const std::size_t inside = mask.CountSet();
  if (inside == 0) return Image(w, h, 1);
  Image solved = inside == mask.pixel_count() ? full_tiles.Get(w, h).Integrate(gradients)
                                              : IntegratePoisson(gradients, mask);
  std::vector<int> labels;
  const int pieces = LabelPieces(mask, labels);
  std::vector<double> difference(static_cast<std::size_t>(pieces)), count(difference.size());
  for (int y = 0; y < h; ++y) {
    for (int x = 0; x < w; ++x) {
      const int piece = labels[static_cast<std::size_t>(y) * w + x];
      double level = 0.0;
      if (piece < 0 || !coarse.At(x0 + x, top + y, level)) continue;
      difference[piece] += level - solved.at(x, y, 0);
      count[piece] += 1.0;
    }
  }
  for (std::size_t p = 0; p < solved.pixel_count(); ++p) {
    const int piece = labels[p];
    if (piece >= 0 && count[piece] > 0.0) {
      solved.pixel(p)[0] += static_cast<float>(difference[piece] / count[piece]);
    }
  }
  return solved;
}

// The blending weight of pixel `i` along an axis for the tile whose core is [core0, core1) of
// [0, size): 1 inside, ramping linearly to 0 across the 2 x overlap pixels shared with each
// neighbour (the neighbours' ramps are complementary: the weights sum to 1).
double RampWeight(int i, int core0, int core1, int size, int overlap) {
  double weight = 1.0;
  if (core0 > 0) weight *= std::clamp((i - (core0 - overlap) + 0.5) / (2.0 * overlap), 0.0, 1.0);
  if (core1 < size) weight *= std::clamp(((core1 + overlap) - i - 0.5) / (2.0 * overlap), 0.0, 1.0);
  return weight;
}

}  // namespace

int CoarseFactor(int width, int height, const TiledPoissonOptions& options) {
  int factor = std::max(1, options.coarse_factor);
  while (static_cast<long>((width + factor - 1) / factor) * ((height + factor - 1) / factor) >
         kMaxCoarseBlocks) {
    factor *= 2;
  }
  return factor;
}

void IntegrateTiledPoisson(int width, int height, const GradientRows& gradients,
                           const std::function<void(ConstImageView height_rows)>& write,
                           const TiledPoissonOptions& options) {
  const int tile = options.tile, overlap = options.overlap;
  if (overlap < 1 || tile < 2 * overlap) {
    throw Error(
        fmt::format("tiled Poisson needs an overlap of at least 1 pixel and tiles of at "
                    "least twice it (tile {}, overlap {})",
                    tile, overlap));
  }
  const CoarseHeight coarse =
      SolveCoarse(width, height, gradients, CoarseFactor(width, height, options));

  gradients.rewind();
  FullTileIntegrators full_tiles;
  // The window: gradient rows [window_top, window_top + window.height()) and the blended height
  // of the same rows (with their mask), of which those above the window's tiles are final.
  Image window, blended;
  int window_top = 0;
  for (int core0 = 0; core0 < height; core0 += tile) {
    const int core1 = std::min(core0 + tile, height);
    const int top = std::max(0, core0 - overlap), bottom = std::min(height, core1 + overlap);
    // Slide the window to [top, bottom): keep the rows shared with the last one, read the rest.
    Image next_window(width, bottom - top, 3), next_blended(width, bottom - top, 2);
    int kept = 0;
    if (!window.empty()) {
      kept = window_top + window.height() - top;
      for (int c = 0; c < 3; ++c) {
        for (int y = 0; y < kept; ++y) {
          std::copy_n(window.row(c, top - window_top + y).begin(), width,
                      next_window.row(c, y).begin());
        }
      }
      for (int y = 0; y < kept; ++y) {
        std::copy_n(blended.row(0, top - window_top + y).begin(), width,
                    next_blended.row(0, y).begin());
      }
    }
    if (bottom - top > kept) {
      const Image rows = gradients.next(bottom - top - kept);
      if (rows.height() != bottom - top - kept || rows.width() != width || rows.channels() != 3) {
        throw Error("tiled Poisson: the gradient rows do not match the image");
      }
      for (int c = 0; c < 3; ++c) {
        for (int y = 0; y < rows.height(); ++y) {
          std::copy_n(rows.row(c, y).begin(), width, next_window.row(c, kept + y).begin());
        }
      }
    }
    window = std::move(next_window);
    blended = std::move(next_blended);
    // The mask travels beside the height (channel 1) to the writer.
    std::copy_n(window.plane(kMask).begin(), window.pixel_count(), blended.plane(1).begin());
    window_top = top;

    // The tiles of this row, solved in parallel, then blended in order.
    const int tiles = (width + tile - 1) / tile;
    std::vector<Image> solved(static_cast<std::size_t>(tiles));
    full_tiles.KeepHeight(window.height());
    tbb::parallel_for(0, tiles, [&](int t) {
      const int x0 = std::max(0, t * tile - overlap);
      const int x1 = std::min(width, std::min((t + 1) * tile, width) + overlap);
      solved[t] = SolveTile(window, top, x0, x1, coarse, full_tiles);
    });
    for (int t = 0; t < tiles; ++t) {
      const int col0 = t * tile, col1 = std::min(col0 + tile, width);
      const int x0 = std::max(0, col0 - overlap);
      for (int y = 0; y < window.height(); ++y) {
        const double wy = RampWeight(top + y, core0, core1, height, overlap);
        if (wy <= 0.0) continue;
        for (int x = 0; x < solved[t].width(); ++x) {
          const double wx = RampWeight(x0 + x, col0, col1, width, overlap);
          blended.at(x0 + x, y, 0) += static_cast<float>(wx * wy * solved[t].at(x, y, 0));
        }
      }
    }
    // Rows above the next tile row's window are final.
    const int final_rows = (core1 >= height ? height : core1 - overlap) - top;
    if (final_rows > 0) write(blended.Rows(0, final_rows));
    if (core1 >= height) break;
  }
}

Image IntegrateTiledPoisson(const Image& gradients, const Mask& mask,
                            const TiledPoissonOptions& options) {
  const int width = gradients.width(), height = gradients.height();
  if (gradients.channels() != 2) throw Error("tiled Poisson: expected 2 gradient channels");
  if (mask.pixel_count() != 0 && !mask.SameSize(gradients)) {
    throw Error("mask and gradients differ in size");
  }
  int next_row = 0;
  GradientRows rows;
  rows.rewind = [&] { next_row = 0; };
  rows.next = [&](int count) {
    count = std::min(count, height - next_row);
    Image band(width, count, 3);
    for (int y = 0; y < count; ++y) {
      for (int x = 0; x < width; ++x) {
        band.at(x, y, kP) = gradients.at(x, next_row + y, 0);
        band.at(x, y, kQ) = gradients.at(x, next_row + y, 1);
        band.at(x, y, kMask) = mask.pixel_count() == 0 || mask(x, next_row + y) ? 1.0f : 0.0f;
      }
    }
    next_row += count;
    return band;
  };
  Image result(width, height, std::vector<std::string>{"height"});
  int written = 0;
  IntegrateTiledPoisson(
      width, height, rows,
      [&](ConstImageView band) {
        for (int y = 0; y < band.height(); ++y) {
          std::copy_n(band.row(0, y).begin(), width, result.row(0, written + y).begin());
        }
        written += band.height();
      },
      options);
  return result;
}

Image IntegratePoissonAnySize(const Image& gradients, const Mask& mask) {
  const std::size_t unknowns = mask.pixel_count() == 0 ? gradients.pixel_count() : mask.CountSet();
  if (unknowns <= static_cast<std::size_t>(kDirectPoissonUnknowns)) {
    return IntegratePoisson(gradients, mask);
  }
  Image height = IntegrateTiledPoisson(gradients, mask);
  // Zero mean over the mask, as IntegratePoisson gives it.
  double sum = 0.0;
  for (std::size_t p = 0; p < height.pixel_count(); ++p) {
    if (mask.pixel_count() == 0 || mask[p]) sum += height.pixel(p)[0];
  }
  // (In double, in raster order, as the streamed export subtracts it: the same bits.)
  const double mean = sum / static_cast<double>(unknowns);
  for (std::size_t p = 0; p < height.pixel_count(); ++p) {
    if (mask.pixel_count() == 0 || mask[p]) {
      height.pixel(p)[0] = static_cast<float>(height.pixel(p)[0] - mean);
    }
  }
  return height;
}

}  // namespace photomat
