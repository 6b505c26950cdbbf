#include "synthesize/solid/spectral_solid.h"

#include <fmt/format.h>
#include <tbb/parallel_for.h>

#include <Eigen/Eigenvalues>
#include <algorithm>
#include <cmath>
#include <complex>
#include <limits>

#include "core/error.h"
#include "core/random.h"
#include "synthesize/volume/voxel_hash.h"

namespace photomat {
namespace {

constexpr int kBins = 256;
constexpr double kBinsPerUnit = 128.0;

int BinOf(float value) {
  const int bin = static_cast<int>(std::floor((static_cast<double>(value) + 1.0) * kBinsPerUnit));
  return std::clamp(bin, 0, kBins - 1);
}

// --- colour basis ---

// The pixels of an image as a pixels x channels matrix: its planes are the columns.
Eigen::Map<const Eigen::MatrixXf> PixelMatrix(const Image& image) {
  return {image.values().data(), static_cast<Eigen::Index>(image.pixel_count()), image.channels()};
}

ColourBasis FitColourBasis(const std::vector<SolidView>& views) {
  const int channels = views.front().image.channels();
  Eigen::VectorXd sum = Eigen::VectorXd::Zero(channels);
  Eigen::MatrixXd outer = Eigen::MatrixXd::Zero(channels, channels);
  double count = 0;
  for (const SolidView& view : views) {
    const Eigen::MatrixXd x = PixelMatrix(view.image).cast<double>();
    sum += x.colwise().sum().transpose();
    outer.noalias() += x.transpose() * x;
    count += static_cast<double>(x.rows());
  }
  const Eigen::VectorXd mean = sum / count;
  const Eigen::MatrixXd covariance = outer / count - mean * mean.transpose();
  const Eigen::SelfAdjointEigenSolver<Eigen::MatrixXd> solver(covariance);
  Eigen::MatrixXd axes = solver.eigenvectors().rowwise().reverse();  // largest variance first
  for (int c = 0; c < channels; ++c) {
    // A fixed sign per axis: the largest component positive.
    Eigen::Index largest = 0;
    axes.col(c).cwiseAbs().maxCoeff(&largest);
    if (axes(largest, c) < 0) axes.col(c) *= -1.0;
  }
  ColourBasis basis;
  basis.mean = mean.cast<float>();
  basis.axes = axes.cast<float>();
  basis.low = Eigen::VectorXf::Constant(channels, std::numeric_limits<float>::max());
  basis.high = Eigen::VectorXf::Constant(channels, std::numeric_limits<float>::lowest());
  basis.input_low = Eigen::VectorXf::Constant(channels, std::numeric_limits<float>::max());
  basis.input_high = Eigen::VectorXf::Constant(channels, std::numeric_limits<float>::lowest());
  for (const SolidView& view : views) {
    const auto x = PixelMatrix(view.image);
    const Eigen::MatrixXf y = (x.rowwise() - basis.mean.transpose()) * basis.axes;
    basis.low = basis.low.cwiseMin(y.colwise().minCoeff().transpose());
    basis.high = basis.high.cwiseMax(y.colwise().maxCoeff().transpose());
    basis.input_low = basis.input_low.cwiseMin(x.colwise().minCoeff().transpose());
    basis.input_high = basis.input_high.cwiseMax(x.colwise().maxCoeff().transpose());
  }
  for (int c = 0; c < channels; ++c) {
    if (!(basis.high[c] > basis.low[c])) basis.high[c] = basis.low[c] + 1e-6f;  // flat channel
  }
  return basis;
}

// --- analysis ---

// Sub-model origins: an even grid whose crops cover the view, then random ones up to `wanted`.
std::vector<std::pair<int, int>> CropOrigins(int width, int height, int crop, int wanted,
                                             Random& random) {
  // Evenly spread origins whose crops cover [0, length).
  const auto spread = [crop](int length) {
    const int count = (length + crop - 1) / crop;
    if (count <= 1) return std::vector<int>{0};
    std::vector<int> origins;
    for (int i = 0; i < count; ++i) origins.push_back(i * (length - crop) / (count - 1));
    return origins;
  };
  std::vector<std::pair<int, int>> origins;
  for (int y : spread(height)) {
    for (int x : spread(width)) origins.emplace_back(x, y);
  }
  while (static_cast<int>(origins.size()) < wanted) {
    origins.emplace_back(
        static_cast<int>(random.Index(static_cast<std::uint64_t>(width - crop + 1))),
        static_cast<int>(random.Index(static_cast<std::uint64_t>(height - crop + 1))));
  }
  return origins;
}

// Full c x c amplitude array from a half spectrum (|F(-k)| = |F(k)| for real input).
std::vector<float> FullAmplitude(const std::vector<float>& half, int c) {
  const int half_width = c / 2 + 1;
  std::vector<float> full(static_cast<std::size_t>(c) * c);
  for (int fy = 0; fy < c; ++fy) {
    for (int fx = 0; fx < c; ++fx) {
      const float value =
          fx < half_width ? half[static_cast<std::size_t>(fy) * half_width + fx]
                          : half[static_cast<std::size_t>((c - fy) % c) * half_width + (c - fx)];
      full[static_cast<std::size_t>(fy) * c + fx] = value;
    }
  }
  // Continue the spectrum through frequency 0 (the mean is not constrained; see ChannelSpectrum).
  double neighbours = 0;
  for (int dy = -1; dy <= 1; ++dy) {
    for (int dx = -1; dx <= 1; ++dx) {
      if (dx != 0 || dy != 0) {
        neighbours += full[static_cast<std::size_t>((dy + c) % c) * c + (dx + c) % c];
      }
    }
  }
  full[0] = static_cast<float>(neighbours / 8.0);
  return full;
}

// Half spectrum of an N x N slice from crop statistics of size c, by bilinear interpolation at
// the same physical frequency (cycles per pixel); amplitudes are unitary, so comparable.
std::vector<float> ResampleHalfSpectrum(const std::vector<float>& half, int c, int n) {
  if (c == n) return half;
  const std::vector<float> full = FullAmplitude(half, c);
  const int half_width = n / 2 + 1;
  std::vector<float> result(static_cast<std::size_t>(n) * half_width);
  const double scale = static_cast<double>(c) / n;
  for (int fy = 0; fy < n; ++fy) {
    const double sy = (fy <= n / 2 ? fy : fy - n) * scale;
    const double y0 = std::floor(sy);
    const double ty = sy - y0;
    for (int fx = 0; fx < half_width; ++fx) {
      const double sx = fx * scale;
      const double x0 = std::floor(sx);
      const double tx = sx - x0;
      const auto at = [&](double x, double y) {
        const int ix = ((static_cast<int>(x) % c) + c) % c;
        const int iy = ((static_cast<int>(y) % c) + c) % c;
        return static_cast<double>(full[static_cast<std::size_t>(iy) * c + ix]);
      };
      const double value = (1 - ty) * ((1 - tx) * at(x0, y0) + tx * at(x0 + 1, y0)) +
                           ty * ((1 - tx) * at(x0, y0 + 1) + tx * at(x0 + 1, y0 + 1));
      result[static_cast<std::size_t>(fy) * half_width + fx] = static_cast<float>(value);
    }
  }
  return result;
}

void AssignRegions(ChannelSpectrum& statistics, int regions) {
  const std::size_t count = statistics.mean.size();
  const int half_width = statistics.spectrum_width();
  float low = std::numeric_limits<float>::max(), high = 0.0f;
  for (std::size_t i = 1; i < count; ++i) {
    low = std::min(low, statistics.mean[i]);
    high = std::max(high, statistics.mean[i]);
  }
  low = std::max(low, high * 1e-7f);
  if (!(high > 0.0f)) high = low = 1.0f;
  const double log_low = std::log(static_cast<double>(low));
  const double span = std::max(std::log(static_cast<double>(high)) - log_low, 1e-12);
  statistics.region.assign(count, -1);
  statistics.region_energy.assign(static_cast<std::size_t>(regions), 0.0);
  for (std::size_t i = 1; i < count; ++i) {
    const double value =
        std::max(static_cast<double>(statistics.mean[i]), static_cast<double>(low));
    const int region = std::clamp(
        static_cast<int>(std::floor(regions * (std::log(value) - log_low) / span)), 0, regions - 1);
    statistics.region[i] = region;
    statistics.region_energy[static_cast<std::size_t>(region)] +=
        statistics.Weight(static_cast<int>(i % half_width)) * statistics.mean[i];
  }
}

// Stretches `values` linearly onto [-1, 1] (a constant slice becomes 0).
void RescaleToUnitRange(std::span<float> values) {
  const auto [low_it, high_it] = std::minmax_element(values.begin(), values.end());
  const float low = *low_it, high = *high_it;
  if (!(high > low)) {
    std::fill(values.begin(), values.end(), 0.0f);
    return;
  }
  const float scale = 2.0f / (high - low);
  for (float& v : values) v = std::clamp(-1.0f + (v - low) * scale, -1.0f, 1.0f);
}

// --- the block ---

// The block: an N^3 volume of the decorrelated channels (see ColourBasis).
using Block = Image;

// Voxel index of pixel (column, row) of slice `index` of `plane` in an N^3 block.
std::size_t SliceVoxel(const Block& block, SlicePlane plane, int index, int column, int row) {
  switch (plane) {
    case SlicePlane::kXY:
      return block.Index(column, row, index);
    case SlicePlane::kXZ:
      return block.Index(column, index, row);
    case SlicePlane::kYZ:
      return block.Index(index, column, row);
  }
  return 0;
}

// Slice `index` of `plane` of channel c, row-major: the FFTs need it contiguous, which only an xy
// slice is in place.
void ReadSlice(const Block& block, int c, SlicePlane plane, int index, std::span<float> slice) {
  const int n = block.width();
  const float* values = block.plane(c).data();
  for (int row = 0; row < n; ++row) {
    for (int column = 0; column < n; ++column) {
      slice[static_cast<std::size_t>(row) * n + column] =
          values[SliceVoxel(block, plane, index, column, row)];
    }
  }
}

void WriteSlice(Block& block, int c, SlicePlane plane, int index, std::span<const float> slice) {
  const int n = block.width();
  float* values = block.plane(c).data();
  for (int row = 0; row < n; ++row) {
    for (int column = 0; column < n; ++column) {
      values[SliceVoxel(block, plane, index, column, row)] =
          slice[static_cast<std::size_t>(row) * n + column];
    }
  }
}

// Coerces every slice of `plane` of `source` and writes it to `target` (may be the same block:
// slices of one orientation share no voxel, so they are independent and run in parallel).
void ProcessPlane(const Block& source, Block& target, const SpectralModel& model, SlicePlane plane,
                  const RealFft2d<float>& fft, int halvings) {
  const int n = model.size;
  const auto& statistics = model.planes[static_cast<int>(plane)];
  tbb::parallel_for(0, n, [&](int index) {
    std::vector<float> slice(static_cast<std::size_t>(n) * n);
    for (int c = 0; c < source.channels(); ++c) {
      ReadSlice(source, c, plane, index, slice);
      MatchSpectrum(slice, statistics[c], fft, halvings);
      MatchHistogram(slice, statistics[c].histogram);
      WriteSlice(target, c, plane, index, slice);
    }
  });
}

struct ChannelFitSums {
  double histogram_mean = 0, histogram_max = 0, inside = 0, inside_average = 0, lsd = 0;
};

ChannelFitSums MeasureChannel(const Block& block, int c, const ChannelSpectrum& statistics,
                              SlicePlane plane, const RealFft2d<float>& fft) {
  const int n = statistics.size;
  const int half_width = statistics.spectrum_width();
  const std::size_t spectrum_size = fft.spectrum_size();
  std::vector<double> histogram_l1(static_cast<std::size_t>(n));
  std::vector<std::vector<float>> amplitudes(static_cast<std::size_t>(n));
  tbb::parallel_for(0, n, [&](int index) {
    std::vector<float> slice(static_cast<std::size_t>(n) * n);
    std::vector<std::complex<float>> spectrum(spectrum_size);
    ReadSlice(block, c, plane, index, slice);
    histogram_l1[static_cast<std::size_t>(index)] =
        CoarseHistogramL1(Histogram256(slice), statistics.histogram, 8);
    fft.Forward(slice, spectrum);
    auto& amplitude = amplitudes[static_cast<std::size_t>(index)];
    amplitude.resize(spectrum_size);
    for (std::size_t i = 0; i < spectrum_size; ++i) {
      amplitude[i] = std::abs(spectrum[i]) / static_cast<float>(n);
    }
  });
  ChannelFitSums sums;
  double weight_total = 0, inside = 0, inside_average = 0, lsd = 0;
  for (std::size_t i = 1; i < spectrum_size; ++i) {
    const double weight = statistics.Weight(static_cast<int>(i % half_width));
    double average = 0;
    for (const auto& amplitude : amplitudes) {
      average += amplitude[i];
      if (amplitude[i] >= statistics.low[i] && amplitude[i] <= statistics.high[i]) {
        inside += weight;
      }
    }
    average /= n;
    if (average >= statistics.low[i] && average <= statistics.high[i]) inside_average += weight;
    const double ratio =
        20.0 * std::log10(std::max(average, 1e-12) /
                          std::max(static_cast<double>(statistics.mean[i]), 1e-12));
    lsd += weight * ratio * ratio;
    weight_total += weight;
  }
  sums.inside = inside / (weight_total * n);
  sums.inside_average = inside_average / weight_total;
  sums.lsd = std::sqrt(lsd / weight_total);
  for (double l1 : histogram_l1) {
    sums.histogram_mean += l1 / n;
    sums.histogram_max = std::max(sums.histogram_max, l1);
  }
  return sums;
}

std::vector<PlaneFit> MeasureBlock(const Block& block, const SpectralModel& model,
                                   const RealFft2d<float>& fft) {
  std::vector<PlaneFit> fits;
  for (SlicePlane plane : kAllSlicePlanes) {
    if (!model.Constrains(plane)) continue;
    PlaneFit fit;
    fit.plane = plane;
    const auto& statistics = model.planes[static_cast<int>(plane)];
    for (int c = 0; c < block.channels(); ++c) {
      const ChannelFitSums sums = MeasureChannel(block, c, statistics[c], plane, fft);
      const double share = 1.0 / static_cast<double>(block.channels());
      fit.histogram_l1_mean += share * sums.histogram_mean;
      fit.histogram_l1_max = std::max(fit.histogram_l1_max, sums.histogram_max);
      fit.inside_bounds += share * sums.inside;
      fit.inside_bounds_average += share * sums.inside_average;
      fit.log_spectral_distance_db += share * sums.lsd;
    }
    fits.push_back(fit);
  }
  return fits;
}

Block BlockFromVolume(const Image& volume, const SpectralModel& model) {
  const int n = model.size;
  if (volume.extent() != ImageExtent::Cube(n) || volume.channels() != model.basis.channels()) {
    throw Error(fmt::format("a {} volume of {} channels does not match the model ({}^3, {})",
                            ToString(volume.extent()), volume.channels(), n,
                            model.basis.channels()));
  }
  return model.basis.ToNormalised(volume);
}

}  // namespace

// --- public ---

std::optional<ViewTransform> ParseViewTransform(std::string_view text) {
  if (text == "none") return ViewTransform::kNone;
  if (text == "transpose") return ViewTransform::kTranspose;
  if (text == "rotate90") return ViewTransform::kRotate90;
  if (text == "rotate180") return ViewTransform::kRotate180;
  if (text == "rotate270") return ViewTransform::kRotate270;
  if (text == "flipx") return ViewTransform::kFlipX;
  if (text == "flipy") return ViewTransform::kFlipY;
  return std::nullopt;
}

Image ApplyViewTransform(const Image& image, ViewTransform transform) {
  const int w = image.width(), h = image.height();
  const bool swaps = transform == ViewTransform::kTranspose ||
                     transform == ViewTransform::kRotate90 ||
                     transform == ViewTransform::kRotate270;
  Image result(swaps ? h : w, swaps ? w : h, image.channels());
  if (!image.channel_names().empty()) result.set_channel_names(image.channel_names());
  for (int y = 0; y < result.height(); ++y) {
    for (int x = 0; x < result.width(); ++x) {
      int sx = x, sy = y;
      switch (transform) {
        case ViewTransform::kNone:
          break;
        case ViewTransform::kTranspose:
          sx = y, sy = x;
          break;
        case ViewTransform::kRotate90:  // clockwise: the top row becomes the right column
          sx = y, sy = h - 1 - x;
          break;
        case ViewTransform::kRotate180:
          sx = w - 1 - x, sy = h - 1 - y;
          break;
        case ViewTransform::kRotate270:
          sx = w - 1 - y, sy = x;
          break;
        case ViewTransform::kFlipX:
          sx = w - 1 - x;
          break;
        case ViewTransform::kFlipY:
          sy = h - 1 - y;
          break;
      }
      const auto source = image.pixel(sx, sy);
      std::copy(source.begin(), source.end(), result.pixel(x, y).begin());
    }
  }
  return result;
}

Image ColourBasis::ToNormalised(const Image& image) const {
  const Eigen::MatrixXf y = (PixelMatrix(image).rowwise() - mean.transpose()) * axes;
  Image normalised = image.depth() == 1 ? Image(image.width(), image.height(), channels())
                                        : Image(image.extent(), channels());
  for (int c = 0; c < channels(); ++c) {
    const float l = low[c], range = high[c] - low[c];
    float* out = normalised.plane(c).data();
    for (Eigen::Index p = 0; p < y.rows(); ++p) out[p] = -1.0f + 2.0f * (y(p, c) - l) / range;
  }
  return normalised;
}

Image ColourBasis::FromNormalised(const Image& normalised) const {
  Eigen::MatrixXf y(static_cast<Eigen::Index>(normalised.pixel_count()), channels());
  for (int c = 0; c < channels(); ++c) {
    const float* in = normalised.plane(c).data();
    const float l = low[c], range = high[c] - low[c];
    for (Eigen::Index p = 0; p < y.rows(); ++p) y(p, c) = l + 0.5f * (in[p] + 1.0f) * range;
  }
  const Eigen::MatrixXf x = y * axes.transpose();
  Image image = normalised.depth() == 1 ? Image(normalised.width(), normalised.height(), channels())
                                        : Image(normalised.extent(), channels());
  for (int c = 0; c < channels(); ++c) {
    float* out = image.plane(c).data();
    for (Eigen::Index p = 0; p < x.rows(); ++p) {
      out[p] = std::clamp(x(p, c) + mean[c], input_low[c], input_high[c]);
    }
  }
  return image;
}

std::array<double, 256> Histogram256(std::span<const float> values) {
  std::array<double, 256> histogram{};
  for (float v : values) histogram[static_cast<std::size_t>(BinOf(v))] += 1.0;
  const double total = static_cast<double>(values.size());
  if (total > 0) {
    for (double& h : histogram) h /= total;
  }
  return histogram;
}

double HistogramL1(const std::array<double, 256>& a, const std::array<double, 256>& b) {
  double sum = 0;
  for (int k = 0; k < kBins; ++k) sum += std::abs(a[k] - b[k]);
  return sum;
}

double CoarseHistogramL1(const std::array<double, 256>& a, const std::array<double, 256>& b,
                         int merge) {
  double sum = 0;
  for (int start = 0; start < kBins; start += merge) {
    double difference = 0;
    for (int k = start; k < std::min(kBins, start + merge); ++k) difference += a[k] - b[k];
    sum += std::abs(difference);
  }
  return sum;
}

ChannelSpectrum AnalyseChannel(const Image& view, int channel, const SpectralSolidOptions& options,
                               int crop_size, std::uint64_t seed) {
  const int n = options.size;
  const int c = crop_size;
  const std::span<const float> values = view.plane(channel);
  Random random(seed);
  const auto origins = CropOrigins(view.width(), view.height(), c, options.crops, random);
  const RealFft2d<float> fft(c, c);
  const std::size_t half = fft.spectrum_size();
  std::vector<double> sum(half, 0.0);
  std::vector<float> low(half, std::numeric_limits<float>::max()), high(half, 0.0f);
  std::vector<float> crop(static_cast<std::size_t>(c) * c);
  std::vector<std::complex<float>> spectrum(half);
  for (const auto& [ox, oy] : origins) {
    for (int y = 0; y < c; ++y) {
      for (int x = 0; x < c; ++x) {
        crop[static_cast<std::size_t>(y) * c + x] =
            values[static_cast<std::size_t>(oy + y) * view.width() + ox + x];
      }
    }
    fft.Forward(crop, spectrum);
    for (std::size_t i = 0; i < half; ++i) {
      const float amplitude = std::abs(spectrum[i]) / static_cast<float>(c);
      sum[i] += amplitude;
      low[i] = std::min(low[i], amplitude);
      high[i] = std::max(high[i], amplitude);
    }
  }
  std::vector<float> mean(half);
  for (std::size_t i = 0; i < half; ++i) {
    mean[i] = static_cast<float>(sum[i] / static_cast<double>(origins.size()));
  }
  ChannelSpectrum statistics;
  statistics.size = n;
  statistics.mean = ResampleHalfSpectrum(mean, c, n);
  statistics.low = ResampleHalfSpectrum(low, c, n);
  statistics.high = ResampleHalfSpectrum(high, c, n);
  for (std::size_t i = 0; i < statistics.mean.size(); ++i) {
    // Interpolation keeps low <= mean <= high; rounding must not break it.
    statistics.low[i] = std::min(statistics.low[i], statistics.mean[i]);
    statistics.high[i] = std::max(statistics.high[i], statistics.mean[i]);
  }
  AssignRegions(statistics, options.regions);
  statistics.histogram = Histogram256(values);
  return statistics;
}

SpectralModel AnalyseViews(const std::vector<SolidView>& views,
                           const SpectralSolidOptions& options) {
  if (views.empty()) throw Error("solid synthesis from views needs at least one view");
  if (options.size < 8) throw Error(fmt::format("block size {} is below 8", options.size));
  if (options.regions < 1 || options.crops < 1 || options.clamp_halvings < 0 ||
      options.iterations < 0) {
    throw Error("crops and regions must be positive, halvings and iterations not negative");
  }
  SpectralModel model;
  model.size = options.size;
  const int channels = views.front().image.channels();
  int smallest_side = std::numeric_limits<int>::max();
  std::array<bool, 3> seen{};
  for (const SolidView& view : views) {
    if (view.image.empty()) throw Error("a view is empty");
    if (view.image.channels() != channels) {
      throw Error(fmt::format("views have {} and {} channels; all must have the same", channels,
                              view.image.channels()));
    }
    if (std::exchange(seen[static_cast<int>(view.plane)], true)) {
      throw Error(fmt::format("two views for plane {}", ToString(view.plane)));
    }
    smallest_side = std::min({smallest_side, view.image.width(), view.image.height()});
  }
  int crop = options.crop_size;
  if (crop == 0) crop = smallest_side >= 2 * options.size ? options.size : smallest_side / 2;
  crop -= crop % 2;
  if (crop < 8 || crop > smallest_side || crop > options.size) {
    throw Error(
        fmt::format("sub-model size {} does not fit views whose smaller side is {} and a "
                    "block of {} (views need at least 16 pixels a side)",
                    crop, smallest_side, options.size));
  }
  model.crop_size = crop;
  model.basis = FitColourBasis(views);
  model.channel_names = views.front().image.channel_names();
  std::uint64_t stream = 0;
  for (const SolidView& view : views) {
    const Image normalised = model.basis.ToNormalised(view.image);
    auto& planes = model.planes[static_cast<int>(view.plane)];
    for (int c = 0; c < channels; ++c) {
      planes.push_back(
          AnalyseChannel(normalised, c, options, crop, HashVoxel(options.seed, ++stream, 0, 0, 0)));
    }
  }
  return model;
}

void ClampAmplitudes(std::span<float> amplitude, const ChannelSpectrum& statistics, int halvings) {
  for (std::size_t i = 1; i < amplitude.size(); ++i) {
    float a = amplitude[i];
    const float low = statistics.low[i], high = statistics.high[i], mean = statistics.mean[i];
    for (int step = 0; step < halvings && (a < low || a > high); ++step) a = 0.5f * (a + mean);
    amplitude[i] = a;
  }
}

void EqualiseRegionEnergies(std::span<float> amplitude, const ChannelSpectrum& statistics) {
  const int half_width = statistics.spectrum_width();
  std::vector<double> energy(statistics.region_energy.size(), 0.0);
  for (std::size_t i = 1; i < amplitude.size(); ++i) {
    energy[static_cast<std::size_t>(statistics.region[i])] +=
        statistics.Weight(static_cast<int>(i % half_width)) * amplitude[i];
  }
  for (std::size_t i = 1; i < amplitude.size(); ++i) {
    const double slice_energy = energy[static_cast<std::size_t>(statistics.region[i])];
    if (slice_energy > 0) {
      amplitude[i] = static_cast<float>(
          amplitude[i] * statistics.region_energy[static_cast<std::size_t>(statistics.region[i])] /
          slice_energy);
    }
  }
}

void MatchSpectrum(std::span<float> slice, const ChannelSpectrum& statistics,
                   const RealFft2d<float>& fft, int halvings) {
  const int n = statistics.size;
  std::vector<std::complex<float>> spectrum(fft.spectrum_size());
  fft.Forward(slice, spectrum);
  const float unitary = 1.0f / static_cast<float>(n);
  std::vector<float> amplitude(spectrum.size());
  for (std::size_t i = 0; i < spectrum.size(); ++i) amplitude[i] = std::abs(spectrum[i]) * unitary;
  std::vector<float> original = amplitude;
  ClampAmplitudes(amplitude, statistics, halvings);
  EqualiseRegionEnergies(amplitude, statistics);
  for (std::size_t i = 1; i < spectrum.size(); ++i) {
    // New magnitude, same phase; a zero coefficient has no phase and takes a real value.
    const float target = amplitude[i] * static_cast<float>(n);
    spectrum[i] = original[i] > 0 ? spectrum[i] * (amplitude[i] / original[i])
                                  : std::complex<float>(target, 0.0f);
  }
  fft.Inverse(spectrum, slice);
  const float inverse_scale = 1.0f / (static_cast<float>(n) * static_cast<float>(n));
  for (float& v : slice) v *= inverse_scale;
  RescaleToUnitRange(slice);
}

void MatchHistogram(std::span<float> slice, const std::array<double, 256>& target) {
  const std::array<double, 256> source = Histogram256(slice);
  std::array<float, 256> new_value{};
  // Two-pointer walk over the cumulative distributions.
  int j = 0;
  double target_done = 0;  // mass of target bins before j
  double source_done = 0;
  for (int k = 0; k < kBins; ++k) {
    const double mass = source[static_cast<std::size_t>(k)];
    if (mass <= 0) continue;
    const double begin = source_done, end = source_done + mass;
    double weighted = 0, covered = 0;
    while (j < kBins) {
      const double bin_end = target_done + target[static_cast<std::size_t>(j)];
      const double overlap = std::min(end, bin_end) - std::max(begin, target_done);
      if (overlap > 0) {
        weighted += overlap * j;
        covered += overlap;
      }
      if (bin_end > end || j == kBins - 1) break;
      target_done = bin_end;
      ++j;
    }
    const double index = covered > 0 ? weighted / covered : j;
    new_value[static_cast<std::size_t>(k)] =
        static_cast<float>(-1.0 + (index + 0.5) / kBinsPerUnit);
    source_done = end;
  }
  for (float& v : slice) v = new_value[static_cast<std::size_t>(BinOf(v))];
}

SpectralSolidResult SynthesizeSpectralSolid(const std::vector<SolidView>& views,
                                            const SpectralSolidOptions& options,
                                            Progress* progress) {
  NullProgress null_progress;
  Progress& report = OrNull(progress, null_progress);
  SpectralSolidResult result;
  result.model = AnalyseViews(views, options);
  const SpectralModel& model = result.model;
  const int n = options.size;
  const std::size_t channels = static_cast<std::size_t>(model.basis.channels());

  // White noise, uniform in [-1, 1], from a per-voxel hash (independent of threads).
  Block block(ImageExtent::Cube(n), static_cast<int>(channels));
  tbb::parallel_for(0, n, [&](int z) {
    for (std::size_t c = 0; c < channels; ++c) {
      for (int y = 0; y < n; ++y) {
        float* row = block.row(static_cast<int>(c), y, z).data();
        for (int x = 0; x < n; ++x) row[x] = HashToSigned(HashVoxel(options.seed, c, x, y, z));
      }
    }
  });

  std::vector<SlicePlane> order;
  for (SlicePlane plane : options.order) {
    if (model.Constrains(plane) && std::find(order.begin(), order.end(), plane) == order.end()) {
      order.push_back(plane);
    }
  }
  const RealFft2d<float> fft(n, n);
  report.Start("solid from views", static_cast<std::size_t>(options.iterations) * order.size());
  for (int iteration = 1; iteration <= options.iterations; ++iteration) {
    const Block previous = block;
    if (options.sequential) {
      for (SlicePlane plane : order) {
        ProcessPlane(block, block, model, plane, fft, options.clamp_halvings);
        report.Advance();
      }
    } else {
      Block sum(ImageExtent::Cube(n), static_cast<int>(channels));
      Block processed = previous;
      for (SlicePlane plane : order) {
        ProcessPlane(previous, processed, model, plane, fft, options.clamp_halvings);
        std::transform(sum.values().begin(), sum.values().end(), processed.values().begin(),
                       sum.values().begin(), std::plus<float>());
        report.Advance();
      }
      const float share = 1.0f / static_cast<float>(order.size());
      std::transform(sum.values().begin(), sum.values().end(), block.values().begin(),
                     [share](float v) { return v * share; });
    }
    double change = 0, norm = 0;
    const std::span<const float> now = block.values(), before = previous.values();
    for (std::size_t i = 0; i < now.size(); ++i) {
      const double d = now[i] - before[i];
      change += d * d;
      norm += static_cast<double>(now[i]) * now[i];
    }
    IterationReport iteration_report;
    iteration_report.iteration = iteration;
    iteration_report.relative_change = norm > 0 ? std::sqrt(change / norm) : 0.0;
    if (options.measure_every_iteration || iteration == options.iterations) {
      iteration_report.fits = MeasureBlock(block, model, fft);
    }
    result.iterations.push_back(std::move(iteration_report));
  }
  report.Finish();

  result.volume = model.basis.FromNormalised(block);
  result.volume.set_channel_names(model.channel_names);
  return result;
}

std::vector<PlaneFit> MeasureSpectralFit(const Image& volume, const SpectralModel& model) {
  const RealFft2d<float> fft(model.size, model.size);
  return MeasureBlock(BlockFromVolume(volume, model), model, fft);
}

}  // namespace photomat
