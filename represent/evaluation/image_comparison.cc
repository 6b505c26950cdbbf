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

// Channel c of `image` as displayed (sRGB-encoded, [0, 1]) within `region`, 0 outside the mask.
cv::Mat SrgbPlane(const Image& image, int c, const Mask& mask, const cv::Rect& region,
                  double peak) {
  cv::Mat plane(region.height, region.width, CV_64F);
  const auto values = image.plane(c);
  for (int y = 0; y < region.height; ++y) {
    auto* out = plane.ptr<double>(y);
    const std::size_t row = static_cast<std::size_t>(region.y + y) * image.width() + region.x;
    for (int x = 0; x < region.width; ++x) {
      const std::size_t p = row + x;
      out[x] = mask[p] ? LinearToSrgb(Displayed(values[p], peak)) : 0.0;
    }
  }
  return plane;
}

cv::Mat SsimWindowMean(const cv::Mat& values) {
  cv::Mat mean;
  cv::GaussianBlur(values, mean, cv::Size(2 * kSsimWindowRadius + 1, 2 * kSsimWindowRadius + 1),
                   1.5);
  return mean;
}

// The mean over the mask of one channel's SSIM map, `x` and `y` the planes of `region`.
double MaskedChannelSsim(const cv::Mat& x, const cv::Mat& y, const Mask& mask,
                         const cv::Rect& region, std::size_t count) {
  constexpr double kC1 = 0.01 * 0.01, kC2 = 0.03 * 0.03;  // (K L)^2 with L = 1
  const cv::Mat mu_x = SsimWindowMean(x), mu_y = SsimWindowMean(y);
  const cv::Mat xx = SsimWindowMean(x.mul(x)), yy = SsimWindowMean(y.mul(y)),
                xy = SsimWindowMean(x.mul(y));
  const auto* mx = mu_x.ptr<double>();
  const auto* my = mu_y.ptr<double>();
  const auto* sxx = xx.ptr<double>();
  const auto* syy = yy.ptr<double>();
  const auto* sxy = xy.ptr<double>();
  double sum = 0.0;
  for (int row = 0; row < region.height; ++row) {
    for (int column = 0; column < region.width; ++column) {
      if (!mask(region.x + column, region.y + row)) continue;
      const std::size_t p = static_cast<std::size_t>(row) * region.width + column;
      const double variance_x = sxx[p] - mx[p] * mx[p], variance_y = syy[p] - my[p] * my[p];
      const double covariance = sxy[p] - mx[p] * my[p];
      sum += (2.0 * mx[p] * my[p] + kC1) * (2.0 * covariance + kC2) /
             ((mx[p] * mx[p] + my[p] * my[p] + kC1) * (variance_x + variance_y + kC2));
    }
  }
  return sum / static_cast<double>(count);
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

double MaskedSsim(const Image& predicted, const Image& truth, const Mask& mask, double peak) {
  const std::size_t pixels = CheckComparable("SSIM", predicted, truth, mask, peak);
  const cv::Rect region = SsimRegion(mask);
  double sum = 0.0;
  for (int c = 0; c < truth.channels(); ++c) {
    sum += MaskedChannelSsim(SrgbPlane(predicted, c, mask, region, peak),
                             SrgbPlane(truth, c, mask, region, peak), mask, region, pixels);
  }
  return sum / truth.channels();
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

}  // namespace photomat
