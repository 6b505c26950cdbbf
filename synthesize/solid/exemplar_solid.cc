#include "synthesize/solid/exemplar_solid.h"

#include <fmt/format.h>
#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <limits>

#include "core/error.h"
#include "core/wrap.h"
#include "synthesize/volume/voxel_hash.h"

namespace photomat {
namespace {

using Int3 = std::array<int, 3>;
constexpr int kDiagonals = 8;

// The 8 diagonal directions {-1, 1}^3; bit a of the index gives the sign along axis a.
constexpr std::array<Int3, kDiagonals> kDiagonal = {{{-1, -1, -1},
                                                     {1, -1, -1},
                                                     {-1, 1, -1},
                                                     {1, 1, -1},
                                                     {-1, -1, 1},
                                                     {1, -1, 1},
                                                     {-1, 1, 1},
                                                     {1, 1, 1}}};

int Round(float value) { return static_cast<int>(std::floor(value + 0.5f)); }

// The warped neighbourhood of one voxel (spec sections 4.4 and 5.3). Output-space offsets:
// neighbour[i] = round(phi(D_i)) and predictor[i][m] = round(phi(D_i) + phi(M_m D_i)), m = 0 the
// neighbour itself (phi(0) = 0), m = 1..3 one step further along x, y, z (phi(D) = F D / |F D|).
//
// Exemplar-space corrections, in units of the level spacing h: a voxel at output offset o
// predicts the exemplar coordinate of diagonal D as S[p + o] + h (D - A o), and its similarity
// candidates for p itself as C_j(S[p + o]) - h A o (A = F^T). With the identity frame these are
// the isometric S[p + D + M D] - h M D and C_j(S[p + D]) - h D of Eq. 4. With a rotated frame,
// the thesis subtracts h M D (and h D) as if the rounded offset o were exactly A^-1 of the
// exemplar offset; o lies on the voxel grid, so every frame then snaps to the nearest of the
// few neighbourhood shapes a 3x3x3 grid has (a slant of 30 degrees came out at 45 in our tests).
// Correcting by the offset actually taken, A o, removes that bias (IMPLEMENTER CHOICE).
struct Neighbourhood {
  std::array<Int3, kDiagonals> neighbour;
  std::array<Eigen::Vector3f, kDiagonals> candidate_shift;  // -A o
  std::array<std::array<Int3, 4>, kDiagonals> predictor;
  std::array<std::array<Eigen::Vector3f, 4>, kDiagonals> prediction_shift;  // D - A o
};

Neighbourhood WarpedNeighbourhood(const Eigen::Matrix3f& frame) {
  Neighbourhood result;
  const auto rounded = [](const Eigen::Vector3f& v) -> Int3 {
    return {Round(v.x()), Round(v.y()), Round(v.z())};
  };
  const auto exemplar_offset = [&frame](const Int3& o) -> Eigen::Vector3f {
    return frame.transpose() * Eigen::Vector3f(static_cast<float>(o[0]), static_cast<float>(o[1]),
                                               static_cast<float>(o[2]));
  };
  for (int i = 0; i < kDiagonals; ++i) {
    const Eigen::Vector3f delta(static_cast<float>(kDiagonal[i][0]),
                                static_cast<float>(kDiagonal[i][1]),
                                static_cast<float>(kDiagonal[i][2]));
    Eigen::Vector3f phi = frame * delta;  // A^-1 = F
    phi /= phi.norm();
    result.neighbour[i] = rounded(phi);
    result.candidate_shift[i] = -exemplar_offset(result.neighbour[i]);
    result.predictor[i][0] = result.neighbour[i];
    for (int axis = 0; axis < 3; ++axis) {
      Eigen::Vector3f step = frame.col(axis) * delta[axis];
      step /= step.norm();
      result.predictor[i][static_cast<std::size_t>(axis + 1)] = rounded(phi + step);
    }
    for (std::size_t m = 0; m < 4; ++m) {
      result.prediction_shift[i][m] = delta - exemplar_offset(result.predictor[i][m]);
    }
  }
  return result;
}

// Per-task buffers of the correction.
struct Scratch {
  std::vector<float> synthesized;
  std::vector<std::size_t> candidates;
};

// The candidates of every voxel of one parity class (the current coordinate first, so ties keep
// it), with their neighbourhood distances |N_S(p) - N_E(u)|^2 and their costs (the distance
// weighted by occupancy matching). Unused slots have an infinite cost.
class CandidateTable {
 public:
  CandidateTable(std::size_t voxels, std::size_t stride)
      : stride_(stride),
        voxels_(voxels * stride, 0),
        distances_(voxels * stride, 0.0f),
        costs_(voxels * stride, std::numeric_limits<float>::infinity()) {}

