#include "synthesize/solid/appearance_space.h"

#include <fmt/format.h>
#include <tbb/parallel_for.h>

#include <Eigen/Eigenvalues>
#include <algorithm>
#include <utility>

#include "core/error.h"

namespace photomat {
namespace {

// Voxels per block of the covariance and projection products. Fixed, so that every product has
// the same shape whatever the thread count and the results are the same bits.
constexpr std::size_t kBlock = 256;
// Groups of blocks whose covariances are summed separately, then in group order.
constexpr std::size_t kGroups = 8;

using RowMatrixXf = Eigen::Matrix<float, Eigen::Dynamic, Eigen::Dynamic, Eigen::RowMajor>;

// The exemplar's channels reduced to at most `max_channels` by PCA (identity when already few).
void FitChannelReduction(const Image& exemplar, int max_channels, AppearanceSpace& space) {
  const int channels = exemplar.channels();
  if (channels <= max_channels) {
    space.channel_mean = Eigen::VectorXf::Zero(channels);
    space.channel_basis = Eigen::MatrixXf::Identity(channels, channels);
    return;
  }
  // The voxels as a voxels x channels matrix (its columns are the planes), in blocks of rows.
  const Eigen::Map<const Eigen::MatrixXf> voxels(
      exemplar.values().data(), static_cast<Eigen::Index>(exemplar.pixel_count()), channels);
  Eigen::VectorXd sum = Eigen::VectorXd::Zero(channels);
  Eigen::MatrixXd outer = Eigen::MatrixXd::Zero(channels, channels);
  for (Eigen::Index first = 0; first < voxels.rows(); first += kBlock) {
    const Eigen::MatrixXd x =
        voxels.middleRows(first, std::min<Eigen::Index>(kBlock, voxels.rows() - first))
            .cast<double>();
    sum += x.colwise().sum().transpose();
    outer.noalias() += x.transpose() * x;
  }
  const double count = static_cast<double>(exemplar.pixel_count());
  const Eigen::VectorXd mean = sum / count;
  const Eigen::SelfAdjointEigenSolver<Eigen::MatrixXd> solver(outer / count -
                                                              mean * mean.transpose());
  space.channel_mean = mean.cast<float>();
  space.channel_basis =
      solver.eigenvectors().rightCols(max_channels).rowwise().reverse().cast<float>();
}

// voxel_count x reduced channels.
RowMatrixXf ReducedChannels(const Image& volume, const AppearanceSpace& space) {
  const int channels = volume.channels();
  // Planar storage: the voxels x channels matrix is column-major.
  const Eigen::Map<const Eigen::MatrixXf> values(
      volume.values().data(), static_cast<Eigen::Index>(volume.pixel_count()), channels);
  if (space.channel_basis.isIdentity(0.0f)) return values;
  return (values.rowwise() - space.channel_mean.transpose()) * space.channel_basis;
}

// An index beyond the array: wrapped (periodic exemplars) or clamped to the nearest face.
int Edge(int value, int length, bool periodic) {
  return periodic ? Wrap(value, length) : std::clamp(value, 0, length - 1);
}

// Writes the neighbourhood of (x, y, z) of `reduced` (a volume of `size`), samples `spacing`
// apart, into `out`, z outermost, then y, then x, channels innermost.
void Gather(const RowMatrixXf& reduced, const ImageExtent& size, int x, int y, int z, int side,
            int spacing, bool periodic, float* out) {
  const int half = side / 2;
  const int channels = static_cast<int>(reduced.cols());
  for (int dz = -half; dz <= half; ++dz) {
    const int zz = Edge(z + spacing * dz, size.depth, periodic);
    for (int dy = -half; dy <= half; ++dy) {
      const int yy = Edge(y + spacing * dy, size.height, periodic);
      for (int dx = -half; dx <= half; ++dx) {
        const int xx = Edge(x + spacing * dx, size.width, periodic);
        const std::size_t index =
            (static_cast<std::size_t>(zz) * size.height + yy) * size.width + xx;
        const float* source = reduced.data() + index * static_cast<std::size_t>(channels);
        out = std::copy(source, source + channels, out);
      }
    }
  }
}

}  // namespace

std::vector<std::size_t> ExemplarDomain::ValidIndices() const {
  std::vector<std::size_t> indices;
  for (int z = 0; z < size.depth; ++z) {
    for (int y = 0; y < size.height; ++y) {
      for (int x = 0; x < size.width; ++x) {
        if (Contains(x, y, z)) indices.push_back(Index(x, y, z));
      }
    }
  }
  return indices;
}

void AppearanceSpace::Project(const Image& volume, int x, int y, int z,
                              std::span<float> out) const {
  const int channels = volume.channels();
  const int side = neighbourhood;
  const int half = side / 2;
  const ImageExtent& size = volume.extent();
  Eigen::VectorXf feature(feature_mean.size());
  Eigen::Index k = 0;
  Eigen::VectorXf reduced(reduced_channels());
  Eigen::VectorXf v(channels);
  for (int dz = -half; dz <= half; ++dz) {
    for (int dy = -half; dy <= half; ++dy) {
      for (int dx = -half; dx <= half; ++dx) {
        const auto voxel =
            volume.pixel(Wrap(x + spacing * dx, size.width), Wrap(y + spacing * dy, size.height),
                         Wrap(z + spacing * dz, size.depth));
        std::copy(voxel.begin(), voxel.end(), v.data());
        reduced = channel_basis.transpose() * (v - channel_mean);
        feature.segment(k, reduced.size()) = reduced;
        k += reduced.size();
      }
    }
  }
  const Eigen::VectorXf projected = feature_basis.transpose() * (feature - feature_mean);
  std::copy(projected.data(), projected.data() + dimensions, out.begin());
}

namespace {

// The space's neighbourhood, spacing and domain, the options and the exemplar's size checked.
AppearanceSpace EmptyAppearanceSpace(const Image& exemplar, const AppearanceOptions& options) {
  if (options.neighbourhood < 1 || options.neighbourhood % 2 == 0) {
    throw Error(fmt::format("neighbourhood {} must be odd and positive", options.neighbourhood));
  }
  if (options.max_channels < 1 || options.covariance_samples < 16 || options.spacing < 1) {
    throw Error("max_channels and spacing must be positive and covariance_samples at least 16");
  }
  if (exemplar.empty()) throw Error("the exemplar is empty");
  AppearanceSpace space;
  space.neighbourhood = options.neighbourhood;
  space.spacing = options.spacing;
  space.domain.size = exemplar.extent();
  space.domain.periodic = options.boundary == ExemplarBoundary::kPeriodic;
  space.domain.border = space.domain.periodic ? 0 : options.neighbourhood / 2;
  const auto extent = space.domain.extent();
  if (std::min({exemplar.width(), exemplar.height(), exemplar.depth()}) < options.neighbourhood ||
      std::min({extent[0], extent[1], extent[2]}) < 1) {
    throw Error(fmt::format("a {} exemplar is too small for {}^3 neighbourhoods{}",
                            ToString(exemplar.extent()), options.neighbourhood,
                            space.domain.periodic ? "" : " inside its border"));
  }
  return space;
}

// The covariance and mean of the neighbourhood vectors of `samples` (each relative to `centre`,
// which keeps the sums well conditioned), summed in kGroups fixed groups of blocks: the same
// result on any number of threads.
std::pair<Eigen::MatrixXd, Eigen::VectorXd> NeighbourhoodCovariance(
    const RowMatrixXf& reduced, const Image& exemplar, const AppearanceSpace& space,
    const std::vector<std::size_t>& samples, const Eigen::RowVectorXf& centre, Progress& report) {
  const int side = space.neighbourhood;
  const Eigen::Index features = static_cast<Eigen::Index>(side) * side * side * reduced.cols();
  const std::size_t blocks = (samples.size() + kBlock - 1) / kBlock;
  std::vector<Eigen::MatrixXd> outer(kGroups, Eigen::MatrixXd::Zero(features, features));
  std::vector<Eigen::VectorXd> sums(kGroups, Eigen::VectorXd::Zero(features));
  tbb::parallel_for(std::size_t{0}, kGroups, [&](std::size_t group) {
    RowMatrixXf block(static_cast<Eigen::Index>(kBlock), features);
    for (std::size_t b = group; b < blocks; b += kGroups) {
      const std::size_t begin = b * kBlock, end = std::min(samples.size(), begin + kBlock);
      block.setZero();
      for (std::size_t i = begin; i < end; ++i) {
        const auto [x, y, z] = space.domain.Coordinates(samples[i]);
        float* row = block.row(static_cast<Eigen::Index>(i - begin)).data();
        Gather(reduced, exemplar.extent(), x, y, z, side, space.spacing, space.domain.periodic,
               row);
        for (Eigen::Index f = 0; f < features; ++f) row[f] -= centre[f % reduced.cols()];
      }
      const Eigen::MatrixXf product = block.transpose() * block;
      outer[group] += product.cast<double>();
      sums[group] += block.colwise().sum().transpose().cast<double>();
      report.Advance();
    }
  });
  Eigen::MatrixXd covariance = Eigen::MatrixXd::Zero(features, features);
  Eigen::VectorXd sum = Eigen::VectorXd::Zero(features);
  for (std::size_t g = 0; g < kGroups; ++g) {
    covariance += outer[g];
    sum += sums[g];
  }
  const double count = static_cast<double>(samples.size());
  const Eigen::VectorXd mean = sum / count;
  covariance = covariance / count - mean * mean.transpose();
  return {covariance, mean};
}

// The space's feature basis (the covariance's leading eigenvectors, each with a fixed sign), its
// mean and the variance it retains.
void FitFeatureBasis(const Eigen::MatrixXd& covariance, const Eigen::VectorXd& mean,
                     const Eigen::RowVectorXf& centre, Eigen::Index reduced_channels,
                     AppearanceSpace& space) {
  const Eigen::SelfAdjointEigenSolver<Eigen::MatrixXd> solver(covariance);
  const Eigen::VectorXd eigenvalues = solver.eigenvalues().cwiseMax(0.0);
  const double total = eigenvalues.sum();
  space.retained_variance = total > 0 ? eigenvalues.tail(space.dimensions).sum() / total : 1.0;
  Eigen::MatrixXd basis = solver.eigenvectors().rightCols(space.dimensions).rowwise().reverse();
  for (int c = 0; c < space.dimensions; ++c) {  // a fixed sign per component
    Eigen::Index largest = 0;
    basis.col(c).cwiseAbs().maxCoeff(&largest);
    if (basis(largest, c) < 0) basis.col(c) *= -1.0;
  }
  space.feature_basis = basis.cast<float>();
  const Eigen::Index features = mean.size();
  Eigen::VectorXf feature_mean(features);
  for (Eigen::Index f = 0; f < features; ++f) {
    feature_mean[f] = static_cast<float>(mean[f]) + centre[f % reduced_channels];
  }
  space.feature_mean = feature_mean;
}

// Every valid voxel's neighbourhood projected onto the basis, into space.values.
void ProjectEveryVoxel(const RowMatrixXf& reduced, const Image& exemplar,
                       const std::vector<std::size_t>& valid, AppearanceSpace& space,
                       Progress& report) {
  const int side = space.neighbourhood;
  const Eigen::Index features = static_cast<Eigen::Index>(side) * side * side * reduced.cols();
  const std::size_t d = static_cast<std::size_t>(space.dimensions);
  space.values.assign(exemplar.pixel_count() * d, 0.0f);
  const std::size_t projection_blocks = (valid.size() + kBlock - 1) / kBlock;
  tbb::parallel_for(std::size_t{0}, projection_blocks, [&](std::size_t b) {
    const std::size_t begin = b * kBlock, end = std::min(valid.size(), begin + kBlock);
    RowMatrixXf block(static_cast<Eigen::Index>(kBlock), features);
    block.setZero();
    for (std::size_t i = begin; i < end; ++i) {
      const auto [x, y, z] = space.domain.Coordinates(valid[i]);
      Gather(reduced, exemplar.extent(), x, y, z, side, space.spacing, space.domain.periodic,
             block.row(static_cast<Eigen::Index>(i - begin)).data());
    }
    const RowMatrixXf projected =
        (block.rowwise() - space.feature_mean.transpose()) * space.feature_basis;
    for (std::size_t i = begin; i < end; ++i) {
      const float* row = projected.row(static_cast<Eigen::Index>(i - begin)).data();
      std::copy(row, row + d, space.values.begin() + static_cast<std::ptrdiff_t>(valid[i] * d));
    }
    report.Advance();
  });
}

}  // namespace

AppearanceSpace ComputeAppearanceSpace(const Image& exemplar, const AppearanceOptions& options,
                                       Progress* progress) {
  NullProgress null_progress;
  Progress& report = OrNull(progress, null_progress);
  AppearanceSpace space = EmptyAppearanceSpace(exemplar, options);
  FitChannelReduction(exemplar, options.max_channels, space);
  const RowMatrixXf reduced = ReducedChannels(exemplar, space);
  const int side = options.neighbourhood;
  const Eigen::Index features = static_cast<Eigen::Index>(side) * side * side * reduced.cols();
  space.dimensions = static_cast<int>(std::min<Eigen::Index>(options.dimensions, features));
  if (space.dimensions < 1) throw Error("the appearance space needs at least one dimension");

  const std::vector<std::size_t> valid = space.domain.ValidIndices();
  const std::size_t stride =
      (valid.size() + static_cast<std::size_t>(options.covariance_samples) - 1) /
      static_cast<std::size_t>(options.covariance_samples);
  std::vector<std::size_t> samples;
  for (std::size_t i = 0; i < valid.size(); i += stride) samples.push_back(valid[i]);
  const Eigen::RowVectorXf centre = reduced.colwise().mean();  // keeps the sums well conditioned
  report.Start("appearance space",
               (samples.size() + kBlock - 1) / kBlock + (valid.size() + kBlock - 1) / kBlock);
  const auto [covariance, mean] =
      NeighbourhoodCovariance(reduced, exemplar, space, samples, centre, report);
  FitFeatureBasis(covariance, mean, centre, reduced.cols(), space);
  ProjectEveryVoxel(reduced, exemplar, valid, space, report);
  report.Finish();
  return space;
}

}  // namespace photomat
