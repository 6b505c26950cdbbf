#include "synthesize/texture/image_quilting.h"

#include <fmt/format.h>
#include <tbb/parallel_for.h>

#include <algorithm>
#include <cmath>
#include <optional>

#include "core/error.h"
#include "core/random.h"
#include "core/wrap.h"
#include "synthesize/texture/boundary_cut.h"

namespace photomat {
namespace {

// Outputs beyond this are certainly a typo (a 64k x 64k output of 6 floats is 100 GB).
constexpr int kMaxOutputSide = 65536;

void CheckOptions(const Image& guide, const SynthesisTarget& target, const QuiltOptions& options,
                  int block, int overlap) {
  if (guide.empty() || guide.channels() < 1) throw Error("quilting needs a non-empty sample");
  if (target.width < 1 || target.height < 1 || target.width > kMaxOutputSide ||
      target.height > kMaxOutputSide) {
    throw Error(fmt::format("output size {}x{} is out of range (1..{})", target.width,
                            target.height, kMaxOutputSide));
  }
  if (block < 2 || block > guide.width() || block > guide.height()) {
    throw Error(fmt::format("block size {} does not fit in the {}x{} sample (2..{})", block,
                            guide.width(), guide.height(),
                            std::min(guide.width(), guide.height())));
  }
  if (overlap < 1 || 2 * overlap > block) {
    throw Error(fmt::format("overlap {} is outside 1..{} (half the block)", overlap, block / 2));
  }
  if (!(options.tolerance >= 0.0) || !std::isfinite(options.tolerance)) {
    throw Error(fmt::format("tolerance {} is not a finite non-negative number", options.tolerance));
  }
  if (!(options.error_floor >= 0.0) || !std::isfinite(options.error_floor)) {
    throw Error(
        fmt::format("error floor {} is not a finite non-negative number", options.error_floor));
  }
  if (options.candidate_stride < 1) {
    throw Error(fmt::format("candidate stride {} is not positive", options.candidate_stride));
  }
  if (!(options.forced_search_rate >= 0.0 && options.forced_search_rate <= 1.0)) {
    throw Error(fmt::format("forced-search rate {} is outside [0, 1]", options.forced_search_rate));
  }
}

// The mean error between horizontally or vertically neighbouring sample pixels: the texture's
// own roughness in the matching metric, per pixel.
double MeanNeighbourError(const Image& space, ErrorMetric metric) {
  double sum = 0.0;
  std::size_t pairs = 0;
  for (int c = 0; c < space.channels(); ++c) {
    for (int y = 0; y < space.height(); ++y) {
      for (int x = 0; x < space.width(); ++x) {
        if (x + 1 < space.width())
          sum += PairError(metric, space.at(x, y, c), space.at(x + 1, y, c));
        if (y + 1 < space.height())
          sum += PairError(metric, space.at(x, y, c), space.at(x, y + 1, c));
      }
    }
  }
  pairs = static_cast<std::size_t>(space.width() - 1) * space.height() +
          static_cast<std::size_t>(space.height() - 1) * space.width();
  return pairs == 0 ? 0.0 : sum / static_cast<double>(pairs);
}

// The already-synthesised pixels under a block, in matching space.
OverlapTemplate MakeTemplate(const OverlapShape& shape, const PlacedBlock& block,
                             const SourceMap& canvas, const Image& space) {
  OverlapTemplate pattern(shape, space.channels());
  for (int v = 0; v < shape.block; ++v) {
    for (int u = 0; u < shape.block; ++u) {
      if (!shape.Contains(u, v)) continue;
      const SamplePixel from =
          canvas.at((block.x + u) % canvas.width(), (block.y + v) % canvas.height());
      if (!from.valid()) throw Error("internal: an overlap pixel was never synthesised");
      for (int c = 0; c < space.channels(); ++c) pattern.at(u, v, c) = space.at(from.x, from.y, c);
    }
  }
  return pattern;
}

// Per-pixel error between the new block and the overlap, over the whole block (0 elsewhere).
std::vector<double> PixelErrors(const OverlapTemplate& pattern, SamplePixel source,
                                const Image& space, ErrorMetric metric) {
  const int b = pattern.shape.block;
  std::vector<double> errors(static_cast<std::size_t>(b) * b, 0.0);
  for (int v = 0; v < b; ++v) {
    for (int u = 0; u < b; ++u) {
      if (!pattern.shape.Contains(u, v)) continue;
      double sum = 0.0;
      for (int c = 0; c < space.channels(); ++c) {
        sum += PairError(metric, space.at(source.x + u, source.y + v, c), pattern.at(u, v, c));
      }
      errors[static_cast<std::size_t>(v) * b + u] = sum;
    }
  }
  return errors;
}

// The thesis's neighbour-block reuse: the source that continues the blocks left (g), above (f)
// and above-left (e) when they agree, inside the sample.
std::optional<SamplePixel> Continuation(const BlockPlacement& placement, int column, int row) {
  const int columns = static_cast<int>(placement.column_positions.size());
  const auto& xs = placement.column_positions;
  const auto& ys = placement.row_positions;
  std::optional<SamplePixel> proposal;
  bool agree = true;
  auto propose = [&](int from_column, int from_row) {
    const PlacedBlock& from =
        placement.blocks[static_cast<std::size_t>(from_row) * columns + from_column];
    const SamplePixel p{from.source.x + xs[column] - xs[from_column],
                        from.source.y + ys[row] - ys[from_row]};
    if (!proposal) {
      proposal = p;
    } else if (*proposal != p) {
      agree = false;
    }
  };
  if (column > 0) propose(column - 1, row);
  if (row > 0) propose(column, row - 1);
  if (column > 0 && row > 0) propose(column - 1, row - 1);
  if (!proposal || !agree) return std::nullopt;
  const int b = placement.block_size;
  if (proposal->x < 0 || proposal->y < 0 || proposal->x > placement.sample_width - b ||
      proposal->y > placement.sample_height - b) {
    return std::nullopt;
  }
  return proposal;
}

// Whether [a, a + length) and [b, b + length) meet on an axis of `extent` pixels (circular when
// `wrap`).
bool Meet(int a, int b, int length, int extent, bool wrap) {
  if (!wrap) return a < b + length && b < a + length;
  const int forward = Wrap(b - a, extent);
  const int backward = Wrap(a - b, extent);
  return forward < length || backward < length;
}

// The blocks (indices into placement.blocks) grouped in waves: a block's wave is one more than the
// latest wave of the earlier blocks whose footprints meet its own. Footprints are B apart at most
// two rows up (rows are at least B/2 apart); a tileable output's last row also meets its first.
std::vector<std::vector<int>> Waves(const BlockPlacement& placement) {
  const int columns = static_cast<int>(placement.column_positions.size());
  const int rows = static_cast<int>(placement.row_positions.size());
  const int b = placement.block_size;
  std::vector<int> wave(placement.blocks.size(), 0);
  std::vector<std::vector<int>> waves;
  for (std::size_t k = 0; k < placement.blocks.size(); ++k) {
    const PlacedBlock& block = placement.blocks[k];
    int latest = -1;
    for (int row : {block.row - 2, block.row - 1, block.row, 0, 1}) {
      if (row < 0 || row >= rows || row > block.row) continue;
      for (int column = 0; column < columns; ++column) {
        const std::size_t other = static_cast<std::size_t>(row) * columns + column;
        if (other >= k) break;
        const PlacedBlock& earlier = placement.blocks[other];
        if (Meet(block.x, earlier.x, b, placement.canvas_width, placement.tileable) &&
            Meet(block.y, earlier.y, b, placement.canvas_height, placement.tileable)) {
          latest = std::max(latest, wave[other]);
        }
      }
    }
    wave[k] = latest + 1;
    if (wave[k] >= static_cast<int>(waves.size())) waves.resize(wave[k] + 1);
    waves[wave[k]].push_back(static_cast<int>(k));
  }
  return waves;
}

// Each block's own random stream (SplitMix64 of the seed and the block's index), so the draws do
// not depend on the order in which blocks run.
std::uint64_t BlockSeed(std::uint64_t seed, std::size_t index) {
  std::uint64_t z = seed + 0x9e3779b97f4a7c15ull * (index + 1);
  z = (z ^ (z >> 30)) * 0xbf58476d1ce4e5b9ull;
  z = (z ^ (z >> 27)) * 0x94d049bb133111ebull;
  return z ^ (z >> 31);
}

}  // namespace

QuiltOptions VarietyQuiltOptions(int sample_width, int sample_height) {
  const int side = std::min(sample_width, sample_height);
  QuiltOptions options;
  options.block_size = std::min(side, std::clamp(side / 4, 8, 64));
  options.tolerance = 0.1;
  options.error_floor = 1.0;
  return options;
}

int DefaultBlockSize(int sample_width, int sample_height) {
  const int side = std::min(sample_width, sample_height);
  return std::min(side, std::clamp(side / 3, 8, 64));
}

int DefaultOverlap(int block_size) {
  return std::max(1, static_cast<int>(std::lround(block_size / 4.0)));
}

BlockPlacement PlanQuilt(const Image& guide, const SynthesisTarget& target,
                         const QuiltOptions& options, Progress* progress) {
  const int block =
      options.block_size > 0 ? options.block_size : DefaultBlockSize(guide.width(), guide.height());
  const int overlap = options.overlap > 0 ? options.overlap : DefaultOverlap(block);
  CheckOptions(guide, target, options, block, overlap);
  const ErrorMetric metric = options.matching.metric;
  const Image space = ChannelTransform::Fit(guide, options.matching).Apply(guide);
  const double neighbour_error = MeanNeighbourError(space, metric);

  BlockPlacement placement;
  placement.block_size = block;
  placement.overlap = overlap;
  placement.width = target.width;
  placement.height = target.height;
  placement.tileable = target.tileable;
  placement.canvas_width = target.tileable ? target.width : std::max(target.width, block);
  placement.canvas_height = target.tileable ? target.height : std::max(target.height, block);
  placement.sample_width = guide.width();
  placement.sample_height = guide.height();
  placement.column_positions = BlockPositions(target.width, block, overlap, target.tileable);
  placement.row_positions = BlockPositions(target.height, block, overlap, target.tileable);
  const int columns = static_cast<int>(placement.column_positions.size());
  const int rows = static_cast<int>(placement.row_positions.size());

  // Every block's position and overlap first; then the blocks in waves: a block depends on the
  // earlier blocks (raster order) whose footprints meet its own, and all blocks of a wave run at
  // once. Each block reads and writes only its footprint and draws from its own random stream,
  // so the result is that of raster order whatever the number of threads.
  for (int row = 0; row < rows; ++row) {
    for (int column = 0; column < columns; ++column) {
      PlacedBlock placed;
      placed.column = column;
      placed.row = row;
      placed.x = placement.column_positions[column];
      placed.y = placement.row_positions[row];
      OverlapShape& shape = placed.overlap;
      shape.block = block;
      if (column > 0) shape.left = placement.column_positions[column - 1] + block - placed.x;
      if (row > 0) shape.top = placement.row_positions[row - 1] + block - placed.y;
      if (target.tileable && column == columns - 1) shape.right = placed.x + block - target.width;
      if (target.tileable && row == rows - 1) shape.bottom = placed.y + block - target.height;
      placement.blocks.push_back(std::move(placed));
    }
  }
  const std::vector<std::vector<int>> waves = Waves(placement);

  SourceMap canvas(placement.canvas_width, placement.canvas_height, guide.width(), guide.height());
  const OverlapSearch search(space, block, metric, options.candidate_stride);
  NullProgress null_progress;
  Progress& report = OrNull(progress, null_progress);
  report.Start("quilting", placement.blocks.size());
  auto place = [&](int index) {
    PlacedBlock& placed = placement.blocks[index];
    const OverlapShape& shape = placed.overlap;
    Random random(BlockSeed(target.seed, index));
    const bool forced = random.Uniform() < options.forced_search_rate;
    std::optional<SamplePixel> continuation;
    if (options.coherence && !forced && shape.right == 0 && shape.bottom == 0) {
      continuation = Continuation(placement, placed.column, placed.row);
    }
    if (shape.empty()) {
      placed.source = search.Candidate(static_cast<int>(random.Index(search.candidate_count())));
      placed.choice = PlacedBlock::Choice::kRandom;
    } else {
      const OverlapTemplate pattern = MakeTemplate(shape, placed, canvas, space);
      if (continuation) {
        placed.source = *continuation;
        placed.choice = PlacedBlock::Choice::kCoherence;
      } else {
        const double floor = options.error_floor * neighbour_error * shape.PixelCount();
        const QualifyingBlocks found =
            search.Qualifying(pattern, options.tolerance, floor, options.search);
        placed.source = found.positions[random.Index(found.positions.size())];
        placed.choice = PlacedBlock::Choice::kSearch;
      }
      placed.cuts = CutBlock(shape, PixelErrors(pattern, placed.source, space, metric));
    }
    placement.Paste(placed, canvas);
    report.Advance();
  };
  for (const std::vector<int>& wave : waves) {
    tbb::parallel_for(std::size_t{0}, wave.size(), [&](std::size_t k) { place(wave[k]); });
  }
  report.Finish();
  return placement;
}

}  // namespace photomat