  std::size_t size() const { return voxels_.size() / stride_; }
  std::size_t stride() const { return stride_; }
  std::size_t voxel(std::size_t i, std::size_t slot) const { return voxels_[i * stride_ + slot]; }
  float distance(std::size_t i, std::size_t slot) const { return distances_[i * stride_ + slot]; }
  float cost(std::size_t i, std::size_t slot) const { return costs_[i * stride_ + slot]; }
  void Set(std::size_t i, std::size_t slot, std::size_t voxel, float distance, float cost) {
    voxels_[i * stride_ + slot] = static_cast<std::uint32_t>(voxel);
    distances_[i * stride_ + slot] = distance;
    costs_[i * stride_ + slot] = cost;
  }

  // Every voxel's slot of the lowest cost (plain matching, no prices).
  std::vector<std::size_t> CheapestSlots() const {
    std::vector<std::size_t> slots(size(), 0);
    tbb::parallel_for(std::size_t{0}, size(), [&](std::size_t i) {
      slots[i] = Cheapest(i, [](float cost, std::size_t) { return cost; });
    });
    return slots;
  }

  // The slot of the lowest cost times `weight(voxel)` (the first of equals).
  template <typename Weight>
  std::size_t Cheapest(std::size_t i, Weight weight) const {
    std::size_t best = 0;
    float best_cost = std::numeric_limits<float>::infinity();
    for (std::size_t slot = 0; slot < stride_; ++slot) {
      const float c = cost(i, slot);
      if (c == std::numeric_limits<float>::infinity()) break;
      const float weighted = weight(c, voxel(i, slot));
      if (weighted < best_cost) best_cost = weighted, best = slot;
    }
    return best;
  }

 private:
  std::size_t stride_;
  std::vector<std::uint32_t> voxels_;
  std::vector<float> distances_;
  std::vector<float> costs_;
};

// Bins per channel of the histogram matching: twice HistogramDistance's default, so that the
// tests' measure is not the control's own (they also measure the bin-free EarthMoverDistance).
constexpr int kHistogramBins = 64;
// Bound of a log-price: a candidate's cost is at most multiplied (or divided) by e. With e^4, the
// prices forced single voxels onto candidates of another colour, a speckle inside the cells that
// shows in the slices, and the match error of cells 16^3 grown to 32^3 rose from 0.0125 to
// 0.0158 (0.0088 without histogram matching), with no better histogram.
constexpr float kMaximumLogPrice = 1.0f;
// Bound of a log-price's step in one round.
constexpr float kLargestStep = 1.0f;
// Price rounds per subpass (ExemplarSolidOptions::histogram_matching).
constexpr int kBalanceRounds = 16;
// Histogram matching runs on the finest level only (spacing h_l = 1): it decides the output's
// colours, while a coarser level's coordinates are a lattice subsample of the exemplar whose
// histogram differs from the exemplar's even for a perfect copy (with h_l <= 2 the identity test
// moved voxels; the measured figures were no better).
constexpr int kHistogramCoarsestSpacing = 1;
// The cost floor, as a share of the mean squared norm of the exemplar neighbourhoods N_E.
constexpr double kCostFloorShare = 0.02;

// Histogram matching (ExemplarSolidOptions::histogram_matching). Kopf et al. 2007 (section 4.2)
// re-weight their optimisation by how much the result over-uses a colour; here the re-weighting
// acts on the choice among candidates, as a price per (channel, bin) that a candidate pays for
// the bin its value falls in: its cost is multiplied by e^(mean over channels of its bins'
// log-prices). A log-price rises while the result over-uses its bin and falls (below 0: a
// discount) while the result under-uses it, and carries over from subpass to subpass, so it
// comes to rest only where the two histograms agree (dual ascent on "result histogram =
// exemplar histogram"). A price proportional to the current excess alone needs a standing
// excess to act, and left most of the drift.
class HistogramControl {
 public:
  HistogramControl() = default;
  // The exemplar's own channels (the per-channel histograms users compare), valid voxels only.
  HistogramControl(const Image& exemplar, const ExemplarDomain& domain, double first_step)
      : channels_(static_cast<std::size_t>(exemplar.channels())), first_step_(first_step) {
    const std::vector<std::size_t> valid = domain.ValidIndices();
    bins_.assign(exemplar.pixel_count() * channels_, 0);
    target_.assign(channels_ * kHistogramBins, 0.0);
    log_prices_.assign(target_.size(), 0.0f);
    for (std::size_t c = 0; c < channels_; ++c) {
      float low = std::numeric_limits<float>::max(), high = std::numeric_limits<float>::lowest();
      for (std::size_t u : valid) {
        low = std::min(low, exemplar.pixel(u)[c]);
        high = std::max(high, exemplar.pixel(u)[c]);
      }
      const float range = high > low ? high - low : 1.0f;
      for (std::size_t u : valid) {
        const int bin =
            std::clamp(static_cast<int>((exemplar.pixel(u)[c] - low) / range * kHistogramBins), 0,
                       kHistogramBins - 1);
        bins_[u * channels_ + c] = static_cast<std::uint8_t>(bin);
        target_[Slot(c, static_cast<std::size_t>(bin))] += 1.0 / static_cast<double>(valid.size());
      }
    }
  }

