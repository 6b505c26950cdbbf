#pragma once

#include <complex>
#include <span>

namespace photomat {

// Real-to-complex discrete Fourier transforms through FFTW (single precision), for the spectra of
// slices and volumes. Transforms are unnormalised, as FFTW's: Inverse(Forward(x)) = count * x.
//
// Plans are made with FFTW_ESTIMATE, which picks the algorithm without timing anything, so the
// same input gives the same bits on every run (FFTW_MEASURE may pick differently from run to run).
// Executing a plan is thread-safe; making one goes through FFTW's process-wide planner, which the
// constructors serialise. Objects are cheap to share across threads for Forward/Inverse.
class RealFft2d {
 public:
  // A width x height array, row-major (x fastest).
  RealFft2d(int width, int height);
  ~RealFft2d();
  RealFft2d(const RealFft2d&) = delete;
  RealFft2d& operator=(const RealFft2d&) = delete;

  int width() const { return width_; }
  int height() const { return height_; }
  // The half spectrum kept by a real transform: height rows of width / 2 + 1 frequencies.
  int spectrum_width() const { return width_ / 2 + 1; }
  std::size_t spectrum_size() const {
    return static_cast<std::size_t>(height_) * static_cast<std::size_t>(spectrum_width());
  }

  void Forward(std::span<const float> image, std::span<std::complex<float>> spectrum) const;
  // Overwrites `spectrum` (FFTW's multi-dimensional complex-to-real transform cannot keep it).
  void Inverse(std::span<std::complex<float>> spectrum, std::span<float> image) const;

 private:
  int width_;
  int height_;
  void* forward_ = nullptr;
  void* inverse_ = nullptr;
};

// The 3D counterpart, forward only (power spectra of volumes).
class RealFft3d {
 public:
  RealFft3d(int size_x, int size_y, int size_z);
  ~RealFft3d();
  RealFft3d(const RealFft3d&) = delete;
  RealFft3d& operator=(const RealFft3d&) = delete;

  int spectrum_x() const { return size_x_ / 2 + 1; }
  std::size_t spectrum_size() const {
    return static_cast<std::size_t>(size_z_) * static_cast<std::size_t>(size_y_) *
           static_cast<std::size_t>(spectrum_x());
  }
  // `volume` x fastest; the spectrum is z-major with x fastest over spectrum_x() frequencies.
  void Forward(std::span<const float> volume, std::span<std::complex<float>> spectrum) const;

 private:
  int size_x_;
  int size_y_;
  int size_z_;
  void* forward_ = nullptr;
};

}  // namespace photomat
