#include "represent/evaluation/image_comparison.h"

#include <fmt/format.h>

#include <algorithm>
#include <opencv2/core.hpp>
#include <opencv2/imgproc.hpp>
#include <string_view>

#include "core/colour.h"
#include "core/error.h"
#include "represent/evaluation/evaluation.h"

namespace photomat {
namespace {

// The checks every comparison makes; returns the number of pixels in the mask.
std::size_t CheckComparable(std::string_view what, const Image& predicted, const Image& truth,
                            const Mask& mask, double peak) {
  if (predicted.width() != truth.width() || predicted.height() != truth.height() ||
      predicted.channels() != truth.channels()) {
    throw Error(fmt::format("{} of a {}x{}x{} image against a {}x{}x{} one", what,
                            predicted.width(), predicted.height(), predicted.channels(),
                            truth.width(), truth.height(), truth.channels()));
  }
  if (!mask.SameSize(truth)) throw Error(fmt::format("{}: the mask is not the images' size", what));
  if (!(peak > 0.0)) throw Error(fmt::format("{}: peak {} is not positive", what, peak));
  const std::size_t count = mask.CountSet();
  if (count == 0) throw Error(fmt::format("{}: the mask selects no pixel", what));
  return count;
}

double Displayed(float value, double peak) { return std::clamp(double{value}, 0.0, peak) / peak; }

constexpr int kSsimWindowRadius = 5;  // the 11 x 11 window

// The part of the images whose SSIM windows the mask's pixels see: the mask's bounding box grown
// by the window's radius, within the image. Outside it the SSIM map is neither needed nor read:
// every window of a mask pixel lies inside it, and where it is cut by the image's edge, the edge
// (and so its mirrored border) is the image's own, so the map over the mask is the same as the
// whole image's, at a fraction of the cost on a masked capture (evaluation's leave-one-out takes
// one per predicted image and method).
cv::Rect SsimRegion(const Mask& mask) {
  int left = mask.width(), right = -1, top = mask.height(), bottom = -1;
  for (int y = 0; y < mask.height(); ++y) {
    for (int x = 0; x < mask.width(); ++x) {
      if (!mask(x, y)) continue;
      left = std::min(left, x);
      right = std::max(right, x);
      top = std::min(top, y);
      bottom = std::max(bottom, y);
    }
  }
  left = std::max(0, left - kSsimWindowRadius);
  top = std::max(0, top - kSsimWindowRadius);
  right = std::min(mask.width() - 1, right + kSsimWindowRadius);
  bottom = std::min(mask.height() - 1, bottom + kSsimWindowRadius);
  return {left, top, right - left + 1, bottom - top + 1};
}

cv::Mat SsimWindowMean(const cv::Mat& values) {
  cv::Mat mean;
  cv::GaussianBlur(values, mean, cv::Size(2 * kSsimWindowRadius + 1, 2 * kSsimWindowRadius + 1),
                   1.5);
  return mean;
}

// Adds to `sum` the SSIM map of planes `x` and `y` (CV_64F, rows of one width) at the pixels of
// rows [first_row, end_row) that `selected` (one byte per pixel of the planes) marks, in raster
// order. Every window of those rows must lie within the planes or meet the image's own edges.
void AddChannelSsim(const cv::Mat& x, const cv::Mat& y, const std::uint8_t* selected, int first_row,
                    int end_row, double& sum) {
  constexpr double kC1 = 0.01 * 0.01, kC2 = 0.03 * 0.03;  // (K L)^2 with L = 1
  const cv::Mat mu_x = SsimWindowMean(x), mu_y = SsimWindowMean(y);
  const cv::Mat xx = SsimWindowMean(x.mul(x)), yy = SsimWindowMean(y.mul(y)),
                xy = SsimWindowMean(x.mul(y));
  const auto* mx = mu_x.ptr<double>();
  const auto* my = mu_y.ptr<double>();
  const auto* sxx = xx.ptr<double>();
  const auto* syy = yy.ptr<double>();
  const auto* sxy = xy.ptr<double>();
  const auto width = static_cast<std::size_t>(x.cols);
  for (std::size_t p = first_row * width; p < end_row * width; ++p) {
    if (!selected[p]) continue;
    const double variance_x = sxx[p] - mx[p] * mx[p], variance_y = syy[p] - my[p] * my[p];
    const double covariance = sxy[p] - mx[p] * my[p];
    sum += (2.0 * mx[p] * my[p] + kC1) * (2.0 * covariance + kC2) /
           ((mx[p] * mx[p] + my[p] * my[p] + kC1) * (variance_x + variance_y + kC2));
  }
}

CieLab DisplayedLab(const Image& image, std::size_t p, double peak) {
  if (image.channels() == 1) {
    const double v = Displayed(image.plane(0)[p], peak);
    return CieLabOfLinearRec709(v, v, v);
  }
  return CieLabOfLinearRec709(Displayed(image.plane(0)[p], peak),
                              Displayed(image.plane(1)[p], peak),
                              Displayed(image.plane(2)[p], peak));
}

}  // namespace

double MaskedPsnr(const Image& predicted, const Image& truth, const Mask& mask, double peak) {
  const std::size_t pixels = CheckComparable("PSNR", predicted, truth, mask, peak);
  double sum = 0.0;
  for (int c = 0; c < truth.channels(); ++c) {
    const auto a = predicted.plane(c);
    const auto b = truth.plane(c);
    for (std::size_t p = 0; p < truth.pixel_count(); ++p) {
      if (!mask[p]) continue;
      const double d = std::clamp(double{a[p]}, 0.0, peak) - std::clamp(double{b[p]}, 0.0, peak);
      sum += d * d;
    }
  }
  return PsnrDecibels(peak, sum / static_cast<double>(pixels * truth.channels()));
}

namespace {

// The comparison of the mask's region, in bands of kBandRows rows (so that the planes held as
// doubles follow the band, not the image).
MaskedDisplayComparison CompareRegion(const Image& predicted, const Image& truth, const Mask& mask,
                                      double peak, bool colour_difference) {
  constexpr int kBandRows = 64;
  const cv::Rect region = SsimRegion(mask);
  MaskedDisplayComparison comparison(region.width, region.height, truth.channels(), peak,
                                     colour_difference);
  for (int first = 0; first < region.height; first += kBandRows) {
    const int rows = std::min(kBandRows, region.height - first);
    Image predicted_band(region.width, rows, truth.channels());
    Image truth_band(region.width, rows, truth.channels());
    Mask mask_band(region.width, rows, false);
    for (int y = 0; y < rows; ++y) {
      const int image_y = region.y + first + y;
      for (int x = 0; x < region.width; ++x) {
        mask_band.Set(x, y, mask(region.x + x, image_y));
        for (int c = 0; c < truth.channels(); ++c) {
          predicted_band.at(x, y, c) = predicted.at(region.x + x, image_y, c);
          truth_band.at(x, y, c) = truth.at(region.x + x, image_y, c);
        }
      }
    }
    comparison.AddBand(first, predicted_band, truth_band, mask_band);
  }
  return comparison;
}

}  // namespace

double MaskedSsim(const Image& predicted, const Image& truth, const Mask& mask, double peak) {
  CheckComparable("SSIM", predicted, truth, mask, peak);
  return CompareRegion(predicted, truth, mask, peak, /*colour_difference=*/false).Ssim();
}

DisplayedComparison CompareDisplayed(const Image& predicted, const Image& truth, const Mask& mask,
                                     double peak) {
  CheckComparable("SSIM and Delta E 2000", predicted, truth, mask, peak);
  MaskedDisplayComparison comparison =
      CompareRegion(predicted, truth, mask, peak, /*colour_difference=*/true);
  const double ssim = comparison.Ssim();
  return {ssim, comparison.MeanDeltaE2000()};
}

double MaskedMeanDeltaE2000(const Image& predicted, const Image& truth, const Mask& mask,
                            double peak) {
  const std::size_t pixels = CheckComparable("Delta E 2000", predicted, truth, mask, peak);
  if (truth.channels() != 1 && truth.channels() != 3) {
    throw Error(fmt::format("Delta E 2000 of {}-channel images: expected 1 (grey) or 3 (RGB)",
                            truth.channels()));
  }
  double sum = 0.0;
  for (std::size_t p = 0; p < truth.pixel_count(); ++p) {
    if (mask[p]) sum += CieDe2000(DisplayedLab(predicted, p, peak), DisplayedLab(truth, p, peak));
  }
  return sum / static_cast<double>(pixels);
}

MaskedDisplayComparison::MaskedDisplayComparison(int width, int height, int channels, double peak,
                                                 bool colour_difference)
    : width_(width),
      height_(height),
      channels_(channels),
      peak_(peak),
      colour_difference_(colour_difference && (channels == 1 || channels == 3)),
      predicted_(static_cast<std::size_t>(channels)),
      truth_(static_cast<std::size_t>(channels)),
      ssim_sums_(static_cast<std::size_t>(channels), 0.0) {
  if (width <= 0 || height <= 0 || channels <= 0) {
    throw Error(fmt::format("a comparison of {}x{}x{} images", width, height, channels));
  }
  if (!(peak > 0.0)) throw Error(fmt::format("comparison: peak {} is not positive", peak));
}

void MaskedDisplayComparison::AppendRows(int rows, const Image* predicted, const Image* truth,
                                         const Mask* mask) {
  const std::size_t count = static_cast<std::size_t>(rows) * width_;
  const std::size_t start = selected_.size();
  selected_.resize(start + count, 0);
  for (std::vector<double>& plane : predicted_) plane.resize(start + count, 0.0);
  for (std::vector<double>& plane : truth_) plane.resize(start + count, 0.0);
  next_row_ += rows;
  if (!mask) return;  // rows outside the mask: 0 in both images
  for (std::size_t p = 0; p < count; ++p) {
    if (!(*mask)[p]) continue;
    selected_[start + p] = 1;
    ++pixels_;
    for (int c = 0; c < channels_; ++c) {
      predicted_[c][start + p] = LinearToSrgb(Displayed(predicted->plane(c)[p], peak_));
      truth_[c][start + p] = LinearToSrgb(Displayed(truth->plane(c)[p], peak_));
    }
    if (colour_difference_) {
      delta_e_sum_ += CieDe2000(DisplayedLab(*predicted, p, peak_), DisplayedLab(*truth, p, peak_));
    }
  }
}

void MaskedDisplayComparison::AddBand(int first_row, const Image& predicted, const Image& truth,
                                      const Mask& mask) {
  if (predicted.width() != width_ || truth.width() != width_ || mask.width() != width_ ||
      predicted.height() != truth.height() || mask.height() != truth.height() ||
      predicted.channels() != channels_ || truth.channels() != channels_) {
    throw Error(fmt::format("comparison of {}x{}x{} images: a band of {}x{}x{} against {}x{}x{}",
                            width_, height_, channels_, predicted.width(), predicted.height(),
                            predicted.channels(), truth.width(), truth.height(), truth.channels()));
  }
  if (first_row < next_row_ || first_row + truth.height() > height_) {
    throw Error(fmt::format("comparison: rows {} to {} after row {} of {}", first_row,
                            first_row + truth.height(), next_row_, height_));
  }
  AppendRows(first_row - next_row_, nullptr, nullptr, nullptr);
  AppendRows(truth.height(), &predicted, &truth, &mask);
  // Rows whose windows the rows held so far complete (all of them at the image's last row).
  Finalise(next_row_ == height_ ? height_ : next_row_ - kSsimWindowRadius);
}

void MaskedDisplayComparison::Finalise(int end_row) {
  if (end_row <= finalised_) return;
  // The rows held start kSsimWindowRadius rows above the first row to finalise (or at row 0) and
  // reach kSsimWindowRadius rows below the last (or the image's last row), so the windows of
  // the rows finalised see the same values as in the whole image.
  const int first = HeldFirstRow();
  const int rows = next_row_ - first;
  for (int c = 0; c < channels_; ++c) {
    const cv::Mat x(rows, width_, CV_64F, predicted_[c].data());
    const cv::Mat y(rows, width_, CV_64F, truth_[c].data());
    AddChannelSsim(x, y, selected_.data(), finalised_ - first, end_row - first, ssim_sums_[c]);
  }
  finalised_ = end_row;
  // Keep the rows the next rows' windows reach up into.
  const int drop = HeldFirstRow() - first;
  if (drop <= 0) return;
  const auto values = static_cast<std::ptrdiff_t>(drop) * width_;
  selected_.erase(selected_.begin(), selected_.begin() + values);
  for (std::vector<double>& plane : predicted_) plane.erase(plane.begin(), plane.begin() + values);
  for (std::vector<double>& plane : truth_) plane.erase(plane.begin(), plane.begin() + values);
}

int MaskedDisplayComparison::HeldFirstRow() const {
  return std::max(0, finalised_ - kSsimWindowRadius);
}

double MaskedDisplayComparison::Ssim() {
  AppendRows(height_ - next_row_, nullptr, nullptr, nullptr);
  Finalise(height_);
  if (pixels_ == 0) throw Error("SSIM: the mask selects no pixel");
  double sum = 0.0;
  for (double channel : ssim_sums_) sum += channel / static_cast<double>(pixels_);
  return sum / channels_;
}

std::optional<double> MaskedDisplayComparison::MeanDeltaE2000() const {
  if (!colour_difference_) return std::nullopt;
  if (pixels_ == 0) throw Error("Delta E 2000: the mask selects no pixel");
  return delta_e_sum_ / static_cast<double>(pixels_);
}

}  // namespace photomat