  bool enabled() const { return first_step_ > 0.0; }

  // Per (channel, bin), how many of the exemplar voxels `coordinates` point to fall in it
  // (`lookup` maps a coordinate triple to its voxel).
  template <typename Lookup>
  std::vector<double> Count(const std::vector<float>& coordinates, Lookup lookup) const {
    std::vector<double> counts(target_.size(), 0.0);
    for (std::size_t i = 0; i < coordinates.size() / 3; ++i)
      Add(counts, lookup(&coordinates[3 * i]), 1);
    return counts;
  }

  // Picks one candidate per voxel of `table`. Per round, every voxel picks its cheapest candidate
  // at the current prices, and the level's histogram that would result (`level_counts`, the
  // level's counts before this subpass, with each voxel's current coordinate, slot 0, replaced
  // by its pick) moves the log-price of every bin holding more voxels than the exemplar's share
  // up, and of every bin holding fewer down, each by its own step (Rprop: a step grows by 1.5
  // while its bin's excess keeps its sign and halves when it flips, starting at `first_step`
  // each subpass). Steps by sign suit a discrete choice whose counts jump, and let the spiky
  // histograms (thin bright sheets on a dark ground) settle as well as the smooth ones; steps
  // proportional to the excess either crawled or oscillated, depending on the exemplar. The
  // picks of a round are proposals; the round whose picks bring the histogram closest to the
  // exemplar's wins, the picks without prices (plain matching) included, so a subpass never
  // leaves the histogram further off than plain matching would. (Picking at prices once per
  // subpass, our first version, made all voxels of a class flee an over-used bin together.)
  // `floor` is added to every cost, so that a perfect match (cost 0) still pays its bin's price.
  std::vector<std::size_t> Balance(const CandidateTable& table, std::vector<double> level_counts,
                                   std::size_t level_voxels, float floor) {
    for (std::size_t i = 0; i < table.size(); ++i) Add(level_counts, table.voxel(i, 0), -1);
    const auto counts_with = [&](const std::vector<std::size_t>& picks) {
      std::vector<double> counts = level_counts;
      for (std::size_t i = 0; i < table.size(); ++i) Add(counts, table.voxel(i, picks[i]), 1);
      return counts;
    };
    const auto histogram_error = [&](const std::vector<double>& counts) {
      double error = 0;
      for (std::size_t k = 0; k < target_.size(); ++k) {
        error += std::abs(counts[k] - target_[k] * static_cast<double>(level_voxels));
      }
      return error;
    };
    std::vector<std::size_t> picks = table.CheapestSlots();
    std::vector<std::size_t> best_picks = picks;
    double best_error = histogram_error(counts_with(picks));
    std::vector<float> weights(bins_.size() / channels_, 1.0f);
    std::vector<float> steps(target_.size(), static_cast<float>(first_step_));
    std::vector<int> last_sign(target_.size(), 0);
    for (int round = 0; round < kBalanceRounds; ++round) {
      // Every exemplar voxel's price factor, once per round rather than once per candidate.
      tbb::parallel_for(std::size_t{0}, weights.size(),
                        [&](std::size_t u) { weights[u] = Weight(u); });
      tbb::parallel_for(std::size_t{0}, table.size(), [&](std::size_t i) {
        picks[i] = table.Cheapest(
            i, [&](float cost, std::size_t voxel) { return (cost + floor) * weights[voxel]; });
      });
      const std::vector<double> counts = counts_with(picks);
      const double error = histogram_error(counts);
      if (error < best_error) best_error = error, best_picks = picks;
      for (std::size_t k = 0; k < target_.size(); ++k) {
        if (target_[k] <= 0.0) continue;  // no valid voxel (hence no candidate) falls in this bin
        const double excess = counts[k] - target_[k] * static_cast<double>(level_voxels);
        const int sign = excess > 0.5 ? 1 : excess < -0.5 ? -1 : 0;
        if (sign != 0 && sign == last_sign[k]) steps[k] = std::min(kLargestStep, steps[k] * 1.5f);
        if (sign != 0 && sign == -last_sign[k]) steps[k] *= 0.5f;
        last_sign[k] = sign;
        log_prices_[k] = std::clamp(log_prices_[k] + static_cast<float>(sign) * steps[k],
                                    -kMaximumLogPrice, kMaximumLogPrice);
      }
    }
    return best_picks;
  }

