#include "core/fft.h"

#include <gtest/gtest.h>

#include <cmath>
#include <complex>
#include <numbers>
#include <thread>
#include <vector>

#include "core/error.h"
#include "core/random.h"

namespace photomat {
namespace {

template <typename Real>
std::vector<Real> RandomValues(std::size_t count, std::uint64_t seed) {
  Random random(seed);
  std::vector<Real> values(count);
  for (Real& v : values) v = static_cast<Real>(random.Uniform(-1.0, 1.0));
  return values;
}

// The half spectrum of a width x height array by the definition of the DFT.
std::vector<std::complex<double>> DirectSpectrum(const std::vector<double>& values, int width,
                                                 int height) {
  const int half = width / 2 + 1;
  std::vector<std::complex<double>> spectrum(static_cast<std::size_t>(height) * half);
  for (int v = 0; v < height; ++v) {
    for (int u = 0; u < half; ++u) {
      std::complex<double> sum = 0.0;
      for (int y = 0; y < height; ++y) {
        for (int x = 0; x < width; ++x) {
          const double angle =
              -2.0 * std::numbers::pi *
              (static_cast<double>(u) * x / width + static_cast<double>(v) * y / height);
          sum += values[static_cast<std::size_t>(y) * width + x] * std::polar(1.0, angle);
        }
      }
      spectrum[static_cast<std::size_t>(v) * half + u] = sum;
    }
  }
  return spectrum;
}

TEST(FftTest, DoubleForwardMatchesTheDefinitionAndInverseRoundTrips) {
  const int width = 12, height = 9;
  const std::vector<double> values = RandomValues<double>(width * height, 1);
  const RealFft2d<double> fft(width, height);
  std::vector<std::complex<double>> spectrum(fft.spectrum_size());
  fft.Forward(values, spectrum);
  const auto expected = DirectSpectrum(values, width, height);
  for (std::size_t k = 0; k < spectrum.size(); ++k) {
    // measured ~1e-15; bound 1e-12 (the direct sum itself rounds at ~100 terms * 1e-16).
    EXPECT_NEAR(std::abs(spectrum[k] - expected[k]), 0.0, 1e-12) << k;
  }
  std::vector<double> back(values.size());
  fft.Inverse(spectrum, back);
  for (std::size_t i = 0; i < values.size(); ++i) {
    EXPECT_NEAR(back[i] / (width * height), values[i], 1e-14) << i;
  }
}

TEST(FftTest, FloatAndDoubleAgree) {
  const int width = 16, height = 8;
  const std::vector<float> values = RandomValues<float>(width * height, 2);
  const RealFft2d<float> fft(width, height);
  std::vector<std::complex<float>> spectrum(fft.spectrum_size());
  fft.Forward(values, spectrum);
  const auto expected =
      DirectSpectrum(std::vector<double>(values.begin(), values.end()), width, height);
  for (std::size_t k = 0; k < spectrum.size(); ++k) {
    // measured ~1e-6 (float rounding of 128 terms); bound 1e-4.
    EXPECT_NEAR(std::abs(std::complex<double>(spectrum[k]) - expected[k]), 0.0, 1e-4) << k;
  }
}

TEST(FftTest, RowLimitedTransformsEqualTheFullOnes) {
  // A template zero below row 5, and a result read above row 7: the split row/column passes
  // give the full transforms' values where they are defined.
  const int width = 20, height = 15;
  std::vector<double> values = RandomValues<double>(width * height, 3);
  std::fill(values.begin() + 5 * width, values.end(), 0.0);
  const RealFft2d<double> full(width, height);
  const RealFft2d<double> limited(width, height, {5, 7});
  std::vector<std::complex<double>> a(full.spectrum_size()), b(full.spectrum_size());
  full.Forward(values, a);
  limited.Forward(values, b);
  for (std::size_t k = 0; k < a.size(); ++k) EXPECT_NEAR(std::abs(a[k] - b[k]), 0.0, 1e-12) << k;
  std::vector<double> from_full(values.size()), from_limited(values.size(), -7.0);
  full.Inverse(a, from_full);
  limited.Inverse(b, from_limited);
  for (int y = 0; y < height; ++y) {
    for (int x = 0; x < width; ++x) {
      const std::size_t i = static_cast<std::size_t>(y) * width + x;
      if (y < 7) {
        EXPECT_NEAR(from_limited[i], from_full[i], 1e-11) << x << ", " << y;
      } else {
        EXPECT_EQ(from_limited[i], -7.0) << "rows past the limit are left as they are";
      }
    }
  }
}

TEST(FftTest, AlignmentDoesNotChangeTheBits) {
  // The same plan runs whatever the arrays' alignment (unaligned ones are copied), so an input at
  // an odd offset gives exactly the bits of an aligned one.
  const int n = 32;
  const std::vector<float> values = RandomValues<float>(n * n, 4);
  std::vector<float> shifted(values.size() + 1);
  std::copy(values.begin(), values.end(), shifted.begin() + 1);
  FftArray<float> aligned(values.size());
  std::copy(values.begin(), values.end(), aligned.data());
  const RealFft2d<float> fft(n, n);
  FftArray<std::complex<float>> a(fft.spectrum_size());
  std::vector<std::complex<float>> b(fft.spectrum_size() + 1);
  fft.Forward(aligned, a);
  fft.Forward(std::span<const float>(shifted).subspan(1), std::span(b).subspan(1));
  for (std::size_t k = 0; k < fft.spectrum_size(); ++k) ASSERT_EQ(a[k], b[k + 1]) << k;
}

TEST(FftTest, PlansCanBeMadeOnManyThreadsAtOnce) {
  // The planner lock: transforms made and run concurrently give the single-threaded bits.
  const int n = 24;
  const std::vector<double> values = RandomValues<double>(n * n, 5);
  const RealFft2d<double> reference(n, n);
  std::vector<std::complex<double>> expected(reference.spectrum_size());
  reference.Forward(values, expected);
  std::vector<std::thread> threads;
  std::vector<int> mismatches(8, 0);
  for (int t = 0; t < 8; ++t) {
    threads.emplace_back([&, t] {
      for (int round = 0; round < 20; ++round) {
        const RealFft2d<double> fft(n, n, {round % 2 ? 10 : 0, 0});
        std::vector<std::complex<double>> spectrum(fft.spectrum_size());
        std::vector<double> input = values;
        if (round % 2) std::fill(input.begin() + 10 * n, input.end(), 0.0);
        fft.Forward(input, spectrum);
        if (round % 2 == 0 && spectrum != expected) ++mismatches[t];
      }
    });
  }
  for (std::thread& thread : threads) thread.join();
  for (int m : mismatches) EXPECT_EQ(m, 0);
}

TEST(FftTest, ThreeDimensionalForwardMatchesTwoPasses) {
  // A volume constant along z has all its energy at frequency z = 0, equal to depth times the
  // 2-D spectrum of one slice.
  const int x = 6, y = 5, z = 4;
  const std::vector<float> slice = RandomValues<float>(x * y, 6);
  std::vector<float> volume;
  for (int k = 0; k < z; ++k) volume.insert(volume.end(), slice.begin(), slice.end());
  const RealFft3d<float> fft3(x, y, z);
  std::vector<std::complex<float>> spectrum(fft3.spectrum_size());
  fft3.Forward(volume, spectrum);
  const RealFft2d<float> fft2(x, y);
  std::vector<std::complex<float>> planar(fft2.spectrum_size());
  fft2.Forward(slice, planar);
  for (std::size_t k = 0; k < planar.size(); ++k) {
    EXPECT_NEAR(std::abs(spectrum[k] - 4.0f * planar[k]), 0.0, 1e-4) << k;
    for (int fz = 1; fz < z; ++fz) {
      EXPECT_NEAR(std::abs(spectrum[fz * planar.size() + k]), 0.0, 1e-4) << k << " " << fz;
    }
  }
}

TEST(FftTest, BadSizesAreErrors) {
  EXPECT_THROW(RealFft2d<float>(0, 4), Error);
  EXPECT_THROW(RealFft2d<double>(4, 4, {5, 0}), Error);
  EXPECT_THROW(RealFft3d<float>(2, 0, 2), Error);
  const RealFft2d<float> fft(4, 4);
  std::vector<float> small(15);
  std::vector<std::complex<float>> spectrum(fft.spectrum_size());
  EXPECT_THROW(fft.Forward(small, spectrum), Error);
}

}  // namespace
}  // namespace photomat
