#pragma once

#include <Eigen/Core>
#include <array>
#include <cstdint>
#include <optional>
#include <span>
#include <string>
#include <string_view>
#include <vector>

#include "core/fft.h"
#include "core/image.h"
#include "core/progress.h"
#include "synthesize/volume/volume.h"

namespace photomat {

// Anisotropic solid texture synthesis from orthogonal 2D views (Dischler, Ghazanfarpour and
// Freydier, Eurographics 1998; ../shared/specs/anisotropic-solid-spectral.md). Every slice of the
// block in a constrained orientation is coerced toward the spectrum (amplitudes only, phases kept)
// and the histogram of that orientation's view, slice after slice, until the block settles.
//
// Values are processed in a decorrelated colour basis (PCA of the pooled pixels of all views, one
// basis for all orientations so that they agree), each channel normalised to [-1, 1] over all
// views. Any number of channels works: a map stack's terms can be views as well as RGB photos.

// How a view image is turned to match the slice axes of its plane (see SlicePlane).
enum class ViewTransform { kNone, kTranspose, kRotate90, kRotate180, kRotate270, kFlipX, kFlipY };
std::optional<ViewTransform> ParseViewTransform(std::string_view text);  // none, transpose, ...
Image ApplyViewTransform(const Image& image, ViewTransform transform);

struct SolidView {
  SlicePlane plane = SlicePlane::kXY;
  Image image;  // already in the slice axes of `plane`
};

struct SpectralSolidOptions {
  int size = 128;  // N: the block is N^3
  int crops = 12;  // q sub-models per view (at least enough to cover it)
  // Side of the square sub-models. 0: N when the view's smaller side is at least 2N (the paper's
  // case), otherwise half the smaller side, and the statistics are resampled to N x N frequencies
  // (IMPLEMENTER CHOICE: the solid exemplars here are no larger than the block, and N x N crops
  // of an N x N view would all be the same, leaving no [min, max] range).
  int crop_size = 0;
  int regions = 32;         // z: log-spaced energy regions
  int clamp_halvings = 50;  // at most this many (a + mean) / 2 steps per frequency
  int iterations = 4;       // T
  // Orientations in the order each iteration processes them (those without a view are skipped).
  std::vector<SlicePlane> order = {SlicePlane::kXY, SlicePlane::kXZ, SlicePlane::kYZ};
  // true: the paper's sequential update (each slice written back at once). false: the authors'
  // earlier parallel update, every orientation from the same old block, results averaged.
  bool sequential = true;
  // Measure the fit of every constrained orientation after each iteration (one extra FFT per
  // slice); otherwise only after the last.
  bool measure_every_iteration = false;
  std::uint64_t seed = 1;
};

// The statistics of one decorrelated channel of one view (paper section 4.1), on the half spectrum
// (size rows of size / 2 + 1 frequencies) of an N x N slice with the unitary normalisation
// (amplitudes divided by N). The mean value (frequency 0) is not a spectral property of a
// stationary texture and is left out of every constraint: the histogram sets it.
struct ChannelSpectrum {
  int size = 0;
  std::vector<float> mean;              // F_avg
  std::vector<float> low;               // F-
  std::vector<float> high;              // F+
  std::vector<int> region;              // energy region of each frequency, -1 for the mean
  std::vector<double> region_energy;    // E_z: sum of F_avg over the full spectrum of each region
  std::array<double, 256> histogram{};  // of the whole view, bins of 1/128 on [-1, 1], sum 1

  int spectrum_width() const { return size / 2 + 1; }
  // 2 for frequencies that stand for a conjugate pair in the half spectrum, 1 for the others.
  double Weight(int fx) const { return (fx == 0 || 2 * fx == size) ? 1.0 : 2.0; }
};

// RGB (or any channels) to decorrelated channels normalised to [-1, 1], and back.
struct ColourBasis {
  Eigen::VectorXf mean;  // per input channel
  Eigen::MatrixXf axes;  // columns: principal axes, largest variance first
  Eigen::VectorXf low;   // per decorrelated channel, over all views
  Eigen::VectorXf high;
  // Per input channel, over all views. Channels synthesised independently can combine into values
  // no view holds (the extremes of two decorrelated channels at one voxel); FromNormalised clamps
  // to this range (IMPLEMENTER CHOICE).
  Eigen::VectorXf input_low;
  Eigen::VectorXf input_high;