 private:
  static std::size_t Slot(std::size_t channel, std::size_t bin) {
    return channel * kHistogramBins + bin;
  }

  void Add(std::vector<double>& counts, std::size_t voxel, double amount) const {
    for (std::size_t c = 0; c < channels_; ++c)
      counts[Slot(c, bins_[voxel * channels_ + c])] += amount;
  }

  // The factor of a candidate voxel's cost: e^(mean over channels of its bins' log-prices), the
  // mean so that the price's reach does not grow with the channel count (a PTM stack has 18).
  float Weight(std::size_t voxel) const {
    float log_price = 0.0f;
    for (std::size_t c = 0; c < channels_; ++c) {
      log_price += log_prices_[Slot(c, bins_[voxel * channels_ + c])];
    }
    return std::exp(log_price / static_cast<float>(channels_));
  }

  std::size_t channels_ = 0;
  double first_step_ = 0.0;
  std::vector<std::uint8_t> bins_;  // voxel_count x channels
  std::vector<double> target_;      // channels x kHistogramBins, each channel summing to 1
  std::vector<float> log_prices_;   // channels x kHistogramBins
};

// Occupancy matching (ExemplarSolidOptions::occupancy_matching): how much more than a uniform
// copy the result uses each block of the exemplar.
struct OccupancyPenalties {
  int blocks = 0;             // per axis
  std::vector<float> values;  // lambda * max(0, count / expected - 1) per block, x fastest
  bool empty() const { return values.empty(); }
};

class OccupancyWeights {
 public:
  OccupancyWeights(const ExemplarDomain& domain, double lambda)
      : domain_(domain), lambda_(lambda) {}

  bool enabled() const { return lambda_ > 0.0; }

  // Counted over the exemplar voxels `coordinates` (a level of `side`^3 voxels) point to
  // (`lookup` maps a coordinate triple to its voxel).
  template <typename Lookup>
  OccupancyPenalties Penalties(const std::vector<float>& coordinates, int side,
                               Lookup lookup) const {
    const auto extent = domain_.extent();
    OccupancyPenalties result;
    result.blocks = std::max(1, std::min({extent[0], extent[1], extent[2], side / 2}));
    result.values.assign(static_cast<std::size_t>(result.blocks) * result.blocks * result.blocks,
                         0.0f);
    const std::size_t voxels = coordinates.size() / 3;
    for (std::size_t i = 0; i < voxels; ++i) {
      result.values[Block(lookup(&coordinates[3 * i]), result.blocks)] += 1.0f;
    }
    const float expected = static_cast<float>(voxels) / static_cast<float>(result.values.size());
    for (float& value : result.values) {
      value = static_cast<float>(lambda_) * std::max(0.0f, value / expected - 1.0f);
    }
    return result;
  }

  // The factor of a candidate voxel's distance.
  float Weight(const OccupancyPenalties& penalties, std::size_t voxel) const {
    return 1.0f + penalties.values[Block(voxel, penalties.blocks)];
  }

 private:
  std::size_t Block(std::size_t voxel, int blocks) const {
    const auto c = domain_.Coordinates(voxel);
    const auto extent = domain_.extent();
    std::size_t index = 0;
    for (int axis = 2; axis >= 0; --axis) {
      const auto a = static_cast<std::size_t>(axis);
      index = index * static_cast<std::size_t>(blocks) +
              static_cast<std::size_t>((c[a] - domain_.origin()) * blocks / extent[a]);
    }
    return index;
  }

  const ExemplarDomain& domain_;
  double lambda_ = 0.0;
};

class Synthesizer {
 public:
  Synthesizer(const Image& exemplar, const PreparedExemplar& prepared,
              const ExemplarSolidOptions& options)
      : exemplar_(exemplar),
        prepared_(prepared),
        appearance_(&prepared.appearance),
        similarity_(&prepared.similarity),
        domain_(prepared.appearance.domain),
        options_(options),
        d_(static_cast<std::size_t>(prepared.appearance.dimensions)),
        occupancy_(prepared.appearance.domain, options.occupancy_matching) {
    const auto extent = domain_.extent();
    smallest_extent_ = std::min({extent[0], extent[1], extent[2]});
    if (options.histogram_matching > 0.0) {
      histogram_ = HistogramControl(exemplar, domain_, options.histogram_matching);
    }
  }

