#include "synthesize/solid/spectral_solid.h"

#include <gtest/gtest.h>
#include <tbb/global_control.h>

#include <cmath>
#include <complex>

#include "core/error.h"
#include "core/image_io.h"
#include "synthesize/volume/voxel_hash.h"
#include "tests/support/test_support.h"

namespace photomat {
namespace {

// Periodic box blur of a width x height array along x (radius rx) and y (radius ry).
std::vector<float> Blur(std::vector<float> values, int width, int height, int rx, int ry) {
  std::vector<float> out(values.size());
  for (int y = 0; y < height; ++y) {
    for (int x = 0; x < width; ++x) {
      float sum = 0;
      for (int d = -rx; d <= rx; ++d) sum += values[y * width + (x + d + width) % width];
      out[y * width + x] = sum / (2 * rx + 1);
    }
  }
  for (int y = 0; y < height; ++y) {
    for (int x = 0; x < width; ++x) {
      float sum = 0;
      for (int d = -ry; d <= ry; ++d) sum += out[((y + d + height) % height) * width + x];
      values[y * width + x] = sum / (2 * ry + 1);
    }
  }
  return values;
}

// An RGB view of streaks: noise blurred by (rx, ry), two correlated channels and one independent.
Image StreakView(int size, int rx, int ry, std::uint64_t seed) {
  std::vector<float> a(size * size), b(size * size);
  for (int i = 0; i < size * size; ++i) {
    a[i] = HashToSigned(HashVoxel(seed, 0, i, 0, 0));
    b[i] = HashToSigned(HashVoxel(seed, 1, i, 0, 0));
  }
  a = Blur(a, size, size, rx, ry);
  b = Blur(b, size, size, 1, 1);
  Image image(size, size, std::vector<std::string>{"R", "G", "B"});
  for (int i = 0; i < size * size; ++i) {
    image.pixel(static_cast<std::size_t>(i))[0] = 0.5f + a[i];
    image.pixel(static_cast<std::size_t>(i))[1] = 0.3f + 0.6f * a[i];
    image.pixel(static_cast<std::size_t>(i))[2] = 0.4f + 0.3f * b[i];
  }
  return image;
}

std::vector<SolidView> StreakViews() {
  // A field elongated along x: xy and xz slices show streaks along x, yz slices do not.
  return {{SlicePlane::kXY, StreakView(64, 5, 0, 1)},
          {SlicePlane::kXZ, StreakView(64, 5, 0, 2)},
          {SlicePlane::kYZ, StreakView(64, 1, 1, 3)}};
}

ChannelSpectrum NoiseStatistics(int n) {
  SpectralSolidOptions options;
  options.size = n;
  const Image view = StreakView(2 * n, 3, 0, 9);
  Image normalised(view.width(), view.height(), 1);
  for (std::size_t p = 0; p < view.pixel_count(); ++p)
    normalised.pixel(p)[0] = view.pixel(p)[0] - 0.5f;
  return AnalyseChannel(normalised, 0, options, n, 4);
}

TEST(SpectralSolidTest, ClampBringsAmplitudesInsideTheModelRange) {
  const ChannelSpectrum statistics = NoiseStatistics(32);
  std::vector<float> amplitude(statistics.mean.size());
  for (std::size_t i = 0; i < amplitude.size(); ++i) {
    amplitude[i] = 3.0f * HashToUnit(HashVoxel(5, 0, static_cast<std::int64_t>(i), 0, 0));
  }
  const std::vector<float> before = amplitude;
  ClampAmplitudes(amplitude, statistics, 50);
  int moved = 0;
  for (std::size_t i = 1; i < amplitude.size(); ++i) {
    if (before[i] >= statistics.low[i] && before[i] <= statistics.high[i]) {
      EXPECT_EQ(amplitude[i], before[i]);
    } else {
      ++moved;
      if (statistics.high[i] > statistics.low[i]) {
        EXPECT_GE(amplitude[i], statistics.low[i]);
        EXPECT_LE(amplitude[i], statistics.high[i]);
      }
    }
  }
  EXPECT_GT(moved, 100);
}

TEST(SpectralSolidTest, RegionEnergiesEqualTheModelsAfterEqualisation) {
  const ChannelSpectrum statistics = NoiseStatistics(32);
  std::vector<float> amplitude(statistics.mean.size());
  for (std::size_t i = 0; i < amplitude.size(); ++i) {
    amplitude[i] = 0.01f + HashToUnit(HashVoxel(6, 0, static_cast<std::int64_t>(i), 0, 0));
  }
  EqualiseRegionEnergies(amplitude, statistics);
  std::vector<double> energy(statistics.region_energy.size(), 0.0);
  for (std::size_t i = 1; i < amplitude.size(); ++i) {
    energy[statistics.region[i]] += statistics.Weight(static_cast<int>(i % 17)) * amplitude[i];
  }
  int non_empty = 0;
  for (std::size_t z = 0; z < energy.size(); ++z) {
    EXPECT_NEAR(energy[z], statistics.region_energy[z], 1e-4 * (1 + statistics.region_energy[z]));
    non_empty += statistics.region_energy[z] > 0;
  }
  EXPECT_GT(non_empty, 10);
}

TEST(SpectralSolidTest, SpectralMatchKeepsPhases) {
  const int n = 32;
  const ChannelSpectrum statistics = NoiseStatistics(n);
  std::vector<float> slice(n * n);
  for (int i = 0; i < n * n; ++i) slice[i] = HashToSigned(HashVoxel(7, 0, i, 0, 0));
  const RealFft2d<float> fft(n, n);
  std::vector<std::complex<float>> before(fft.spectrum_size()), after(fft.spectrum_size());
  fft.Forward(slice, before);
  MatchSpectrum(slice, statistics, fft, 50);
  fft.Forward(slice, after);
  float low = 1, high = -1;
  for (float v : slice) low = std::min(low, v), high = std::max(high, v);
  EXPECT_FLOAT_EQ(low, -1.0f);
  EXPECT_FLOAT_EQ(high, 1.0f);
  for (std::size_t i = 1; i < before.size(); ++i) {
    if (std::abs(after[i]) < 1e-3f * n) continue;  // phase of a vanishing coefficient
    const float phase_change = std::abs(std::arg(after[i] * std::conj(before[i])));
    EXPECT_LT(phase_change, 1e-2f) << "frequency " << i;
  }
}

TEST(SpectralSolidTest, HistogramMatchReachesTheTargetAndKeepsOrder) {
  // Target: a two-peaked histogram; source: uniform noise.
  std::vector<float> model(4096);
  for (int i = 0; i < 4096; ++i) {
    const float u = HashToSigned(HashVoxel(8, 0, i, 0, 0));
    model[i] = (i % 3 == 0 ? -0.6f : 0.4f) + 0.2f * u;
  }
  const auto target = Histogram256(model);
  std::vector<float> slice(64 * 64);
  for (int i = 0; i < 64 * 64; ++i) slice[i] = HashToSigned(HashVoxel(9, 0, i, 0, 0));
  const std::vector<float> before = slice;
  const double l1_before = HistogramL1(Histogram256(slice), target);
  MatchHistogram(slice, target);
  const double l1_after = HistogramL1(Histogram256(slice), target);
  EXPECT_GT(l1_before, 0.8);
  EXPECT_LT(l1_after, 0.25);  // bin granularity: a source bin is never split
  for (std::size_t i = 0; i < slice.size(); ++i) {
    for (std::size_t j = i + 1; j < std::min(slice.size(), i + 50); ++j) {
      if (before[i] < before[j]) {
        EXPECT_LE(slice[i], slice[j]);
      }
    }
  }
  // Applying it again moves values by at most about a bin.
  std::vector<float> again = slice;
  MatchHistogram(again, target);
  for (std::size_t i = 0; i < slice.size(); ++i) EXPECT_NEAR(again[i], slice[i], 2.0 / 128);
}

double StreakAnisotropy(const Image& volume, SlicePlane plane) {
  // Mean squared difference of neighbours along slice columns vs rows (channel R).
  double along_columns = 0, along_rows = 0;
  for (int i = 0; i < SliceCount(volume.extent(), plane); ++i) {
    const Image slice = ExtractSlice(volume, plane, i);
    for (int y = 0; y + 1 < slice.height(); ++y) {
      for (int x = 0; x + 1 < slice.width(); ++x) {
        along_columns += std::pow(slice.at(x + 1, y, 0) - slice.at(x, y, 0), 2);
        along_rows += std::pow(slice.at(x, y + 1, 0) - slice.at(x, y, 0), 2);
      }
    }
  }
  return along_rows / along_columns;  // > 1: smoother along columns (streaks along them)
}

void PrintReport(const std::vector<IterationReport>& iterations) {
  for (const IterationReport& report : iterations) {
    std::printf("iteration %d: change %.4f", report.iteration, report.relative_change);
    for (const PlaneFit& fit : report.fits) {
      std::printf(" | %s histogram L1 %.3f (max %.3f) inside %.3f, mean inside %.3f, %.2f dB",
                  std::string(ToString(fit.plane)).c_str(), fit.histogram_l1_mean,
                  fit.histogram_l1_max, fit.inside_bounds, fit.inside_bounds_average,
                  fit.log_spectral_distance_db);
    }
    std::printf("\n");
  }
}

TEST(SpectralSolidTest, ReproducesEachViewsStatisticsAndConverges) {
  SpectralSolidOptions options;
  options.size = 32;
  options.iterations = 5;
  options.measure_every_iteration = true;
  const SpectralSolidResult result = SynthesizeSpectralSolid(StreakViews(), options);
  PrintReport(result.iterations);
  ASSERT_EQ(result.iterations.size(), 5u);
  // Convergence: the change levels off after two or three iterations.
  const auto& it = result.iterations;
  EXPECT_LT(it[1].relative_change, 0.3 * it[0].relative_change);
  for (std::size_t t = 2; t < it.size(); ++t) {
    EXPECT_LE(it[t].relative_change, it[t - 1].relative_change);
  }
  // The fit of each constrained orientation, against the white-noise start.
  const std::vector<PlaneFit> noise = MeasureSpectralFit(
      [&] {
        Image start(ImageExtent::Cube(32), 3);
        for (std::size_t i = 0; i < start.values().size(); ++i) {
          start.values()[i] = 0.5f + 0.5f * HashToSigned(HashVoxel(1, 0, i, 0, 0));
        }
        return start;
      }(),
      result.model);
  ASSERT_EQ(it.back().fits.size(), 3u);
  for (std::size_t p = 0; p < 3; ++p) {
    const PlaneFit& fit = it.back().fits[p];
    SCOPED_TRACE(std::string(ToString(fit.plane)));
    EXPECT_GT(fit.inside_bounds_average, 0.85);  // slice-mean spectrum inside [F-, F+]
    EXPECT_GT(fit.inside_bounds, 0.75);          // single slices
    EXPECT_LT(fit.histogram_l1_mean, 0.2);
    EXPECT_LT(fit.histogram_l1_mean, 0.3 * noise[p].histogram_l1_mean);
    EXPECT_LT(fit.log_spectral_distance_db, 0.5 * noise[p].log_spectral_distance_db);
    // Each iteration improves on the first.
    EXPECT_GE(fit.inside_bounds, it.front().fits[p].inside_bounds);
  }
  // Anisotropy: streaks along x in the xy and xz slices, none in yz.
  EXPECT_GT(StreakAnisotropy(result.volume, SlicePlane::kXY), 2.0);
  EXPECT_GT(StreakAnisotropy(result.volume, SlicePlane::kXZ), 2.0);
  EXPECT_NEAR(StreakAnisotropy(result.volume, SlicePlane::kYZ), 1.0, 0.3);
}

TEST(SpectralSolidTest, WoodFromThreeRealViews) {
  PHOTOMAT_TEST_DATA_OR_SKIP(folder, "textures/solid-exemplars");
  std::vector<SolidView> views;
  for (SlicePlane plane : kAllSlicePlanes) {
    views.push_back(
        {plane,
         ReadImage(folder / ("Exemplar_20_" + std::string(ToString(plane)) + ".jpg")).image});
  }
  SpectralSolidOptions options;
  options.size = 32;
  options.iterations = 3;
  const SpectralSolidResult result = SynthesizeSpectralSolid(views, options);
  PrintReport(result.iterations);
  EXPECT_EQ(result.model.crop_size, 32);
  EXPECT_EQ(result.volume.channel_names(), (std::vector<std::string>{"R", "G", "B"}));
  for (const PlaneFit& fit : result.iterations.back().fits) {
    SCOPED_TRACE(std::string(ToString(fit.plane)));
    EXPECT_GT(fit.inside_bounds_average, 0.8);
    EXPECT_LT(fit.histogram_l1_mean, 0.25);
  }
  // Colour stays in the views' range.
  for (float v : result.volume.values()) {
    EXPECT_GE(v, 0.0f);
    EXPECT_LE(v, 1.0f);
  }
}

TEST(SpectralSolidTest, SameSeedSameBytesWithOneAndTwoThreads) {
  SpectralSolidOptions options;
  options.size = 16;
  options.iterations = 2;
  Image one, two;
  {
    tbb::global_control limit(tbb::global_control::max_allowed_parallelism, 1);
    one = SynthesizeSpectralSolid(StreakViews(), options).volume;
  }
  {
    tbb::global_control limit(tbb::global_control::max_allowed_parallelism, 2);
    two = SynthesizeSpectralSolid(StreakViews(), options).volume;
  }
  ASSERT_TRUE(one.SameShape(two));
  EXPECT_EQ(std::memcmp(one.values().data(), two.values().data(), one.values().size_bytes()), 0);
  options.seed = 2;
  const Image other = SynthesizeSpectralSolid(StreakViews(), options).volume;
  EXPECT_NE(std::memcmp(one.values().data(), other.values().data(), one.values().size_bytes()), 0);
}

TEST(SpectralSolidTest, RejectsBadViews) {
  SpectralSolidOptions options;
  options.size = 16;
  EXPECT_THROW(SynthesizeSpectralSolid({}, options), Error);
  EXPECT_THROW(SynthesizeSpectralSolid({{SlicePlane::kXY, StreakView(32, 1, 1, 1)},
                                        {SlicePlane::kXY, StreakView(32, 1, 1, 2)}},
                                       options),
               Error);
  EXPECT_THROW(SynthesizeSpectralSolid({{SlicePlane::kXY, StreakView(32, 1, 1, 1)},
                                        {SlicePlane::kXZ, Image(32, 32, 1)}},
                                       options),
               Error);
  EXPECT_THROW(SynthesizeSpectralSolid({{SlicePlane::kXY, StreakView(12, 1, 1, 1)}}, options),
               Error);
}

TEST(SpectralSolidTest, ViewTransforms) {
  Image image(3, 2, 1);
  for (int y = 0; y < 2; ++y) {
    for (int x = 0; x < 3; ++x) image.at(x, y, 0) = static_cast<float>(10 * y + x);
  }
  const Image transposed = ApplyViewTransform(image, ViewTransform::kTranspose);
  EXPECT_EQ(transposed.width(), 2);
  EXPECT_EQ(transposed.at(1, 2, 0), 12.0f);
  const Image rotated = ApplyViewTransform(image, ViewTransform::kRotate90);
  EXPECT_EQ(rotated.at(1, 0, 0), 0.0f);  // top-left goes to the top-right
  EXPECT_EQ(ApplyViewTransform(image, ViewTransform::kRotate180).at(0, 0, 0), 12.0f);
  const Image back = ApplyViewTransform(ApplyViewTransform(image, ViewTransform::kRotate90),
                                        ViewTransform::kRotate270);
  for (int y = 0; y < 2; ++y) {
    for (int x = 0; x < 3; ++x) EXPECT_EQ(back.at(x, y, 0), image.at(x, y, 0));
  }
  EXPECT_FALSE(ParseViewTransform("sideways"));
}

}  // namespace
}  // namespace photomat
