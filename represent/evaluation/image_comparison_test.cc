#include "represent/evaluation/image_comparison.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <opencv2/core.hpp>
#include <opencv2/quality/qualityssim.hpp>
#include <random>

#include "core/colour.h"
#include "core/error.h"

namespace photomat {
namespace {

// A smooth RGB pattern with noise of `noise` (seeded), values in [0, 1].
Image Pattern(int width, int height, double noise, unsigned seed) {
  Image image(width, height, 3);
  std::mt19937 random(seed);
  std::normal_distribution<float> normal(0.0f, 1.0f);
  for (int c = 0; c < 3; ++c) {
    for (int y = 0; y < height; ++y) {
      for (int x = 0; x < width; ++x) {
        const double v = 0.5 + 0.3 * std::sin(0.2 * x + c) * std::cos(0.15 * y - c);
        image.plane(c)[static_cast<std::size_t>(y) * width + x] =
            static_cast<float>(std::clamp(v + noise * normal(random), 0.0, 1.0));
      }
    }
  }
  return image;
}

// The image as OpenCV's SSIM takes it: 8-bit-range floats (its constants are (K 255)^2) of the
// sRGB-encoded values, channels interleaved.
cv::Mat SrgbCodes(const Image& image) {
  cv::Mat mat(image.height(), image.width(), CV_32FC3);
  for (int y = 0; y < image.height(); ++y) {
    for (int x = 0; x < image.width(); ++x) {
      const std::size_t p = static_cast<std::size_t>(y) * image.width() + x;
      for (int c = 0; c < 3; ++c) {
        mat.at<cv::Vec3f>(y, x)[c] = static_cast<float>(255.0 * LinearToSrgb(image.plane(c)[p]));
      }
    }
  }
  return mat;
}

TEST(ImageComparisonTest, MaskedPsnrClampsToThePeakAndSkipsUnmaskedPixels) {
  Image truth(3, 1, 2), predicted(3, 1, 2);
  // Channel 0: errors 0.1 and (clamped) 0; channel 1: errors 0.1 and 0.3. Pixel 2 is masked out.
  truth.plane(0)[0] = 0.5f;
  predicted.plane(0)[0] = 0.6f;
  truth.plane(0)[1] = 1.0f;
  predicted.plane(0)[1] = 1.7f;  // both clamp to 1
  truth.plane(1)[0] = 0.2f;
  predicted.plane(1)[0] = 0.1f;
  truth.plane(1)[1] = 0.3f;
  predicted.plane(1)[1] = 0.0f;
  truth.plane(0)[2] = 0.0f;
  predicted.plane(0)[2] = 1.0f;
  Mask mask(3, 1, true);
  mask.Set(2, false);
  // MSE = (0.01 + 0 + 0.01 + 0.09) / 4 = 0.0275, peak 1.
  EXPECT_NEAR(MaskedPsnr(predicted, truth, mask, 1.0), 10.0 * std::log10(1.0 / 0.0275), 1e-5);
  EXPECT_TRUE(std::isinf(MaskedPsnr(truth, truth, mask, 1.0)));
  EXPECT_THROW(MaskedPsnr(predicted, Image(2, 1, 2), Mask(2, 1, true), 1.0), Error);
  EXPECT_THROW(MaskedPsnr(predicted, truth, Mask(3, 1, false), 1.0), Error);
  EXPECT_THROW(MaskedPsnr(predicted, truth, mask, 0.0), Error);
}

TEST(ImageComparisonTest, SsimOfAWholeImageEqualsOpenCvsQualitySsim) {
  const Image truth = Pattern(64, 48, 0.0, 1);
  const Mask all(64, 48, true);
  for (const double noise : {0.01, 0.05, 0.2}) {
    const Image predicted = Pattern(64, 48, noise, 2);
    const cv::Scalar reference =
        cv::quality::QualitySSIM::compute(SrgbCodes(truth), SrgbCodes(predicted), cv::noArray());
    const double expected = (reference[0] + reference[1] + reference[2]) / 3.0;
    // OpenCV computes in float (its input here is float), photomat in double: measured
    // differences at most 2.3e-9; bound 1e-8.
    EXPECT_NEAR(MaskedSsim(predicted, truth, all, 1.0), expected, 1e-8) << noise;
    EXPECT_LT(MaskedSsim(predicted, truth, all, 1.0), 1.0);
  }
  EXPECT_NEAR(MaskedSsim(truth, truth, all, 1.0), 1.0, 1e-12);
}

TEST(ImageComparisonTest, MaskedSsimIsTheWholeImagesMapAveragedOverTheMask) {
  // MaskedSsim computes the map only where the mask's windows reach; the reference is OpenCV's
  // map of the whole images (0 outside the mask, as the IMPLEMENTER CHOICE says) averaged over
  // the mask. Masks inside the image, at its corners and across it.
  const Image truth = Pattern(64, 48, 0.0, 1);
  const Image predicted = Pattern(64, 48, 0.05, 2);
  struct Box {
    int left, top, right, bottom;  // right and bottom excluded
  };
  for (const Box box : {Box{20, 15, 40, 30}, Box{0, 0, 30, 20}, Box{40, 30, 64, 48},
                        Box{0, 10, 64, 20}, Box{31, 3, 32, 4}}) {
    Mask mask(64, 48, false);
    Image truth_in_mask(64, 48, 3), predicted_in_mask(64, 48, 3);
    for (int y = box.top; y < box.bottom; ++y) {
      for (int x = box.left; x < box.right; ++x) {
        mask.Set(x, y, true);
        for (int c = 0; c < 3; ++c) {
          truth_in_mask.at(x, y, c) = truth.at(x, y, c);
          predicted_in_mask.at(x, y, c) = predicted.at(x, y, c);
        }
      }
    }
    cv::Mat map;
    cv::quality::QualitySSIM::compute(SrgbCodes(truth_in_mask), SrgbCodes(predicted_in_mask), map);
    double sum = 0.0;
    for (int y = box.top; y < box.bottom; ++y) {
      for (int x = box.left; x < box.right; ++x) {
        const cv::Vec3d v = map.at<cv::Vec3d>(y, x);  // OpenCV's map is in double
        sum += (v[0] + v[1] + v[2]) / 3.0;
      }
    }
    const double expected = sum / static_cast<double>(mask.CountSet());
    // As above: OpenCV in float, photomat in double.
    EXPECT_NEAR(MaskedSsim(predicted, truth, mask, 1.0), expected, 1e-8)
        << box.left << "," << box.top;
  }
}

// Rows [first, first + rows) of `image`.
Image Rows(const Image& image, int first, int rows) {
  Image band(image.width(), rows, image.channels());
  for (int c = 0; c < image.channels(); ++c) {
    for (int y = 0; y < rows; ++y) {
      for (int x = 0; x < image.width(); ++x) band.at(x, y, c) = image.at(x, first + y, c);
    }
  }
  return band;
}

Mask Rows(const Mask& mask, int first, int rows) {
  Mask band(mask.width(), rows, false);
  for (int y = 0; y < rows; ++y) {
    for (int x = 0; x < mask.width(); ++x) band.Set(x, y, mask(x, first + y));
  }
  return band;
}

TEST(ImageComparisonTest, BandsGiveTheWholeImagesSsimAndColourDifference) {
  // A disc mask on 40 x 37 images, given in bands of 1, 2, 3, 7 and 37 rows, and with the bands
  // the mask leaves empty (its first and last rows) not given at all, as a streamed evaluation
  // skips them.
  const Image truth = Pattern(40, 37, 0.0, 1);
  const Image predicted = Pattern(40, 37, 0.08, 4);
  Mask disc(40, 37, false);
  for (int y = 0; y < 37; ++y) {
    for (int x = 0; x < 40; ++x) disc.Set(x, y, (x - 20) * (x - 20) + (y - 18) * (y - 18) < 150);
  }
  const double ssim = MaskedSsim(predicted, truth, disc, 0.9);
  const double delta_e = MaskedMeanDeltaE2000(predicted, truth, disc, 0.9);
  for (const int band : {1, 2, 3, 7, 37}) {
    for (const bool skip_empty : {false, true}) {
      MaskedDisplayComparison comparison(40, 37, 3, 0.9);
      for (int first = 0; first < 37; first += band) {
        const int rows = std::min(band, 37 - first);
        const Mask mask = Rows(disc, first, rows);
        if (skip_empty && mask.CountSet() == 0) continue;
        comparison.AddBand(first, Rows(predicted, first, rows), Rows(truth, first, rows), mask);
      }
      // The whole images' SSIM is taken over the mask's region, these over every column: the
      // same windows and sums in the same order, so the same bits.
      EXPECT_EQ(comparison.Ssim(), ssim) << band << (skip_empty ? " skipping" : "");
      EXPECT_EQ(*comparison.MeanDeltaE2000(), delta_e) << band;
    }
  }
  EXPECT_LT(ssim, 0.99);
  EXPECT_GT(delta_e, 0.5);
  // Both in one pass, as an evaluation takes them: the same bits.
  const DisplayedComparison both = CompareDisplayed(predicted, truth, disc, 0.9);
  EXPECT_EQ(both.ssim, ssim);
  ASSERT_TRUE(both.mean_delta_e2000);
  EXPECT_EQ(*both.mean_delta_e2000, delta_e);
  EXPECT_FALSE(MaskedDisplayComparison(4, 4, 3, 1.0, /*colour_difference=*/false)
                   .MeanDeltaE2000()
                   .has_value());

  MaskedDisplayComparison comparison(40, 37, 3, 1.0);
  comparison.AddBand(5, Rows(predicted, 5, 3), Rows(truth, 5, 3), Rows(disc, 5, 3));
  EXPECT_THROW(comparison.AddBand(6, Rows(predicted, 6, 3), Rows(truth, 6, 3), Rows(disc, 6, 3)),
               Error);  // rows given already
  EXPECT_THROW(comparison.AddBand(35, Rows(predicted, 0, 3), Rows(truth, 0, 3), Rows(disc, 0, 3)),
               Error);  // beyond the last row
  EXPECT_FALSE(MaskedDisplayComparison(4, 4, 2, 1.0).MeanDeltaE2000().has_value());
  EXPECT_THROW(MaskedDisplayComparison(4, 4, 3, 1.0).Ssim(), Error);  // no pixel selected
}

TEST(ImageComparisonTest, SsimOfConstantImagesIsTheLuminanceTerm) {
  // No variance: SSIM = (2 a b + C1) / (a^2 + b^2 + C1) of the sRGB encodings a and b.
  Image predicted(16, 16, 1), truth(16, 16, 1);
  for (float& v : predicted.values()) v = 0.2f;
  for (float& v : truth.values()) v = 0.6f;
  const double a = LinearToSrgb(double{0.2f}), b = LinearToSrgb(double{0.6f}), c1 = 1e-4;
  EXPECT_NEAR(MaskedSsim(predicted, truth, Mask(16, 16, true), 1.0),
              (2.0 * a * b + c1) / (a * a + b * b + c1), 1e-9);
  // The peak scales the values: 0.4 of peak 2 is 0.2 of peak 1; above the peak clamps.
  for (float& v : predicted.values()) v = 0.4f;
  for (float& v : truth.values()) v = 1.2f;
  EXPECT_NEAR(MaskedSsim(predicted, truth, Mask(16, 16, true), 2.0),
              (2.0 * a * b + c1) / (a * a + b * b + c1), 1e-9);
  for (float& v : predicted.values()) v = 7.0f;
  for (float& v : truth.values()) v = 1.0f;
  EXPECT_NEAR(MaskedSsim(predicted, truth, Mask(16, 16, true), 1.0), 1.0, 1e-12);
}

TEST(ImageComparisonTest, SsimIgnoresWhatLiesOutsideTheMaskAndFallsWithNoise) {
  const Image truth = Pattern(40, 40, 0.0, 1);
  Mask mask(40, 40, false);
  for (int y = 10; y < 30; ++y) {
    for (int x = 10; x < 30; ++x) mask.Set(x, y, true);
  }
  Image predicted = truth;
  const double equal = MaskedSsim(predicted, truth, mask, 1.0);
  EXPECT_NEAR(equal, 1.0, 1e-12);
  for (int c = 0; c < 3; ++c) predicted.plane(c)[0] = 0.9f;  // outside the mask
  EXPECT_EQ(MaskedSsim(predicted, truth, mask, 1.0), equal);
  double previous = 1.0;
  for (const double noise : {0.01, 0.03, 0.1, 0.3}) {
    const double ssim = MaskedSsim(Pattern(40, 40, noise, 3), truth, mask, 1.0);
    EXPECT_LT(ssim, previous) << noise;
    previous = ssim;
  }
  EXPECT_THROW(MaskedSsim(predicted, truth, Mask(40, 40, false), 1.0), Error);
  EXPECT_THROW(MaskedSsim(predicted, Image(40, 39, 3), mask, 1.0), Error);
}

TEST(ImageComparisonTest, DeltaE2000OfWhiteAgainstBlackIsOneHundred) {
  // L* 100 against 0, a* = b* = 0: CIEDE2000 is the lightness difference, 100 (the ICC's HDR
  // working group's reference pair). Two of three pixels so: a mean of 200 / 3; one of two: 50.
  Image predicted(2, 2, 3), truth(2, 2, 3);
  for (int c = 0; c < 3; ++c) {
    predicted.plane(c)[0] = 1.0f;
    predicted.plane(c)[1] = 3.0f;  // clamps to white
    predicted.plane(c)[2] = 0.25f;
    truth.plane(c)[2] = 0.25f;
    predicted.plane(c)[3] = 1.0f;  // outside the mask
  }
  Mask mask(2, 2, true);
  mask.Set(3, false);
  EXPECT_NEAR(MaskedMeanDeltaE2000(predicted, truth, mask, 1.0), 200.0 / 3.0, 1e-9);
  Mask two(2, 2, false);
  two.Set(0, true);
  two.Set(2, true);
  EXPECT_NEAR(MaskedMeanDeltaE2000(predicted, truth, two, 1.0), 50.0, 1e-9);
  EXPECT_EQ(MaskedMeanDeltaE2000(truth, truth, mask, 1.0), 0.0);
}

TEST(ImageComparisonTest, DeltaE2000IsOfTheDisplayedColoursAndGreyImagesAreNeutral) {
  Image predicted(1, 1, 3), truth(1, 1, 3);
  const float rgb[3] = {0.8f, 0.3f, 0.1f}, other[3] = {0.7f, 0.35f, 0.12f};
  for (int c = 0; c < 3; ++c) {
    predicted.plane(c)[0] = 2.0f * rgb[c];  // peak 2
    truth.plane(c)[0] = 2.0f * other[c];
  }
  EXPECT_NEAR(MaskedMeanDeltaE2000(predicted, truth, Mask(1, 1, true), 2.0),
              CieDe2000(CieLabOfLinearRec709(rgb[0], rgb[1], rgb[2]),
                        CieLabOfLinearRec709(other[0], other[1], other[2])),
              1e-6);
  // A grey image is R = G = B: its difference is the three-channel one of the same values.
  Image grey_a(1, 1, 1), grey_b(1, 1, 1), rgb_a(1, 1, 3), rgb_b(1, 1, 3);
  grey_a.plane(0)[0] = 0.3f;
  grey_b.plane(0)[0] = 0.5f;
  for (int c = 0; c < 3; ++c) {
    rgb_a.plane(c)[0] = 0.3f;
    rgb_b.plane(c)[0] = 0.5f;
  }
  EXPECT_DOUBLE_EQ(MaskedMeanDeltaE2000(grey_a, grey_b, Mask(1, 1, true), 1.0),
                   MaskedMeanDeltaE2000(rgb_a, rgb_b, Mask(1, 1, true), 1.0));
  EXPECT_THROW(MaskedMeanDeltaE2000(Image(1, 1, 2), Image(1, 1, 2), Mask(1, 1, true), 1.0), Error);
}

}  // namespace
}  // namespace photomat