  ExemplarSolidResult Run(Progress& report) {
    const ImageExtent& size = options_.size;
    int levels = 0;
    while ((1 << levels) < std::max({size.width, size.height, size.depth})) ++levels;
    std::vector<FrameField> fields;
    if (options_.field) fields = FieldPyramid(levels);

    ExemplarSolidResult result;
    std::vector<float> coordinates(3, static_cast<float>(domain_.origin()));
    report.Start("solid synthesis", static_cast<std::size_t>(levels));
    for (int level = 1; level <= levels; ++level) {
      const int side = 1 << level;
      const int spacing = 1 << (levels - level);
      const FrameField* field = options_.field ? &fields[static_cast<std::size_t>(level)] : nullptr;
      coordinates = Upsample(coordinates, side / 2, spacing, field);
      Jitter(coordinates, side, spacing, level);
      // Offsets of h_l >= n / 2 wrap around the exemplar: those levels are jitter only.
      if (2 * spacing < smallest_extent_ && options_.correction_passes > 0) {
        // The Gaussian-stack level of this spacing (or the exemplar itself).
        appearance_ = &prepared_.AppearanceAt(spacing);
        similarity_ = &prepared_.SimilarityAt(spacing);
        const std::vector<float> exemplar_neighbourhoods = ExemplarNeighbourhoods(spacing);
        histogram_active_ = histogram_.enabled() && spacing <= kHistogramCoarsestSpacing;
        if (histogram_active_) cost_floor_ = CostFloor(exemplar_neighbourhoods);
        for (int pass = 0; pass < options_.correction_passes; ++pass) {
          const double objective =
              Correct(coordinates, side, spacing, field, exemplar_neighbourhoods);
          result.passes.push_back({level, spacing, pass, objective});
        }
      }
      report.Advance();
    }
    report.Finish();
    Output(coordinates, 1 << levels, result);
    return result;
  }

 private:
  std::vector<FrameField> FieldPyramid(int levels) const {
    std::vector<FrameField> fields(static_cast<std::size_t>(levels) + 1);
    fields[static_cast<std::size_t>(levels)] =
        options_.field->Resampled(ImageExtent::Cube(1 << levels));
    for (int level = levels - 1; level >= 0; --level) {
      fields[static_cast<std::size_t>(level)] =
          fields[static_cast<std::size_t>(level) + 1].Downsampled();
    }
    return fields;
  }

  static std::size_t Index(int side, int x, int y, int z) {
    return (static_cast<std::size_t>(z) * side + y) * side + x;
  }

  float WrapFloat(float value, int axis) const {
    const float origin = static_cast<float>(domain_.origin());
    const float length = static_cast<float>(domain_.extent()[static_cast<std::size_t>(axis)]);
    float offset = std::fmod(value - origin, length);
    if (offset < 0) offset += length;
    return origin + offset;
  }

  // The exemplar voxel a (float) coordinate points to.
  std::size_t Lookup(const float* coordinate) const {
    return domain_.Index(domain_.Wrap(Round(coordinate[0]), 0),
                         domain_.Wrap(Round(coordinate[1]), 1),
                         domain_.Wrap(Round(coordinate[2]), 2));
  }

  // Eq. 1 (isometric) or Eq. 5 (anisometric, A = F^T) of the spec.
  std::vector<float> Upsample(const std::vector<float>& parent, int parent_side, int spacing,
                              const FrameField* field) const {
    const int side = 2 * parent_side;
    std::vector<float> child(static_cast<std::size_t>(side) * side * side * 3);
    tbb::parallel_for(0, side, [&](int z) {
      for (int y = 0; y < side; ++y) {
        for (int x = 0; x < side; ++x) {
          const float* from = &parent[3 * Index(parent_side, x / 2, y / 2, z / 2)];
          float* to = &child[3 * Index(side, x, y, z)];
          Eigen::Vector3f offset(static_cast<float>(x & 1), static_cast<float>(y & 1),
                                 static_cast<float>(z & 1));
          if (field) {
            offset = field->at(x, y, z).transpose() * (offset - Eigen::Vector3f::Constant(0.5f));
          }
          for (int axis = 0; axis < 3; ++axis) {
            to[axis] = WrapFloat(from[axis] + static_cast<float>(spacing) * offset[axis], axis);
          }
        }
      }
    });
    return child;
  }

  // Eq. 2: S += floor(h r H(p) + 1/2), H a hash of (seed, level, p) in [-1, 1]^3.
  void Jitter(std::vector<float>& coordinates, int side, int spacing, int level) const {
    if (options_.jitter == 0.0) return;
    const float amplitude = static_cast<float>(spacing * options_.jitter);
    tbb::parallel_for(0, side, [&](int z) {
      for (int y = 0; y < side; ++y) {
        for (int x = 0; x < side; ++x) {
          float* s = &coordinates[3 * Index(side, x, y, z)];
          for (int axis = 0; axis < 3; ++axis) {
            const float h = HashToSigned(
                HashVoxel(options_.seed, static_cast<std::uint64_t>(3 * level + axis), x, y, z));
            s[axis] = WrapFloat(s[axis] + std::floor(amplitude * h + 0.5f), axis);
          }
        }
      }
    });
  }

