#include "core/fft.h"

#include <fftw3.h>
#include <fmt/format.h>

#include <mutex>

#include "core/error.h"

namespace photomat {
namespace {

// FFTW's planner is process-wide state that is not thread-safe; this is the one lock around it.
std::mutex& PlannerMutex() {
  static std::mutex mutex;
  return mutex;
}

// FFTW_UNALIGNED: callers pass std::vector storage, whose alignment may differ from the arrays
// the plan was made with.
constexpr unsigned kPlanFlags = FFTW_ESTIMATE | FFTW_UNALIGNED;

template <typename T>
T* Allocate(std::size_t count) {
  T* data = static_cast<T*>(fftwf_malloc(sizeof(T) * count));
  if (!data) throw Error(fmt::format("cannot allocate {} bytes for an FFT", sizeof(T) * count));
  return data;
}

void CheckSpan(std::size_t actual, std::size_t expected, const char* what) {
  if (actual != expected) {
    throw Error(fmt::format("FFT {} holds {} values, expected {}", what, actual, expected));
  }
}

fftwf_complex* AsFftw(std::complex<float>* data) { return reinterpret_cast<fftwf_complex*>(data); }

}  // namespace

RealFft2d::RealFft2d(int width, int height) : width_(width), height_(height) {
  if (width <= 0 || height <= 0) throw Error(fmt::format("invalid FFT size {}x{}", width, height));
  const std::size_t count = static_cast<std::size_t>(width) * static_cast<std::size_t>(height);
  float* real = Allocate<float>(count);
  fftwf_complex* complex = Allocate<fftwf_complex>(spectrum_size());
  {
    std::lock_guard lock(PlannerMutex());
    forward_ = fftwf_plan_dft_r2c_2d(height, width, real, complex, kPlanFlags);
    inverse_ = fftwf_plan_dft_c2r_2d(height, width, complex, real, kPlanFlags);
  }
  fftwf_free(real);
  fftwf_free(complex);
  if (!forward_ || !inverse_) throw Error(fmt::format("FFTW cannot plan {}x{}", width, height));
}

RealFft2d::~RealFft2d() {
  std::lock_guard lock(PlannerMutex());
  if (forward_) fftwf_destroy_plan(static_cast<fftwf_plan>(forward_));
  if (inverse_) fftwf_destroy_plan(static_cast<fftwf_plan>(inverse_));
}

void RealFft2d::Forward(std::span<const float> image,
                        std::span<std::complex<float>> spectrum) const {
  CheckSpan(image.size(), static_cast<std::size_t>(width_) * height_, "image");
  CheckSpan(spectrum.size(), spectrum_size(), "spectrum");
  // r2c does not write its input; FFTW's signature is not const-correct.
  fftwf_execute_dft_r2c(static_cast<fftwf_plan>(forward_), const_cast<float*>(image.data()),
                        AsFftw(spectrum.data()));
}

void RealFft2d::Inverse(std::span<std::complex<float>> spectrum, std::span<float> image) const {
  CheckSpan(image.size(), static_cast<std::size_t>(width_) * height_, "image");
  CheckSpan(spectrum.size(), spectrum_size(), "spectrum");
  fftwf_execute_dft_c2r(static_cast<fftwf_plan>(inverse_), AsFftw(spectrum.data()), image.data());
}

RealFft3d::RealFft3d(int size_x, int size_y, int size_z)
    : size_x_(size_x), size_y_(size_y), size_z_(size_z) {
  if (size_x <= 0 || size_y <= 0 || size_z <= 0) {
    throw Error(fmt::format("invalid FFT size {}x{}x{}", size_x, size_y, size_z));
  }
  const std::size_t count = static_cast<std::size_t>(size_x) * size_y * size_z;
  float* real = Allocate<float>(count);
  fftwf_complex* complex = Allocate<fftwf_complex>(spectrum_size());
  {
    std::lock_guard lock(PlannerMutex());
    forward_ = fftwf_plan_dft_r2c_3d(size_z, size_y, size_x, real, complex, kPlanFlags);
  }
  fftwf_free(real);
  fftwf_free(complex);
  if (!forward_) {
    throw Error(fmt::format("FFTW cannot plan {}x{}x{}", size_x, size_y, size_z));
  }
}

RealFft3d::~RealFft3d() {
  std::lock_guard lock(PlannerMutex());
  if (forward_) fftwf_destroy_plan(static_cast<fftwf_plan>(forward_));
}

void RealFft3d::Forward(std::span<const float> volume,
                        std::span<std::complex<float>> spectrum) const {
  CheckSpan(volume.size(), static_cast<std::size_t>(size_x_) * size_y_ * size_z_, "volume");
  CheckSpan(spectrum.size(), spectrum_size(), "spectrum");
  fftwf_execute_dft_r2c(static_cast<fftwf_plan>(forward_), const_cast<float*>(volume.data()),
                        AsFftw(spectrum.data()));
}

}  // namespace photomat
