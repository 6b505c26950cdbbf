#include "calibrate/radiometry/capture_corrections.h"

#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include <algorithm>
#include <filesystem>
#include <functional>
#include <string>
#include <vector>

#include "core/error.h"
#include "core/near_light.h"

namespace photomat {
namespace {

// 12 lights, 20 x 14 pixels, 3 channels of values in (0.1, 0.9) that differ at every sample.
PhotometricSet Capture() {
  std::vector<Image> images;
  std::vector<LightDirection> lights;
  for (int i = 0; i < 12; ++i) {
    Image image(20, 14, 3);
    for (int c = 0; c < 3; ++c) {
      for (int y = 0; y < 14; ++y) {
        for (int x = 0; x < 20; ++x) {
          image.at(x, y, c) =
              0.1f + 0.8f * static_cast<float>((7 * x + 13 * y + 29 * c + 31 * i) % 97) / 97.0f;
        }
      }
    }
    images.push_back(std::move(image));
    lights.push_back(LightDirection::FromSlantTilt(20.0 + 3.0 * i, 30.0 * i));
  }
  PhotometricSet set(std::move(images), std::move(lights));
  set.set_intensities(std::vector<std::vector<float>>(12, {1.0f, 0.9f, 1.1f}));
  return set;
}

// Rows [first, first + count) of every image, as StreamedSet::ReadBand gives them.
PhotometricSet Band(const PhotometricSet& set, int first, int count) {
  std::vector<Image> images;
  for (const Image& image : set.images()) images.emplace_back(image.Rows(first, count));
  PhotometricSet band(std::move(images), set.lights());
  band.set_intensities(set.intensities());
  return band;
}

std::vector<NearLight> Lamps(const PhotometricSet& set) {
  std::vector<NearLight> lamps;
  for (const LightDirection& l : set.lights()) {
    NearLight lamp;
    lamp.position = 30.0 * l.vector();
    lamp.intensity = 900.0;
    lamps.push_back(lamp);
  }
  return lamps;
}

Image Dark(int width, int height) {
  Image dark(width, height, 1);
  for (int y = 0; y < height; ++y) {
    for (int x = 0; x < width; ++x) dark.at(x, y, 0) = 0.01f * static_cast<float>((x + y) % 5);
  }
  return dark;
}

// Every correction acts on a pixel alone (the near lamps' normalisation is the whole field's),
// so bands of any height give the rows of the whole capture corrected at once, bit for bit.
// `make` gives the corrections afresh for each pass (a flat-field folder is read in row order).
void ExpectBandsEqualTheWhole(const PhotometricSet& set,
                              const std::function<CaptureCorrections()>& make) {
  CaptureCorrections once = make();
  const PhotometricSet whole = CorrectCaptureBand(set, 0, set.height(), once);
  for (int rows : {1, 3, 5}) {
    CaptureCorrections corrections = make();
    for (int first = 0; first < set.height(); first += rows) {
      const int count = std::min(rows, set.height() - first);
      const PhotometricSet band =
          CorrectCaptureBand(Band(set, first, count), first, set.height(), corrections);
      ASSERT_EQ(band.intensities(), whole.intensities());
      for (int i = 0; i < set.size(); ++i) {
        const Image expected(whole.image(i).Rows(first, count));
        ASSERT_TRUE(std::equal(expected.values().begin(), expected.values().end(),
                               band.image(i).values().begin()))
            << "image " << i << ", rows " << first << ".." << first + count - 1;
      }
      if (corrections.near_lights) {
        ASSERT_TRUE(band.near_lighting());
        EXPECT_EQ(band.near_lighting()->first_row, first);
        EXPECT_EQ(band.near_lighting()->height, set.height());
      }
    }
  }
}

TEST(CaptureCorrectionsTest, BandsOfResponseDarkAndNearLampsEqualTheWholeCapture) {
  const PhotometricSet set = Capture();
  const auto make = [&] {
    CaptureCorrections corrections;
    corrections.response = ResponseCurve::Srgb(3, 256);
    corrections.dark = Dark(set.width(), set.height());
    corrections.near_lights.emplace(Lamps(set), set.width(), set.height(), set.channels());
    return corrections;
  };
  ExpectBandsEqualTheWhole(set, make);
  // The corrections did something: the near lamps' fall-off is divided out.
  CaptureCorrections corrections = make();
  const PhotometricSet whole = CorrectCaptureBand(set, 0, set.height(), corrections);
  EXPECT_NE(whole.image(0).at(0, 0, 0), set.image(0).at(0, 0, 0));
}

// A target's gain maps as SaveFlatField writes them, with values that differ per light, pixel
// and channel.
std::filesystem::path SaveGains(const PhotometricSet& set, const std::string& name) {
  std::vector<Image> gains;
  for (int i = 0; i < set.size(); ++i) {
    Image gain(set.width(), set.height(), set.channels());
    for (int c = 0; c < set.channels(); ++c) {
      for (int y = 0; y < set.height(); ++y) {
        for (int x = 0; x < set.width(); ++x) {
          gain.at(x, y, c) = 0.5f + 0.01f * static_cast<float>(i + x + 2 * y + 3 * c);
        }
      }
    }
    gains.push_back(std::move(gain));
  }
  const std::filesystem::path folder = std::filesystem::path(::testing::TempDir()) / name;
  std::filesystem::remove_all(folder);
  SaveFlatField(folder, FlatField(std::move(gains), set.lights()));
  return folder;
}

TEST(CaptureCorrectionsTest, BandsOfATargetsFlatFieldEqualTheWholeCapture) {
  const PhotometricSet set = Capture();
  const std::filesystem::path folder = SaveGains(set, "capture_corrections_flat");
  ExpectBandsEqualTheWhole(set, [&] {
    CaptureCorrections corrections;
    corrections.flat_field.emplace(folder);
    corrections.dark = Dark(set.width(), set.height());
    return corrections;
  });
  // The gains read band by band are the whole field's (LoadFlatField), and they were divided out.
  CaptureCorrections corrections;
  corrections.flat_field.emplace(folder);
  const PhotometricSet corrected = CorrectCaptureBand(set, 0, set.height(), corrections);
  const FlatField whole = LoadFlatField(folder);
  EXPECT_FLOAT_EQ(corrected.image(5).at(7, 9, 2),
                  set.image(5).at(7, 9, 2) / whole.gain(5).at(7, 9, 2));
}

// The flat-field's rows are read in order: a band that skips or repeats rows is refused.
TEST(CaptureCorrectionsTest, BandsOutOfOrderAreRefusedWithAFlatField) {
  const PhotometricSet set = Capture();
  CaptureCorrections corrections;
  corrections.flat_field.emplace(SaveGains(set, "capture_corrections_order"));
  CorrectCaptureBand(Band(set, 0, 4), 0, set.height(), corrections);
  try {
    CorrectCaptureBand(Band(set, 6, 4), 6, set.height(), corrections);
    FAIL() << "no error";
  } catch (const Error& error) {
    EXPECT_THAT(error.what(), testing::HasSubstr("rows from 6 corrected after the flat-field's "
                                                 "rows up to 4"));
  }
}

// A band's rows of a dark frame or flat-field of another height would fit the band: the whole
// frame's size is checked for every band, with the in-memory message.
TEST(CaptureCorrectionsTest, ADarkFrameOfAnotherHeightIsRefusedInEveryBand) {
  const PhotometricSet set = Capture();
  CaptureCorrections corrections;
  corrections.dark = Dark(set.width(), set.height() + 2);
  try {
    CorrectCaptureBand(Band(set, 0, 3), 0, set.height(), corrections);
    FAIL() << "no error";
  } catch (const Error& error) {
    EXPECT_THAT(error.what(), testing::HasSubstr("the dark frame is 20x16 with 1 channels but the "
                                                 "images are 20x14 with 3"));
  }
}

}  // namespace
}  // namespace photomat