  // What histogram matching adds to every candidate's cost (HistogramControl::Balance): a share
  // of the mean squared norm of the exemplar neighbourhoods, the scale of the distances.
  float CostFloor(const std::vector<float>& neighbourhoods) const {
    const std::vector<std::size_t> valid = domain_.ValidIndices();
    const std::size_t length = kDiagonals * d_;
    double sum = 0;
    for (std::size_t u : valid) {
      for (std::size_t k = 0; k < length; ++k) sum += std::pow(neighbourhoods[u * length + k], 2);
    }
    return static_cast<float>(kCostFloorShare * sum / static_cast<double>(valid.size()));
  }

  // N_E(u) = concat over the diagonals D of V~[u + h D], for every valid voxel u.
  std::vector<float> ExemplarNeighbourhoods(int spacing) const {
    std::vector<float> result(domain_.size.pixel_count() * kDiagonals * d_, 0.0f);
    const std::vector<std::size_t> valid = domain_.ValidIndices();
    tbb::parallel_for(std::size_t{0}, valid.size(), [&](std::size_t i) {
      const auto u = domain_.Coordinates(valid[i]);
      float* out = &result[valid[i] * kDiagonals * d_];
      for (int k = 0; k < kDiagonals; ++k) {
        const std::size_t v = domain_.Index(domain_.Wrap(u[0] + spacing * kDiagonal[k][0], 0),
                                            domain_.Wrap(u[1] + spacing * kDiagonal[k][1], 1),
                                            domain_.Wrap(u[2] + spacing * kDiagonal[k][2], 2));
        const auto value = appearance_->at(v);
        std::copy(value.begin(), value.end(), out + static_cast<std::size_t>(k) * d_);
      }
    });
    return result;
  }

  // One correction pass: 8 subpasses over the parity classes of voxels. Each subpass reads a
  // snapshot of the coordinates taken at its start, so no voxel ever reads one being written
  // (warped neighbourhoods can reach a voxel of the same class). Returns the mean objective.
  double Correct(std::vector<float>& coordinates, int side, int spacing, const FrameField* field,
                 const std::vector<float>& exemplar_neighbourhoods) {
    std::vector<float> error(static_cast<std::size_t>(side) * side * side, 0.0f);
    const auto lookup = [this](const float* c) { return Lookup(c); };
    for (int parity = 0; parity < 8; ++parity) {
      const Int3 start{parity & 1, (parity >> 1) & 1, (parity >> 2) & 1};
      if (start[0] >= side || start[1] >= side || start[2] >= side) continue;
      std::vector<Int3> members;
      for (int z = start[2]; z < side; z += 2) {
        for (int y = start[1]; y < side; y += 2) {
          for (int x = start[0]; x < side; x += 2) members.push_back({x, y, z});
        }
      }
      const std::vector<float> snapshot = coordinates;
      const OccupancyPenalties occupancy = occupancy_.enabled()
                                               ? occupancy_.Penalties(snapshot, side, lookup)
                                               : OccupancyPenalties();
      const CandidateTable table =
          ScoreClass(members, side, spacing, field, snapshot, exemplar_neighbourhoods, occupancy);
      const std::vector<std::size_t> picks =
          histogram_active_ ? histogram_.Balance(table, histogram_.Count(snapshot, lookup),
                                                 snapshot.size() / 3, cost_floor_)
                            : table.CheapestSlots();
      for (std::size_t i = 0; i < members.size(); ++i) {
        const Int3& p = members[i];
        const std::size_t index = Index(side, p[0], p[1], p[2]);
        const auto u = domain_.Coordinates(table.voxel(i, picks[i]));
        for (int axis = 0; axis < 3; ++axis) {
          coordinates[3 * index + static_cast<std::size_t>(axis)] =
              static_cast<float>(u[static_cast<std::size_t>(axis)]);
        }
        error[index] = table.distance(i, picks[i]);
      }
    }
    double sum = 0;
    for (float e : error) sum += e;
    return sum / static_cast<double>(error.size());
  }

  const float* At(const std::vector<float>& coordinates, int side, const Int3& p,
                  const Int3& offset) const {
    return &coordinates[3 * Index(side, Wrap(p[0] + offset[0], side), Wrap(p[1] + offset[1], side),
                                  Wrap(p[2] + offset[2], side))];
  }

