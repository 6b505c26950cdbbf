#include "calibrate/radiometry/flat_field.h"

#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <string>
#include <vector>

#include "calibrate/radiometry/near_light.h"
#include "calibrate/testing/synthetic_calibration.h"
#include "capture/io/capture_manifest.h"
#include "capture/io/load_photometric_set.h"
#include "capture/io/streamed_set.h"
#include "core/atomic_file.h"
#include "core/error.h"
#include "tests/support/test_support.h"

namespace photomat {
namespace {

// Lamps 1.2 image widths from the centre at slants 30 and 50 (strong fall-off), of unequal
// brightness, about 1 at the centre of the sample.
std::vector<NearLight> RingOfLamps(int width) {
  std::vector<NearLight> lights;
  for (double slant : {30.0, 50.0}) {
    for (int k = 0; k < 6; ++k) {
      NearLight light;
      light.position =
          1.2 * width * LightDirection::FromSlantTilt(slant, 60.0 * k + slant).vector();
      light.intensity = light.position.squaredNorm() * (1.0 + 0.1 * k);
      lights.push_back(light);
    }
  }
  return lights;
}

// Largest relative difference between two flat-fields' gains.
double WorstRelativeDifference(const FlatField& a, const FlatField& b) {
  double worst = 0.0;
  for (int i = 0; i < a.size(); ++i) {
    const auto va = a.gain(i).values(), vb = b.gain(i).values();
    for (std::size_t v = 0; v < va.size(); ++v) {
      worst = std::max(worst, std::abs(double{va[v]} - vb[v]) / vb[v]);
    }
  }
  return worst;
}

TEST(FlatFieldTest, CleanTargetGivesTheNearLightGains) {
  const int size = 48;
  const auto lights = RingOfLamps(size);
  const FlatField truth = FlatFieldFromNearLights(lights, size, size, 3);
  const PhotometricSet target = RenderNearLightTarget(size, size, lights, 0.4);
  FlatFieldOptions smoothed;
  smoothed.model = FlatFieldModel::kSmoothed;
  smoothed.smoothing_sigma = 0.5;
  EXPECT_LT(WorstRelativeDifference(EstimateFlatField(target, smoothed), truth), 0.01);
  EXPECT_LT(WorstRelativeDifference(EstimateFlatField(target), truth), 0.01);
}

TEST(FlatFieldTest, PolynomialModelAveragesANoisyTarget) {
  const int size = 48;
  const auto lights = RingOfLamps(size);
  const FlatField truth = FlatFieldFromNearLights(lights, size, size, 3);
  // 5 % noise on a mid-grey target.
  const PhotometricSet target = RenderNearLightTarget(size, size, lights, 0.4, 0.004, 7);
  FlatFieldOptions raw;
  raw.model = FlatFieldModel::kSmoothed;
  raw.smoothing_sigma = 0.3;  // essentially unsmoothed
  const double unsmoothed = WorstRelativeDifference(EstimateFlatField(target, raw), truth);
  const double polynomial = WorstRelativeDifference(EstimateFlatField(target), truth);
  EXPECT_GT(unsmoothed, 0.08);
  EXPECT_LT(polynomial, 0.02);
}

TEST(FlatFieldTest, ApplyingTheGainsMakesTheTargetUniform) {
  const int size = 32;
  const auto lights = RingOfLamps(size);
  const PhotometricSet target = RenderNearLightTarget(size, size, lights, 0.5);
  const PhotometricSet flat =
      ApplyFlatField(target, FlatFieldFromNearLights(lights, size, size, 3));
  for (int i = 0; i < flat.size(); ++i) {
    // A uniform target under a distant unit light from l: albedo * l.z everywhere (up to the
    // common normalisation), the same ratio for every light.
    const double expected = flat.image(0).at(0, 0, 0) / flat.light(0).z() * flat.light(i).z();
    for (float v : flat.image(i).values()) EXPECT_NEAR(v, expected, 1e-4 * expected);
  }
}

TEST(FlatFieldTest, SaveAndLoadRoundTrip) {
  testing::TempDir dir;
  const auto lights = RingOfLamps(16);
  const FlatField flat = FlatFieldFromNearLights(lights, 16, 12, 3);
  SaveFlatField(dir / "ff", flat);
  const FlatField loaded = LoadFlatField(dir / "ff");
  ASSERT_EQ(loaded.size(), flat.size());
  EXPECT_LT(WorstRelativeDifference(loaded, flat), 1e-3);  // half floats
  EXPECT_LT(loaded.lights()[3].AngleToDegrees(flat.lights()[3]), 1e-9);
}

TEST(FlatFieldTest, MismatchedSetsAreRejected) {
  const auto lights = RingOfLamps(16);
  const FlatField flat = FlatFieldFromNearLights(lights, 16, 16, 3);
  const PhotometricSet other_size = RenderNearLightTarget(20, 16, lights);
  EXPECT_THROW(ApplyFlatField(other_size, flat), Error);
  std::vector<NearLight> moved = lights;
  moved[2].position = 20.0 * LightDirection::FromSlantTilt(60, 200).vector();
  EXPECT_THROW(ApplyFlatField(RenderNearLightTarget(16, 16, moved), flat), Error);
  EXPECT_THROW(ApplyFlatField(RenderNearLightTarget(16, 16, {lights[0]}), flat), Error);
}

TEST(FlatFieldTest, DarkTargetIsAnError) {
  const auto lights = RingOfLamps(16);
  PhotometricSet target = RenderNearLightTarget(16, 16, lights, 0.0);
  EXPECT_THROW(EstimateFlatField(target), Error);
}

// A target (noisy unless `noise` is 0) whose mask leaves a border out, written as float EXR (or
// 16-bit PNG).
std::filesystem::path WriteTarget(const testing::TempDir& dir, const std::string& name,
                                  double albedo, double noise,
                                  SampleType type = SampleType::kFloat) {
  const int width = 40, height = 32;
  PhotometricSet target =
      RenderNearLightTarget(width, height, RingOfLamps(width), albedo, noise, 7);
  Mask mask(width, height, false);
  for (int y = 3; y < height - 2; ++y) {
    for (int x = 2; x < width - 4; ++x) mask.Set(x, y, true);
  }
  target.set_mask(mask);
  SaveSetOptions save;
  save.sample_type = type;
  SavePhotometricSet(dir / name, target, save);
  return dir / name;
}

LoadOptions TargetLoadOptions() {
  LoadOptions load;
  load.apply_intensities = false;  // as `calibrate flatfield` reads a target
  return load;
}

// The streamed estimate (one image per thread at a time) writes what the in-memory estimate of
// the whole target, saved, writes: the same gain maps bit for bit and the same description, for
// both models and a masked target; no scratch folder is left.
TEST(FlatFieldTest, StreamedEstimateWritesTheInMemoryFlatField) {
  testing::TempDir dir;
  const std::filesystem::path target = WriteTarget(dir, "target", 0.4, 0.004);
  const LoadedSet whole = LoadPhotometricSet(target, TargetLoadOptions());
  ASSERT_TRUE(whole.set.mask());
  FlatFieldOptions smoothed;
  smoothed.model = FlatFieldModel::kSmoothed;
  for (const FlatFieldOptions& options : {FlatFieldOptions{}, smoothed}) {
    const std::string model(ToString(options.model));
    std::filesystem::create_directories(dir / "out");
    StreamedSet streamed = OpenStreamedSet(target, TargetLoadOptions());
    EstimateFlatFieldStreamed(streamed, dir / "out" / model, options);
    SaveFlatField(dir / ("in-memory-" + model), EstimateFlatField(whole.set, options));
    EXPECT_EQ(ReadTextFile(dir / "out" / model / "flatfield.json"),
              ReadTextFile(dir / ("in-memory-" + model) / "flatfield.json"));
    const FlatField a = LoadFlatField(dir / "out" / model);
    const FlatField b = LoadFlatField(dir / ("in-memory-" + model));
    ASSERT_EQ(a.size(), b.size());
    for (int i = 0; i < a.size(); ++i) {
      EXPECT_TRUE(testing::SameBits(a.gain(i), b.gain(i))) << model << ", light " << i;
    }
  }
  EXPECT_EQ(testing::EntriesOf(dir / "out"), (std::vector<std::string>{"polynomial", "smoothed"}));
}

// A dark target (found in the first pass) and a target image truncated part-way: an Error naming
// the image, and no folder, gain map or scratch left.
TEST(FlatFieldTest, StreamedEstimateOfABadTargetLeavesNothing) {
  testing::TempDir dir;
  std::filesystem::create_directories(dir / "out");
  StreamedSet dark = OpenStreamedSet(WriteTarget(dir, "dark", 0.0, 0.0), TargetLoadOptions());
  try {
    EstimateFlatFieldStreamed(dark, dir / "out" / "ff");
    FAIL() << "no error";
  } catch (const Error& error) {
    EXPECT_THAT(error.what(), ::testing::HasSubstr("the target is dark at pixel"));
  }
  EXPECT_TRUE(testing::EntriesOf(dir / "out").empty());
  const std::filesystem::path target = WriteTarget(dir, "cut", 0.4, 0.004, SampleType::kUint16);
  StreamedSet cut = OpenStreamedSet(target, TargetLoadOptions());
  const std::filesystem::path victim = target / "img_005.png";
  std::filesystem::resize_file(victim, std::filesystem::file_size(victim) / 2);
  try {
    EstimateFlatFieldStreamed(cut, dir / "out" / "ff");
    FAIL() << "no error";
  } catch (const Error& error) {
    EXPECT_THAT(error.what(), ::testing::HasSubstr("img_005.png"));
  }
  EXPECT_TRUE(testing::EntriesOf(dir / "out").empty());
}

TEST(NearLightTest, ReadsPositionsAndRejectsBadLines) {
  testing::TempDir dir;
  testing::WriteFile(dir / "lamps.txt", "2\n# x y z intensity\n0 0 100\n50 0 80 1.5\n");
  const auto lights = ReadNearLights(dir / "lamps.txt");
  ASSERT_EQ(lights.size(), 2u);
  EXPECT_DOUBLE_EQ(lights[1].intensity, 1.5);
  EXPECT_NEAR(NominalDirection(lights[1]).SlantDegrees(), std::atan2(50.0, 80.0) * 180 / M_PI,
              1e-9);
  testing::WriteFile(dir / "below.txt", "0 0 -5\n");
  EXPECT_THROW(ReadNearLights(dir / "below.txt"), Error);
  testing::WriteFile(dir / "count.txt", "3\n0 0 5\n");
  EXPECT_THROW(ReadNearLights(dir / "count.txt"), Error);
  // The sample frame: the image centre is the origin, y up.
  EXPECT_EQ(SamplePoint(4, 2, 0, 0), Eigen::Vector3d(-1.5, 0.5, 0.0));
}

}  // namespace
}  // namespace photomat
