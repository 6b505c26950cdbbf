#pragma once

#include <cstddef>
#include <cstdint>
#include <optional>
#include <vector>

#include "core/image.h"

namespace photomat {

// How close a predicted image is to a captured one: the measures the held-out benchmarks report
// (bench/held_out_lights, bench/compact_form). Each is taken over the pixels of `mask`, with both
// images clamped to [0, peak] first: `peak` is the value shown as white (1 for images scaled to
// [0, 1], e.g. 8-bit codes / 255), so the images compared are what a display of them would show.
// Each throws Error for images of different sizes or channel counts, a mask of another size, an
// empty mask or a peak that is not positive.

// 10 log10(peak^2 / MSE) in dB over the mask and every channel, on the linear values; infinite
// for equal images.
double MaskedPsnr(const Image& predicted, const Image& truth, const Mask& mask, double peak);

// The structural similarity (Wang, Bovik, Sheikh and Simoncelli 2004) of the images' sRGB
// renderings: every value clamped, divided by `peak` and encoded with the sRGB curve; the SSIM
// map of each channel with the paper's 11 x 11 Gaussian window (sigma 1.5, OpenCV's GaussianBlur,
// borders mirrored as OpenCV's own SSIM in opencv_contrib's quality module does), K1 = 0.01,
// K2 = 0.03 and dynamic range 1; its mean over the mask, then over the channels. 1 for equal
// images. IMPLEMENTER CHOICE: pixels outside the mask are set to 0 in both images before the
// windows are taken, so the background, which no fit models, neither helps nor hurts; windows at
// the mask's border see the object's edge against the same black in both. The map is computed
// only where the mask's windows reach (its bounding box grown by the window's radius), which
// gives the whole map's values there.
double MaskedSsim(const Image& predicted, const Image& truth, const Mask& mask, double peak);

// MaskedSsim and, for one- or three-channel images, MaskedMeanDeltaE2000 in one pass over the
// mask's region: what an evaluation reports of each predicted image.
struct DisplayedComparison {
  double ssim = 0.0;
  std::optional<double> mean_delta_e2000;
};
DisplayedComparison CompareDisplayed(const Image& predicted, const Image& truth, const Mask& mask,
                                     double peak);

// The mean CIEDE2000 colour difference over the mask (CieDe2000, core/colour.h) between the
// images' renderings: every value clamped and divided by `peak`, read as linear Rec.709 / sRGB
// RGB, converted to CIELAB under D65 (CieLabOfLinearRec709). The sRGB rendering's transfer curve
// is undone by the conversion to XYZ, so the difference is that of the rendered colours
// (IMPLEMENTER CHOICE: without an 8-bit quantisation of the rendering, which would floor every
// difference at the code step). One-channel images are grey (R = G = B); images of another
// channel count than 1 or 3 throw Error.
double MaskedMeanDeltaE2000(const Image& predicted, const Image& truth, const Mask& mask,
                            double peak);

// MaskedSsim and MaskedMeanDeltaE2000 of two images given band by band in row order, as a
// streamed evaluation predicts them: the same values as of the whole images, bit for bit
// (MaskedSsim is this with one band), holding at most a band and 2 x 5 rows of each plane as
// doubles (the SSIM window reaches 5 rows above and below). Rows no band gives (bands the mask
// leaves empty) lie outside the mask.
class MaskedDisplayComparison {
 public:
  // Images of width x height and `channels`, shown with `peak` as white; without
  // `colour_difference` the SSIM alone (MeanDeltaE2000 gives none). Throws Error for an empty
  // size or a peak that is not positive.
  MaskedDisplayComparison(int width, int height, int channels, double peak,
                          bool colour_difference = true);
  // Rows [first_row, first_row + the band's height) of both images and of the mask. Throws Error
  // for bands of another width or channel count, or rows before those given already.
  void AddBand(int first_row, const Image& predicted, const Image& truth, const Mask& mask);
  // After the last band: the SSIM. Throws Error if the mask selected no pixel.
  double Ssim();
  // The mean colour difference; none for images of other than one or three channels.
  std::optional<double> MeanDeltaE2000() const;

 private:
  // Appends `rows` rows to the planes held: the bands' (or, for null pointers, outside the mask).
  void AppendRows(int rows, const Image* predicted, const Image* truth, const Mask* mask);
  // Adds the SSIM of the rows up to `end_row`, then drops the rows no later window reaches.
  void Finalise(int end_row);
  // The first row held: the window's radius above the first row not yet finalised (or row 0).
  int HeldFirstRow() const;

  int width_, height_, channels_;
  double peak_;
  bool colour_difference_;  // asked for, and the images have one or three channels
  int next_row_ = 0;        // rows given so far
  int finalised_ = 0;       // rows whose SSIM is summed
  // Rows [HeldFirstRow(), next_row_) of each channel as displayed (0 outside the mask), and the
  // mask.
  std::vector<std::vector<double>> predicted_, truth_;
  std::vector<std::uint8_t> selected_;
  std::vector<double> ssim_sums_;  // per channel, over the rows finalised
  double delta_e_sum_ = 0.0;
  std::size_t pixels_ = 0;
};

}  // namespace photomat