  // The candidates of the voxels `members`, their distances and costs.
  CandidateTable ScoreClass(const std::vector<Int3>& members, int side, int spacing,
                            const FrameField* field, const std::vector<float>& snapshot,
                            const std::vector<float>& exemplar_neighbourhoods,
                            const OccupancyPenalties& occupancy) const {
    CandidateTable table(members.size(), 1 + kDiagonals * static_cast<std::size_t>(similarity_->k));
    const Neighbourhood isometric = WarpedNeighbourhood(Eigen::Matrix3f::Identity());
    tbb::parallel_for(tbb::blocked_range<std::size_t>(0, members.size()),
                      [&](const tbb::blocked_range<std::size_t>& range) {
                        Scratch scratch;
                        scratch.synthesized.resize(kDiagonals * d_);
                        scratch.candidates.reserve(table.stride());
                        for (std::size_t i = range.begin(); i != range.end(); ++i) {
                          const Int3& p = members[i];
                          const Neighbourhood local =
                              field ? WarpedNeighbourhood(field->at(p[0], p[1], p[2])) : isometric;
                          ScoreCandidates(p, side, spacing, local, snapshot,
                                          exemplar_neighbourhoods, occupancy, scratch, table, i);
                        }
                      });
    return table;
  }

  // Fills row `row` of `table` with the candidates of voxel p and their distances and costs.
  void ScoreCandidates(const Int3& p, int side, int spacing, const Neighbourhood& local,
                       const std::vector<float>& snapshot,
                       const std::vector<float>& exemplar_neighbourhoods,
                       const OccupancyPenalties& occupancy, Scratch& scratch, CandidateTable& table,
                       std::size_t row) const {
    std::vector<float>& synthesized = scratch.synthesized;
    std::vector<std::size_t>& candidates = scratch.candidates;
    // N_S(p): per diagonal, the mean of 4 predictions of its appearance.
    for (int i = 0; i < kDiagonals; ++i) {
      std::array<std::span<const float>, 4> predictions;
      for (int m = 0; m < 4; ++m) {
        const float* s = At(snapshot, side, p, local.predictor[i][static_cast<std::size_t>(m)]);
        const Eigen::Vector3f& shift = local.prediction_shift[i][static_cast<std::size_t>(m)];
        const float h = static_cast<float>(spacing);
        const std::size_t u = domain_.Index(domain_.Wrap(Round(s[0] + h * shift.x()), 0),
                                            domain_.Wrap(Round(s[1] + h * shift.y()), 1),
                                            domain_.Wrap(Round(s[2] + h * shift.z()), 2));
        predictions[static_cast<std::size_t>(m)] = appearance_->at(u);
      }
      float* target = synthesized.data() + static_cast<std::size_t>(i) * d_;
      for (std::size_t k = 0; k < d_; ++k) {
        // Pairwise, so four equal predictions average to exactly that value.
        target[k] =
            ((predictions[0][k] + predictions[1][k]) + (predictions[2][k] + predictions[3][k])) *
            0.25f;
      }
    }
    // Candidates: the current coordinate first (ties keep it), then C_j(S[p + D]) - h D.
    candidates.clear();
    candidates.push_back(Lookup(&snapshot[3 * Index(side, p[0], p[1], p[2])]));
    for (int i = 0; i < kDiagonals; ++i) {
      const std::size_t base = Lookup(At(snapshot, side, p, local.neighbour[i]));
      for (std::int32_t c : similarity_->at(base)) {
        if (c < 0) continue;
        const auto u = domain_.Coordinates(static_cast<std::size_t>(c));
        const Eigen::Vector3f& shift = local.candidate_shift[i];
        const float h = static_cast<float>(spacing);
        const Int3 shifted{u[0] + Round(h * shift.x()), u[1] + Round(h * shift.y()),
                           u[2] + Round(h * shift.z())};
        if (!domain_.periodic && !domain_.Contains(shifted[0], shifted[1], shifted[2])) continue;
        const std::size_t candidate = domain_.Index(
            domain_.Wrap(shifted[0], 0), domain_.Wrap(shifted[1], 1), domain_.Wrap(shifted[2], 2));
        if (std::find(candidates.begin(), candidates.end(), candidate) == candidates.end()) {
          candidates.push_back(candidate);
        }
      }
    }
    const std::size_t length = kDiagonals * d_;
    for (std::size_t slot = 0; slot < candidates.size(); ++slot) {
      const std::size_t candidate = candidates[slot];
      const float* e = &exemplar_neighbourhoods[candidate * length];
      float distance = 0.0f;
      for (std::size_t k = 0; k < length; ++k) {
        const float diff = synthesized[k] - e[k];
        distance += diff * diff;
      }
      const float cost =
          occupancy.empty() ? distance : distance * occupancy_.Weight(occupancy, candidate);
      table.Set(row, slot, candidate, distance, cost);
    }
  }

