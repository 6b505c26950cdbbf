#include "core/fft.h"

#include <fftw3.h>
#include <fmt/format.h>

#include <algorithm>
#include <mutex>

#include "core/error.h"

namespace photomat {
namespace {

// FFTW's planner is process-wide state that is not thread-safe; this is the one lock around it.
std::mutex& PlannerMutex() {
  static std::mutex mutex;
  return mutex;
}

// The FFTW interface of each precision.
template <typename Real>
struct Fftw;

template <>
struct Fftw<float> {
  using Plan = fftwf_plan;
  using Complex = fftwf_complex;
  static void* Malloc(std::size_t bytes) { return fftwf_malloc(bytes); }
  static void Free(void* p) { fftwf_free(p); }
  static bool Aligned(const void* p) {
    return fftwf_alignment_of(static_cast<float*>(const_cast<void*>(p))) == 0;
  }
  static Plan R2c2d(int rows, int columns, float* in, Complex* out, unsigned flags) {
    return fftwf_plan_dft_r2c_2d(rows, columns, in, out, flags);
  }
  static Plan C2r2d(int rows, int columns, Complex* in, float* out, unsigned flags) {
    return fftwf_plan_dft_c2r_2d(rows, columns, in, out, flags);
  }
  static Plan R2c3d(int n0, int n1, int n2, float* in, Complex* out, unsigned flags) {
    return fftwf_plan_dft_r2c_3d(n0, n1, n2, in, out, flags);
  }
  static Plan RowsR2c(int n, int howmany, float* in, int in_distance, Complex* out,
                      int out_distance, unsigned flags) {
    return fftwf_plan_many_dft_r2c(1, &n, howmany, in, nullptr, 1, in_distance, out, nullptr, 1,
                                   out_distance, flags);
  }
  static Plan RowsC2r(int n, int howmany, Complex* in, int in_distance, float* out,
                      int out_distance, unsigned flags) {
    return fftwf_plan_many_dft_c2r(1, &n, howmany, in, nullptr, 1, in_distance, out, nullptr, 1,
                                   out_distance, flags);
  }
  static Plan Columns(int n, int howmany, Complex* data, int stride, int sign, unsigned flags) {
    return fftwf_plan_many_dft(1, &n, howmany, data, nullptr, stride, 1, data, nullptr, stride, 1,
                               sign, flags);
  }
  static void Execute(Plan plan, float* in, Complex* out) { fftwf_execute_dft_r2c(plan, in, out); }
  static void Execute(Plan plan, Complex* in, float* out) { fftwf_execute_dft_c2r(plan, in, out); }
  static void Execute(Plan plan, Complex* in, Complex* out) { fftwf_execute_dft(plan, in, out); }
  static void Destroy(Plan plan) { fftwf_destroy_plan(plan); }
};

template <>
struct Fftw<double> {
  using Plan = fftw_plan;
  using Complex = fftw_complex;
  static void* Malloc(std::size_t bytes) { return fftw_malloc(bytes); }
  static void Free(void* p) { fftw_free(p); }
  static bool Aligned(const void* p) {
    return fftw_alignment_of(static_cast<double*>(const_cast<void*>(p))) == 0;
  }
  static Plan R2c2d(int rows, int columns, double* in, Complex* out, unsigned flags) {
    return fftw_plan_dft_r2c_2d(rows, columns, in, out, flags);
  }
  static Plan C2r2d(int rows, int columns, Complex* in, double* out, unsigned flags) {
    return fftw_plan_dft_c2r_2d(rows, columns, in, out, flags);
  }
  static Plan R2c3d(int n0, int n1, int n2, double* in, Complex* out, unsigned flags) {
    return fftw_plan_dft_r2c_3d(n0, n1, n2, in, out, flags);
  }
  static Plan RowsR2c(int n, int howmany, double* in, int in_distance, Complex* out,
                      int out_distance, unsigned flags) {
    return fftw_plan_many_dft_r2c(1, &n, howmany, in, nullptr, 1, in_distance, out, nullptr, 1,
                                  out_distance, flags);
  }
  static Plan RowsC2r(int n, int howmany, Complex* in, int in_distance, double* out,
                      int out_distance, unsigned flags) {
    return fftw_plan_many_dft_c2r(1, &n, howmany, in, nullptr, 1, in_distance, out, nullptr, 1,
                                  out_distance, flags);
  }
  static Plan Columns(int n, int howmany, Complex* data, int stride, int sign, unsigned flags) {
    return fftw_plan_many_dft(1, &n, howmany, data, nullptr, stride, 1, data, nullptr, stride, 1,
                              sign, flags);
  }
  static void Execute(Plan plan, double* in, Complex* out) { fftw_execute_dft_r2c(plan, in, out); }
  static void Execute(Plan plan, Complex* in, double* out) { fftw_execute_dft_c2r(plan, in, out); }
  static void Execute(Plan plan, Complex* in, Complex* out) { fftw_execute_dft(plan, in, out); }
  static void Destroy(Plan plan) { fftw_destroy_plan(plan); }
};

// The real type of a real or complex value.
template <typename T>
struct RealOf {
  using type = T;
};
template <typename Real>
struct RealOf<std::complex<Real>> {
  using type = Real;
};
template <typename T>
using RealOfT = typename RealOf<std::remove_const_t<T>>::type;

// No trial runs (FFTW_ESTIMATE): deterministic plans, inputs untouched while planning.
constexpr unsigned kPlanFlags = FFTW_ESTIMATE;

void CheckSpan(std::size_t actual, std::size_t expected, const char* what) {
  if (actual != expected) {
    throw Error(fmt::format("FFT {} holds {} values, expected {}", what, actual, expected));
  }
}

template <typename Real>
typename Fftw<Real>::Complex* AsFftw(std::complex<Real>* data) {
  return reinterpret_cast<typename Fftw<Real>::Complex*>(data);
}

// `values` itself when FFTW-aligned, otherwise a copy in `copy` (made when `fill`).
template <typename T>
T* AlignedOrCopy(std::span<T> values, FftArray<std::remove_const_t<T>>& copy, bool fill) {
  if (Fftw<RealOfT<T>>::Aligned(values.data())) return values.data();
  copy = FftArray<std::remove_const_t<T>>(values.size());
  if (fill) std::copy(values.begin(), values.end(), copy.data());
  return copy.data();
}

// Destroys the plans made under the planner lock.
template <typename Plan>
void DestroyPlans(std::initializer_list<Plan> plans, void (*destroy)(Plan)) {
  const std::lock_guard lock(PlannerMutex());
  for (Plan plan : plans) {
    if (plan) destroy(plan);
  }
}

}  // namespace

template <typename T>
FftArray<T>::FftArray(std::size_t size) : size_(size) {
  void* memory = Fftw<RealOfT<T>>::Malloc(sizeof(T) * std::max<std::size_t>(size, 1));
  if (!memory) throw Error(fmt::format("cannot allocate {} bytes for an FFT", sizeof(T) * size));
  data_.reset(static_cast<T*>(memory));
  std::fill_n(data_.get(), size, T{});
}

template <typename T>
void FftArray<T>::Free::operator()(void* p) const {
  Fftw<RealOfT<T>>::Free(p);
}

template <typename Real>
struct RealFft2d<Real>::Plans {
  using Plan = typename Fftw<Real>::Plan;
  Plan forward = nullptr;          // 2-D, or the row pass of the rows that carry data
  Plan forward_columns = nullptr;  // with a row pass only: in place, every column
  Plan inverse = nullptr;          // 2-D, or the row pass of the rows wanted
  Plan inverse_columns = nullptr;  // with a row pass only: in place, every column
};

template <typename Real>
RealFft2d<Real>::RealFft2d(int width, int height, FftRows rows)
    : width_(width), height_(height), rows_(rows), plans_(std::make_unique<Plans>()) {
  if (width <= 0 || height <= 0 || rows.forward_input < 0 || rows.forward_input > height ||
      rows.inverse_output < 0 || rows.inverse_output > height) {
    throw Error(fmt::format("invalid FFT size {}x{} (rows {}, {})", width, height,
                            rows.forward_input, rows.inverse_output));
  }
  if (rows_.forward_input == 0) rows_.forward_input = height;
  if (rows_.inverse_output == 0) rows_.inverse_output = height;
  using F = Fftw<Real>;
  FftArray<Real> real(size());
  FftArray<Complex> complex(spectrum_size());
  typename F::Complex* spectrum = AsFftw(complex.data());
  const int half = spectrum_width();
  {
    const std::lock_guard lock(PlannerMutex());
    if (rows_.forward_input == height) {
      plans_->forward = F::R2c2d(height, width, real.data(), spectrum, kPlanFlags);
    } else {
      plans_->forward =
          F::RowsR2c(width, rows_.forward_input, real.data(), width, spectrum, half, kPlanFlags);
      plans_->forward_columns = F::Columns(height, half, spectrum, half, FFTW_FORWARD, kPlanFlags);
    }
    if (rows_.inverse_output == height) {
      plans_->inverse = F::C2r2d(height, width, spectrum, real.data(), kPlanFlags);
    } else {
      plans_->inverse_columns = F::Columns(height, half, spectrum, half, FFTW_BACKWARD, kPlanFlags);
      plans_->inverse =
          F::RowsC2r(width, rows_.inverse_output, spectrum, half, real.data(), width, kPlanFlags);
    }
  }
  const bool split_forward = rows_.forward_input != height;
  const bool split_inverse = rows_.inverse_output != height;
  if (!plans_->forward || !plans_->inverse || (split_forward && !plans_->forward_columns) ||
      (split_inverse && !plans_->inverse_columns)) {
    DestroyPlans(
        {plans_->forward, plans_->forward_columns, plans_->inverse, plans_->inverse_columns},
        &F::Destroy);
    throw Error(fmt::format("FFTW cannot plan {}x{}", width, height));
  }
}

template <typename Real>
RealFft2d<Real>::~RealFft2d() {
  DestroyPlans({plans_->forward, plans_->forward_columns, plans_->inverse, plans_->inverse_columns},
               &Fftw<Real>::Destroy);
}

template <typename Real>
void RealFft2d<Real>::Forward(std::span<const Real> image, std::span<Complex> spectrum) const {
  CheckSpan(image.size(), size(), "image");
  CheckSpan(spectrum.size(), spectrum_size(), "spectrum");
  FftArray<Real> image_copy;
  FftArray<Complex> spectrum_copy;
  // r2c does not write its input; FFTW's signature is not const-correct.
  Real* in = const_cast<Real*>(AlignedOrCopy(image, image_copy, true));
  Complex* out = AlignedOrCopy(spectrum, spectrum_copy, false);
  using F = Fftw<Real>;
  F::Execute(plans_->forward, in, AsFftw(out));
  if (plans_->forward_columns) {
    // Rows without data have all-zero spectra.
    const std::size_t filled = static_cast<std::size_t>(rows_.forward_input) * spectrum_width();
    std::fill(out + filled, out + spectrum_size(), Complex(0, 0));
    F::Execute(plans_->forward_columns, AsFftw(out), AsFftw(out));
  }
  if (out != spectrum.data()) std::copy_n(out, spectrum_size(), spectrum.data());
}

template <typename Real>
void RealFft2d<Real>::Inverse(std::span<Complex> spectrum, std::span<Real> image) const {
  CheckSpan(image.size(), size(), "image");
  CheckSpan(spectrum.size(), spectrum_size(), "spectrum");
  FftArray<Complex> spectrum_copy;
  FftArray<Real> image_copy;
  Complex* in = AlignedOrCopy(spectrum, spectrum_copy, true);
  Real* out = AlignedOrCopy(image, image_copy, false);
  using F = Fftw<Real>;
  if (plans_->inverse_columns) F::Execute(plans_->inverse_columns, AsFftw(in), AsFftw(in));
  F::Execute(plans_->inverse, AsFftw(in), out);
  if (out != image.data()) {
    std::copy_n(out, static_cast<std::size_t>(rows_.inverse_output) * width_, image.data());
  }
}

template <typename Real>
struct RealFft3d<Real>::Plans {
  typename Fftw<Real>::Plan forward = nullptr;
};

template <typename Real>
RealFft3d<Real>::RealFft3d(int size_x, int size_y, int size_z)
    : size_x_(size_x), size_y_(size_y), size_z_(size_z), plans_(std::make_unique<Plans>()) {
  if (size_x <= 0 || size_y <= 0 || size_z <= 0) {
    throw Error(fmt::format("invalid FFT size {}x{}x{}", size_x, size_y, size_z));
  }
  FftArray<Real> real(size());
  FftArray<Complex> complex(spectrum_size());
  {
    const std::lock_guard lock(PlannerMutex());
    plans_->forward =
        Fftw<Real>::R2c3d(size_z, size_y, size_x, real.data(), AsFftw(complex.data()), kPlanFlags);
  }
  if (!plans_->forward) {
    throw Error(fmt::format("FFTW cannot plan {}x{}x{}", size_x, size_y, size_z));
  }
}

template <typename Real>
RealFft3d<Real>::~RealFft3d() {
  DestroyPlans({plans_->forward}, &Fftw<Real>::Destroy);
}

template <typename Real>
void RealFft3d<Real>::Forward(std::span<const Real> volume, std::span<Complex> spectrum) const {
  CheckSpan(volume.size(), size(), "volume");
  CheckSpan(spectrum.size(), spectrum_size(), "spectrum");
  FftArray<Real> volume_copy;
  FftArray<Complex> spectrum_copy;
  Real* in = const_cast<Real*>(AlignedOrCopy(volume, volume_copy, true));
  Complex* out = AlignedOrCopy(spectrum, spectrum_copy, false);
  Fftw<Real>::Execute(plans_->forward, in, AsFftw(out));
  if (out != spectrum.data()) std::copy_n(out, spectrum_size(), spectrum.data());
}

template class FftArray<float>;
template class FftArray<double>;
template class FftArray<std::complex<float>>;
template class FftArray<std::complex<double>>;
template class RealFft2d<float>;
template class RealFft2d<double>;
template class RealFft3d<float>;
template class RealFft3d<double>;

}  // namespace photomat