  int channels() const { return static_cast<int>(mean.size()); }
  // Every pixel (or voxel) of `image` in the decorrelated channels, and back: a matrix product of
  // the planes (pixels x channels).
  Image ToNormalised(const Image& image) const;
  Image FromNormalised(const Image& normalised) const;
};

struct SpectralModel {
  int size = 0;
  int crop_size = 0;
  ColourBasis basis;
  std::vector<std::string> channel_names;
  // Per orientation (indexed by SlicePlane), per decorrelated channel; empty when no view.
  std::array<std::vector<ChannelSpectrum>, 3> planes;

  bool Constrains(SlicePlane plane) const { return !planes[static_cast<int>(plane)].empty(); }
};

// Throws Error for no views, two views of one plane, differing channel counts or views too small.
SpectralModel AnalyseViews(const std::vector<SolidView>& views,
                           const SpectralSolidOptions& options);

// The statistics of one channel (values in [-1, 1]) of one view.
ChannelSpectrum AnalyseChannel(const Image& view, int channel, const SpectralSolidOptions& options,
                               int crop_size, std::uint64_t seed);

// --- The slice process (paper section 4), exposed for tests. ---

// 256-bin histogram on [-1, 1] (bin k = [-1 + k/128, -1 + (k+1)/128[; 1 goes to the last bin),
// normalised to sum 1.
std::array<double, 256> Histogram256(std::span<const float> values);
double HistogramL1(const std::array<double, 256>& a, const std::array<double, 256>& b);
// The same after merging every `merge` neighbouring bins.
double CoarseHistogramL1(const std::array<double, 256>& a, const std::array<double, 256>& b,
                         int merge);

// Every amplitude outside [F-, F+] moves halfway to F_avg until inside, at most `halvings` times.
void ClampAmplitudes(std::span<float> amplitude, const ChannelSpectrum& statistics, int halvings);
// Scales the amplitudes of each region so that its energy equals the view's.
void EqualiseRegionEnergies(std::span<float> amplitude, const ChannelSpectrum& statistics);
// Spectral coercion of an N x N slice: amplitudes clamped and equalised, phases kept, inverse
// transform, then the range stretched back to [-1, 1].
void MatchSpectrum(std::span<float> slice, const ChannelSpectrum& statistics,
                   const RealFft2d<float>& fft, int halvings);
// Bin-level histogram specification (paper Fig. 3): the pixels of a source bin all move to the
// mass-weighted mean of the target bins its cumulative interval covers, never split.
void MatchHistogram(std::span<float> slice, const std::array<double, 256>& target);

// How well the slices of one orientation match its view, averaged over channels.
struct PlaneFit {
  SlicePlane plane = SlicePlane::kXY;
  // L1 distance of slice histograms to the view's, mean and worst over slices. Measured on 32 bins
  // (8 of the model's 256 merged): N^2 pixels spread over 256 bins too thinly for the distance to
  // say anything but the sample size at small N.
  double histogram_l1_mean = 0;
  double histogram_l1_max = 0;
  double inside_bounds = 0;             // share of (slice, frequency) amplitudes in [F-, F+]
  double inside_bounds_average = 0;     // share of frequencies whose slice-mean amplitude is
  double log_spectral_distance_db = 0;  // slice-mean amplitude vs F_avg, RMS of 20 log10 ratio
};

struct IterationReport {
  int iteration = 0;
  double relative_change = 0;  // |B_t - B_t-1| / |B_t|
  std::vector<PlaneFit> fits;  // constrained orientations (empty unless measured)
};

struct SpectralSolidResult {
  Image volume;
  SpectralModel model;
  std::vector<IterationReport> iterations;
};

SpectralSolidResult SynthesizeSpectralSolid(const std::vector<SolidView>& views,
                                            const SpectralSolidOptions& options,
                                            Progress* progress = nullptr);

// The fit of every constrained orientation of `volume` (in the model's colour space).
std::vector<PlaneFit> MeasureSpectralFit(const Image& volume, const SpectralModel& model);

}  // namespace photomat
