#pragma once

#include <complex>
#include <cstddef>
#include <memory>
#include <span>

namespace photomat {

// Real-to-complex discrete Fourier transforms through FFTW, in single (float) or double precision:
// the one FFT of photomat (spectra of slices and volumes, FFT correlation, Frankot-Chellappa
// integration, pattern spectra). Transforms are unnormalised, as FFTW's:
// Inverse(Forward(x)) = count * x.
//
// Plans are made with FFTW_ESTIMATE, which picks the algorithm without timing anything, so the
// same input gives the same bits on every run (FFTW_MEASURE may pick differently from run to
// run). Plans are made for arrays aligned as FFTW's own allocation (so that its SIMD kernels can
// run); arrays passed in that are not are copied through aligned ones (FftArray avoids the copy),
// so every call runs the same plan and gives the same bits wherever its arrays lie.
//
// Thread safety: executing a plan is thread-safe, so one transform object can serve many threads
// at once. Making and destroying plans goes through FFTW's planner, which is process-wide state
// that is not thread-safe: every plan photomat makes is made under one process-wide lock, inside
// this wrapper (no other code calls FFTW).

// An array aligned as FFTW allocates (fftw_malloc), zero-filled.
template <typename T>
class FftArray {
 public:
  FftArray() = default;
  explicit FftArray(std::size_t size);

  std::size_t size() const { return size_; }
  T* data() { return data_.get(); }
  const T* data() const { return data_.get(); }
  T& operator[](std::size_t i) { return data_[i]; }
  const T& operator[](std::size_t i) const { return data_[i]; }
  operator std::span<T>() { return {data_.get(), size_}; }  // NOLINT: implicit by design
  operator std::span<const T>() const { return {data_.get(), size_}; }  // NOLINT

 private:
  struct Free {
    void operator()(void* p) const;
  };
  std::unique_ptr<T[], Free> data_;
  std::size_t size_ = 0;
};

// The rows of a 2-D transform that carry data (IMPLEMENTER CHOICE: an FFT correlation's template
// is zero below its block, and only the candidates' rows of its result are read). A transform
// that knows this runs its row pass on those rows only (and its column pass on all columns), so
// the unused rows cost nothing; 0 means all rows.
struct FftRows {
  int forward_input = 0;   // Forward reads rows [0, forward_input); the rest count as zero
  int inverse_output = 0;  // Inverse writes rows [0, inverse_output); the rest are left as they are
};

template <typename Real>
class RealFft2d {
 public:
  using Complex = std::complex<Real>;

  // A width x height array, row-major (x fastest). Throws Error for sizes below 1 or rows outside
  // [0, height].
  RealFft2d(int width, int height, FftRows rows = {});
  ~RealFft2d();
  RealFft2d(const RealFft2d&) = delete;
  RealFft2d& operator=(const RealFft2d&) = delete;

  int width() const { return width_; }
  int height() const { return height_; }
  std::size_t size() const { return static_cast<std::size_t>(width_) * height_; }
  // The half spectrum kept by a real transform: height rows of width / 2 + 1 frequencies.
  int spectrum_width() const { return width_ / 2 + 1; }
  std::size_t spectrum_size() const {
    return static_cast<std::size_t>(height_) * static_cast<std::size_t>(spectrum_width());
  }

  void Forward(std::span<const Real> image, std::span<Complex> spectrum) const;
  // Overwrites `spectrum` (FFTW's multi-dimensional complex-to-real transform cannot keep it).
  void Inverse(std::span<Complex> spectrum, std::span<Real> image) const;

 private:
  struct Plans;
  int width_;
  int height_;
  FftRows rows_;
  std::unique_ptr<Plans> plans_;
};

// The 3D counterpart, forward only (power spectra of volumes).
template <typename Real>
class RealFft3d {
 public:
  using Complex = std::complex<Real>;

  RealFft3d(int size_x, int size_y, int size_z);
  ~RealFft3d();
  RealFft3d(const RealFft3d&) = delete;
  RealFft3d& operator=(const RealFft3d&) = delete;

  std::size_t size() const {
    return static_cast<std::size_t>(size_x_) * static_cast<std::size_t>(size_y_) *
           static_cast<std::size_t>(size_z_);
  }
  int spectrum_x() const { return size_x_ / 2 + 1; }
  std::size_t spectrum_size() const {
    return static_cast<std::size_t>(size_z_) * static_cast<std::size_t>(size_y_) *
           static_cast<std::size_t>(spectrum_x());
  }
  // `volume` x fastest; the spectrum is z-major with x fastest over spectrum_x() frequencies.
  void Forward(std::span<const Real> volume, std::span<Complex> spectrum) const;

 private:
  struct Plans;
  int size_x_;
  int size_y_;
  int size_z_;
  std::unique_ptr<Plans> plans_;
};

}  // namespace photomat
