#pragma once

#include <cstdint>
#include <random>

namespace photomat {

// A seeded random source whose sequences are the same on every platform and standard library:
// std::mt19937_64 is fully specified, but std::*_distribution are not, so the transforms are ours.
// Every random choice in photomat takes one of these (or a seed), so any run can be reproduced.
class Random {
 public:
  explicit Random(std::uint64_t seed) : engine_(seed) {}

  // Uniform in [0, 1), 53 random bits.
  double Uniform() { return static_cast<double>(engine_() >> 11) * 0x1.0p-53; }
  double Uniform(double low, double high) { return low + (high - low) * Uniform(); }
  // Uniform integer in [0, n), n > 0 (Lemire's unbiased multiply-shift would be overkill here: the
  // bias of a 64-bit modulo for n < 2^32 is below 2^-32).
  std::uint64_t Index(std::uint64_t n) { return engine_() % n; }
  // Standard normal by Box-Muller.
  double Normal();

 private:
  std::mt19937_64 engine_;
  bool has_spare_ = false;
  double spare_ = 0.0;
};

class Image;

// Adds sigma * Normal() to every value of `image`, drawn pixel by pixel in raster order with the
// channels of a pixel innermost (the order of a sensor's interleaved samples, so a seed gives the
// same noise whatever the image's storage).
void AddGaussianNoise(Image& image, double sigma, Random& random);

}  // namespace photomat