  void Output(const std::vector<float>& coordinates, int side, ExemplarSolidResult& result) const {
    const ImageExtent& size = options_.size;
    result.volume = Image(size, exemplar_.channels());
    if (!exemplar_.channel_names().empty()) {
      result.volume.set_channel_names(exemplar_.channel_names());
    }
    result.coordinates =
        Image(size, std::vector<std::string>{"exemplar.x", "exemplar.y", "exemplar.z"});
    tbb::parallel_for(0, size.depth, [&](int z) {
      for (int y = 0; y < size.height; ++y) {
        for (int x = 0; x < size.width; ++x) {
          const std::size_t u = Lookup(&coordinates[3 * Index(side, x, y, z)]);
          const auto source = exemplar_.pixel(u);
          std::copy(source.begin(), source.end(), result.volume.pixel(x, y, z).begin());
          const auto c = domain_.Coordinates(u);
          for (int axis = 0; axis < 3; ++axis) {
            result.coordinates.at(x, y, z, axis) =
                static_cast<float>(c[static_cast<std::size_t>(axis)]);
          }
        }
      }
    });
  }

  const Image& exemplar_;
  const PreparedExemplar& prepared_;
  const AppearanceSpace* appearance_;  // of the level being corrected
  const SimilaritySet* similarity_;
  const ExemplarDomain& domain_;
  const ExemplarSolidOptions& options_;
  std::size_t d_;
  int smallest_extent_ = 0;
  HistogramControl histogram_;
  bool histogram_active_ = false;  // at the level being corrected
  float cost_floor_ = 0.0f;
  OccupancyWeights occupancy_;
};

}  // namespace

ExemplarSolidResult SynthesizeExemplarSolid(const Image& exemplar, const PreparedExemplar& prepared,
                                            const ExemplarSolidOptions& options,
                                            Progress* progress) {
  if (options.size.width < 1 || options.size.height < 1 || options.size.depth < 1) {
    throw Error(fmt::format("invalid output size {}", ToString(options.size)));
  }
  if (!(options.jitter >= 0.0) || options.correction_passes < 0 ||
      !(options.histogram_matching >= 0.0) || !(options.occupancy_matching >= 0.0)) {
    throw Error("jitter, correction passes, histogram and occupancy matching must not be negative");
  }
  const auto fits = [&](const AppearanceSpace& appearance, const SimilaritySet& similarity) {
    return appearance.domain.size == exemplar.extent() &&
           appearance.domain.border == prepared.appearance.domain.border &&
           appearance.dimensions == prepared.appearance.dimensions &&
           similarity.indices.size() ==
               exemplar.pixel_count() * static_cast<std::size_t>(similarity.k);
  };
  bool consistent = fits(prepared.appearance, prepared.similarity);
  for (const PreparedLevel& level : prepared.stack) {
    consistent = consistent && fits(level.appearance, level.similarity);
  }
  if (!consistent) {
    throw Error("the prepared appearance space and similarity set are not this exemplar's");
  }
  NullProgress null_progress;
  Synthesizer synthesizer(exemplar, prepared, options);
  return synthesizer.Run(OrNull(progress, null_progress));
}

ExemplarSolidResult RandomCoordinateSolid(const Image& exemplar, const ExemplarDomain& domain,
                                          ImageExtent size, std::uint64_t seed) {
  ExemplarSolidResult result;
  result.volume = Image(size, exemplar.channels());
  if (!exemplar.channel_names().empty()) result.volume.set_channel_names(exemplar.channel_names());
  result.coordinates =
      Image(size, std::vector<std::string>{"exemplar.x", "exemplar.y", "exemplar.z"});
  const auto extent = domain.extent();
  for (int z = 0; z < size.depth; ++z) {
    for (int y = 0; y < size.height; ++y) {
      for (int x = 0; x < size.width; ++x) {
        Int3 u;
        for (std::size_t axis = 0; axis < 3; ++axis) {
          const std::uint64_t h = HashVoxel(seed, 100 + axis, x, y, z);
          u[axis] =
              domain.origin() + static_cast<int>(h % static_cast<std::uint64_t>(extent[axis]));
          result.coordinates.at(x, y, z, static_cast<int>(axis)) = static_cast<float>(u[axis]);
        }
        const auto source = exemplar.pixel(domain.Index(u[0], u[1], u[2]));
        std::copy(source.begin(), source.end(), result.volume.pixel(x, y, z).begin());
      }
    }
  }
  return result;
}

}  // namespace photomat
