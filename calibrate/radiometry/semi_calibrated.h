#pragma once

#include <Eigen/Core>
#include <filesystem>
#include <functional>
#include <string>
#include <vector>

#include "core/photometric_set.h"
#include "core/progress.h"

namespace photomat {

// Semi-calibrated photometric stereo: known light directions, unknown light intensities e(i, c),
// estimated jointly with the normals. For a Lambertian pixel p, I(p, i, c) = e(i, c) b(p, c).l(i),
// so with u = 1 / e the values diag(I_p) u lie in the span of the lights: the projector P_p onto
// what the pixel's lights cannot explain annihilates them. u is therefore the eigenvector of the
// smallest eigenvalue of M_c = sum_p diag(I_p,c) P_p diag(I_p,c), the linear solution of Cho et
// al. (semi-calibrated photometric stereo, TPAMI 2018), computed per channel.
//
// Shadows, highlights and clipped samples are not Lambertian: each observation (pixel p, image i)
// carries a weight w(p, i) >= 0, P_p is then the weighted projector W - W L^T (L W L^T)^-1 L W
// (weighted least squares of the pixel's corrected values by its lights), and iterations re-weigh
// the observations under the current intensities until no intensity changes by more than
// `tolerance`. The weights come from an ObservationWeigher (IMPLEMENTER CHOICE):
//   - the default, RankWindowWeights: each pixel's rank window (its darkest and brightest
//     observations, ranked by channel sum over the current intensities, are shadows and
//     highlights) times a Cauchy weight of the share of the window's values the lights cannot
//     explain (pixels that stay far from Lambertian count less);
//   - represent/robust_intensities.h passes the robust fit's shared outlier weights (robust
//     photometric stereo, README "Robust fitting"), which judge every observation against a
//     robust Lambertian model: on DiLiGenT cat they leave the least-squares normals 0.9 degrees
//     from the calibrated ones, against 2.5 with rank windows (README, "Calibration"). The CLI
//     uses them; calibrate cannot call the robust fit itself
//     (represent depends on calibrate), hence the hook.
// The scale of each channel is arbitrary (it trades against albedo): the intensities are
// normalised to a mean of 1 per channel, as a light_intensities.txt can be. With all lights
// within a cone around the camera axis, an intensity error that is a smooth function of the light
// direction (c + a.l) is only weakly observable; non-Lambertian shading shows up there first.

// The sampled pixels of a set, one row: image i of `samples` holds, at column k, the k-th sampled
// pixel of image i as captured (not divided by any intensities); `samples.intensities()` are the
// current estimate. An ObservationWeigher returns a samples x images matrix of weights >= 0
// (0 leaves the observation out).
using ObservationWeigher = std::function<Eigen::MatrixXf(const PhotometricSet& samples)>;

struct SemiCalibratedOptions {
  int max_iterations = 100;
  // Stops when no intensity changes by more than this fraction in an iteration (0.1 %: far below
  // what the intensities are known to; on DiLiGenT cat 1e-4 changes the normals by 0.015 degree
  // and takes twice the iterations).
  double tolerance = 1e-3;
  // Also stops when the largest change has not fallen to a new low for this many iterations
  // (the weights cycle; on DiLiGenT cat the robust weights settle at changes near 3e-4).
  int stall_iterations = 3;
  // Rank window of RankWindowWeights (as in the robust fit).
  double dark_fraction = 0.25;
  double bright_fraction = 0.1;
  // At most this many of the mask's pixels take part (every k-th, deterministic): the estimate
  // is a sum over pixels.
  int max_pixels = 5000;
  // Empty: RankWindowWeights with the fractions above.
  ObservationWeigher weigher;
  Progress* progress = nullptr;
};

struct SemiCalibratedResult {
  // One row per image, one value per channel (mean 1 per channel).
  std::vector<std::vector<float>> intensities;
  int iterations = 0;
  double last_change = 0.0;  // largest relative change in the last iteration
};

// The default weights: per sampled pixel, 1 inside its rank window (0 outside) times a Cauchy
// weight of the share of the window's corrected channel-sum values that its lights cannot explain
// (scale: twice the median share over the samples).
Eigen::MatrixXf RankWindowWeights(const PhotometricSet& samples, double dark_fraction,
                                  double bright_fraction);

// Estimates the intensities of `set`'s lights from its images as captured (not divided by any
// intensities). Throws Error naming the set's source for fewer than 4 images, coplanar lights, too
// few usable pixels, or weights of the wrong shape.
SemiCalibratedResult EstimateLightIntensities(const PhotometricSet& set,
                                              const SemiCalibratedOptions& options = {});

// The estimate uses the sampled pixels only: every k-th pixel of the mask, at most
// options.max_pixels (linear indices y * width + x, ascending). So a capture too large to hold is
// estimated from its samples gathered band by band (SemiCalibratedSamples), with the same result.
std::vector<std::size_t> SemiCalibratedPixels(const Mask& mask,
                                              const SemiCalibratedOptions& options);

// The sampled pixels of a capture read band by band, in any order of bands: each band's sampled
// pixels are copied into one-row images (the samples of ObservationWeigher).
class SemiCalibratedSamples {
 public:
  // `pixels` from SemiCalibratedPixels of the capture's mask; `width` the capture's.
  SemiCalibratedSamples(std::vector<std::size_t> pixels, int width);
  // Copies the sampled pixels of `band`, rows [first_row, first_row + band.height()) of the
  // capture, as captured (its intensities are ignored).
  void Add(const PhotometricSet& band, int first_row);
  // The samples gathered (the bands' lights, names and source); pixels of rows never added are 0.
  PhotometricSet samples() const;

 private:
  std::vector<std::size_t> pixels_;
  int width_ = 0;
  // One-row images, one per capture image; empty until the first band.
  std::vector<Image> strips_;
  std::vector<LightDirection> lights_;
  std::vector<std::string> names_;
  std::filesystem::path source_;
};

// EstimateLightIntensities of a set of which only the samples are held: `samples` as
// SemiCalibratedSamples gathers them (or the whole set's SemiCalibratedPixels, one row), the
// result the same as the whole set's, bit for bit.
SemiCalibratedResult EstimateLightIntensitiesFromSamples(PhotometricSet samples,
                                                         const SemiCalibratedOptions& options = {});

}  // namespace photomat
