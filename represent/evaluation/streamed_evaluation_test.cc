#include "represent/evaluation/streamed_evaluation.h"

#include <fmt/format.h>
#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include <memory>
#include <string>

#include "calibrate/radiometry/exposure.h"
#include "capture/io/capture_manifest.h"
#include "capture/io/load_photometric_set.h"
#include "core/error.h"
#include "core/image_io.h"
#include "represent/fitting/fit.h"
#include "represent/stack/map_stack.h"
#include "represent/streaming/fitted_stack_writer.h"
#include "represent/streaming/streamed_fit.h"
#include "tests/support/synthetic_sets.h"
#include "tests/support/test_support.h"

namespace photomat {
namespace {

namespace fs = std::filesystem;
using ::testing::HasSubstr;
using ::testing::ThrowsMessage;

// A 40 x 36 capture with shadows and highlights and a mask whose first rows are empty (bands
// without a pixel), as float EXRs.
fs::path WriteCapture(const fs::path& folder) {
  const auto synthetic = testing::ShadowedSpecularSet(40);
  std::vector<Image> images;
  for (const Image& image : synthetic.set.images()) images.emplace_back(image.Rows(0, 36));
  PhotometricSet set(std::move(images), synthetic.set.lights());
  Mask mask(40, 36, false);
  for (int y = 6; y < 36; ++y) {
    for (int x = 0; x < 40; ++x) mask.Set(x, y, (x - 20) * (x - 20) + (y - 20) * (y - 20) < 250);
  }
  set.set_mask(mask);
  SaveSetOptions options;
  options.sample_type = SampleType::kFloat;
  SavePhotometricSet(folder, set, options);
  return folder;
}

// The capture's ground-truth normals (WriteCapture's rows) as a float EXR at `path`; returns them.
Image WriteTruthNormals(const fs::path& path) {
  Image truth(testing::ShadowedSpecularSet(40).material.normals.Rows(0, 36));
  ImageWriteOptions exr;
  exr.sample_type = SampleType::kFloat;
  WriteImage(path, truth, exr);
  return truth;
}

// The streamed eta of reconstruction equals the in-memory evaluation's (the same fit relit at every
// captured light) to double rounding: the same squared differences, summed per band.
TEST(StreamedEvaluationTest, BandsGiveTheInMemoryEtaOfReconstruction) {
  testing::TempDir dir;
  const fs::path input = WriteCapture(dir / "capture");
  const LoadedSet loaded = LoadPhotometricSet(input);
  const Observations observations(loaded.set);
  EvaluationOptions in_memory;
  in_memory.prediction = false;
  for (const char* name : {"gradient", "ptm", "eigen6", "hsh9"}) {
    const Method method = Method::Parse(name);
    SaveRepresentation(dir / "stack.exr", Fit(loaded.set, method));
    const MethodEvaluation whole =
        EvaluateMethod(loaded.set, observations, method, nullptr, in_memory);
    StreamedSet set = OpenStreamedSet(input);
    StackBandReader stack(dir / "stack.exr");
    StreamedEvaluationOptions options;
    options.band_rows = 5;
    const MethodEvaluation streamed = EvaluateStackStreamed(set, stack, options);
    EXPECT_EQ(streamed.method.Name(), name);
    EXPECT_NEAR(streamed.eta_reconstruction, whole.eta_reconstruction,
                1e-9 * whole.eta_reconstruction)
        << name;
    ASSERT_EQ(streamed.reconstruction_per_image.size(), whole.reconstruction_per_image.size());
    for (std::size_t k = 0; k < whole.reconstruction_per_image.size(); ++k) {
      EXPECT_NEAR(streamed.reconstruction_per_image[k], whole.reconstruction_per_image[k],
                  1e-9 * whole.reconstruction_per_image[k])
          << name << " image " << k;
    }
  }
}

// With ground-truth normals, each band's normals are compared with the truth's rows: the same
// statistics as the in-memory evaluation's, bit for bit (the same errors, in the same order), for
// the methods that give normals, and none for those that do not.
TEST(StreamedEvaluationTest, BandsGiveTheInMemoryNormalErrors) {
  testing::TempDir dir;
  const fs::path input = WriteCapture(dir / "capture");
  const Image truth = WriteTruthNormals(dir / "truth.exr");
  const LoadedSet loaded = LoadPhotometricSet(input);
  const Observations observations(loaded.set);
  EvaluationOptions in_memory;
  in_memory.prediction = false;
  int compared = 0;
  for (const char* name : {"gradient", "ptm", "eigen6", "hsh9"}) {
    const Method method = Method::Parse(name);
    SaveRepresentation(dir / "stack.exr", Fit(loaded.set, method));
    const MethodEvaluation whole =
        EvaluateMethod(loaded.set, observations, method, &truth, in_memory);
    StreamedSet set = OpenStreamedSet(input);
    StackBandReader stack(dir / "stack.exr");
    StreamedEvaluationOptions options;
    options.band_rows = 5;
    options.ground_truth_normals = dir / "truth.exr";
    const MethodEvaluation streamed = EvaluateStackStreamed(set, stack, options);
    ASSERT_EQ(streamed.normals.has_value(), whole.normals.has_value()) << name;
    if (!whole.normals) continue;
    ++compared;
    EXPECT_EQ(streamed.normals->ToJson(), whole.normals->ToJson()) << name;
    EXPECT_GT(whole.normals->pixels, 500u) << name;
  }
  EXPECT_GE(compared, 2);  // Gradient and PTM give normals
}

// Several stacks evaluated in one pass over the photographs (EvaluateStacksStreamed, what
// `evaluate --stream` does) give each stack's evaluation alone: the same normal statistics bit for
// bit and the same eta to double rounding (measured: equal here, both in bands of 5 rows; bound
// 1e-12 relative), in the stacks' order.
TEST(StreamedEvaluationTest, StacksEvaluatedInOnePassGiveEachStacksEvaluation) {
  testing::TempDir dir;
  const fs::path input = WriteCapture(dir / "capture");
  WriteTruthNormals(dir / "truth.exr");
  const LoadedSet loaded = LoadPhotometricSet(input);
  const std::vector<std::string> names = {"hsh9", "gradient", "eigen6", "ptm"};
  std::vector<StackBandReader> readers;
  readers.reserve(names.size());
  std::vector<StackBandReader*> stacks;
  for (const std::string& name : names) {
    const fs::path path = dir / (name + ".exr");
    SaveRepresentation(path, Fit(loaded.set, Method::Parse(name)));
    stacks.push_back(&readers.emplace_back(path));
  }
  StreamedEvaluationOptions options;
  options.band_rows = 5;
  options.ground_truth_normals = dir / "truth.exr";
  StreamedSet set = OpenStreamedSet(input);
  const std::vector<MethodEvaluation> together = EvaluateStacksStreamed(set, stacks, options);
  ASSERT_EQ(together.size(), names.size());
  for (std::size_t m = 0; m < names.size(); ++m) {
    const MethodEvaluation alone = EvaluateStackStreamed(set, *stacks[m], options);
    EXPECT_EQ(together[m].method.Name(), names[m]);
    EXPECT_NEAR(together[m].eta_reconstruction, alone.eta_reconstruction,
                1e-12 * alone.eta_reconstruction)
        << names[m];
    ASSERT_EQ(together[m].reconstruction_per_image.size(), alone.reconstruction_per_image.size());
    for (std::size_t k = 0; k < alone.reconstruction_per_image.size(); ++k) {
      EXPECT_NEAR(together[m].reconstruction_per_image[k], alone.reconstruction_per_image[k],
                  1e-12 * alone.reconstruction_per_image[k])
          << names[m] << " image " << k;
    }
    ASSERT_EQ(together[m].normals.has_value(), alone.normals.has_value()) << names[m];
    if (alone.normals) {
      EXPECT_EQ(together[m].normals->ToJson(), alone.normals->ToJson()) << names[m];
    }
  }
  // Gradient and PTM give normals, HSH and Eigen-k none.
  EXPECT_TRUE(together[1].normals && together[3].normals);
  EXPECT_FALSE(together[0].normals || together[2].normals);
}

// `methods` predicted on the capture at `input` streamed, in bands of 5 rows, and in memory with
// `in_memory`'s folds and robust options: the same predicted images, and eta and PSNR within
// 1e-12 relative and 1e-11 dB (mean and per image), and for held-out images the SSIM and colour
// difference within 1e-12 and 1e-11. Returns the in-memory evaluations.
std::vector<MethodEvaluation> ExpectStreamedPredictionMatches(const fs::path& input,
                                                              const std::vector<Method>& methods,
                                                              const EvaluationOptions& in_memory) {
  const LoadedSet loaded = LoadPhotometricSet(input);
  const Observations observations(loaded.set);
  std::vector<MethodEvaluation> streamed(methods.size());
  StreamedSet set = OpenStreamedSet(input);
  StreamedPredictionOptions options;
  options.band_rows = 5;
  options.hold_out_every = in_memory.hold_out_every;
  options.robust = in_memory.robust;
  options.appearance = in_memory.hold_out_every > 0;  // held-out images only
  PredictStreamed(set, methods, streamed, options);
  std::vector<MethodEvaluation> wholes;
  for (std::size_t i = 0; i < methods.size(); ++i) {
    const std::string label =
        fmt::format("{}{}, hold out every {}", in_memory.robust ? "robust " : "", methods[i].Name(),
                    in_memory.hold_out_every);
    const MethodEvaluation& whole = wholes.emplace_back(
        EvaluateMethod(loaded.set, observations, methods[i], nullptr, in_memory));
    EXPECT_EQ(streamed[i].prediction_images, whole.prediction_images) << label;
    if (!streamed[i].eta_prediction || !streamed[i].psnr_prediction ||
        streamed[i].prediction_images != whole.prediction_images) {
      ADD_FAILURE() << label << ": no streamed prediction of the same images";
      continue;
    }
    EXPECT_NEAR(*streamed[i].eta_prediction, *whole.eta_prediction, 1e-12 * *whole.eta_prediction)
        << label;
    EXPECT_NEAR(*streamed[i].psnr_prediction, *whole.psnr_prediction, 1e-11) << label;
    for (std::size_t j = 0; j < whole.prediction_images.size(); ++j) {
      EXPECT_NEAR(streamed[i].prediction_per_image[j], whole.prediction_per_image[j],
                  1e-12 * whole.prediction_per_image[j])
          << label << ", image " << whole.prediction_images[j];
      EXPECT_NEAR(streamed[i].psnr_prediction_per_image[j], whole.psnr_prediction_per_image[j],
                  1e-11)
          << label << ", image " << whole.prediction_images[j];
    }
    // The SSIM and colour difference of held-out images, compared band by band: measured equal
    // to the in-memory ones bit for bit (least squares, robust, pbr); the bounds are the eta's.
    if (!options.appearance) {
      EXPECT_FALSE(streamed[i].ssim_prediction || streamed[i].delta_e2000_prediction) << label;
      continue;
    }
    if (streamed[i].ssim_prediction_per_image.size() != whole.prediction_images.size() ||
        streamed[i].delta_e2000_prediction_per_image.size() != whole.prediction_images.size()) {
      ADD_FAILURE() << label << ": no SSIM or colour difference of every held-out image";
      continue;
    }
    for (std::size_t j = 0; j < whole.prediction_images.size(); ++j) {
      EXPECT_NEAR(streamed[i].ssim_prediction_per_image[j], whole.ssim_prediction_per_image[j],
                  1e-12)
          << label << ", image " << whole.prediction_images[j];
      EXPECT_NEAR(streamed[i].delta_e2000_prediction_per_image[j],
                  whole.delta_e2000_prediction_per_image[j], 1e-11)
          << label << ", image " << whole.prediction_images[j];
    }
  }
  return wholes;
}

// The streamed prediction fits every fold band by band (the Gram-based methods' fold bases from
// the whole set's Gram matrix) and sums each predicted image's errors over the bands: the
// in-memory leave-one-out and held-out eta and PSNR of prediction, to double rounding (the fold
// fits are the same; the sums differ in order). Measured: at most 1.1e-14 relative in eta and
// 7.1e-14 dB in PSNR per image; the bounds, 1e-12 and 1e-11 dB, leave a hundredfold margin.
TEST(StreamedEvaluationTest, BandsGiveTheInMemoryPrediction) {
  testing::TempDir dir;
  const fs::path input = WriteCapture(dir / "capture");
  std::vector<Method> methods;
  for (const char* name :
       {"3i", "gradient", "ptm", "ptm-lrgb", "hsh9", "eigen6", "rbf", "bilinear"}) {
    methods.push_back(Method::Parse(name));
  }
  for (int hold_out_every : {0, 3}) {
    EvaluationOptions in_memory;
    in_memory.hold_out_every = hold_out_every;
    const std::vector<MethodEvaluation> wholes =
        ExpectStreamedPredictionMatches(input, methods, in_memory);
    for (const MethodEvaluation& whole : wholes) {
      // Prediction is harder than reconstruction: a real error, not a copy of the fit's.
      EXPECT_GT(*whole.eta_prediction, whole.eta_reconstruction)
          << whole.method.Name() << ", hold out every " << hold_out_every;
    }
  }
}

// Robust folds: each fold's robust fit of the band, its measured masks found on the band, gives
// the in-memory robust prediction, whose measured masks are the whole set's; for the methods
// fitted per pixel from the robust weights and for those fitted on the fold's imputed profiles
// (Eigen-k's EM passes, rbf and bilinear models from the imputed Gram matrix). Measured: at most
// 1.24e-14 relative in eta per image (Tukey, leave-one-out and every 4th held out; Eigen-k, rbf
// and bilinear 1.28e-14); bounds as above.
TEST(StreamedEvaluationTest, BandsGiveTheInMemoryRobustPrediction) {
  testing::TempDir dir;
  const fs::path input = WriteCapture(dir / "capture");
  const std::vector<Mask> measured = MeasuredPixelMasks(LoadPhotometricSet(input).set);
  std::vector<Method> methods;
  for (const char* name : {"gradient", "ptm", "hsh9", "eigen6", "rbf", "bilinear"}) {
    methods.push_back(Method::Parse(name));
  }
  for (int hold_out_every : {0, 4}) {
    EvaluationOptions in_memory;
    in_memory.hold_out_every = hold_out_every;
    in_memory.robust.emplace();
    in_memory.robust->loss = RobustLoss::kTukey;
    in_memory.robust->measured = measured;
    ExpectStreamedPredictionMatches(input, methods, in_memory);
  }
}

// The fit of every image that PredictStreamed makes beside its folds (whole_set_fit), written by
// FittedStackWriter, is FitStreamed's fit in the same bands: the same maps and details, least
// squares and robust (robust Eigen-k's EM passes, rbf and bilinear from the imputed Gram matrix
// included), so `evaluate --stream` takes its scratch stacks from the prediction's passes. The
// fold more changes no fold's fit: the predictions are those made without it, bit for bit.
TEST(StreamedEvaluationTest, TheWholeSetFitBesideTheFoldsIsTheStreamedFit) {
  testing::TempDir dir;
  const fs::path input = WriteCapture(dir / "capture");
  std::vector<Method> methods;
  for (const char* name : {"gradient", "ptm", "hsh9", "eigen6", "rbf", "bilinear"}) {
    methods.push_back(Method::Parse(name));
  }
  for (const bool robust : {false, true}) {
    StreamedSet set = OpenStreamedSet(input);
    StreamedPredictionOptions predict;
    predict.band_rows = 5;
    predict.hold_out_every = 4;
    StreamedFitOptions fit;
    fit.band_rows = 5;
    fit.robust = robust;
    fit.robust_options.loss = RobustLoss::kTukey;
    if (robust) predict.robust = fit.robust_options;
    std::vector<MethodEvaluation> alone(methods.size()), beside(methods.size());
    PredictStreamed(set, methods, alone, predict);

    std::vector<fs::path> fitted, whole_set;
    std::vector<std::unique_ptr<FittedStackWriter>> writers;
    for (const Method& method : methods) {
      const std::string name = fmt::format("{}{}.exr", robust ? "robust-" : "", method.Name());
      fitted.push_back(dir / ("fitted-" + name));
      whole_set.push_back(dir / ("beside-" + name));
      writers.push_back(std::make_unique<FittedStackWriter>(
          whole_set.back(), set.width(), set.height(), fit.compression, fit.provenance));
    }
    predict.whole_set_fit = [&](std::size_t i, int first_row, const Representation& band) {
      writers[i]->Write(first_row, band);
    };
    PredictStreamed(set, methods, beside, predict);
    for (auto& writer : writers) writer->Commit();
    FitStreamed(set, methods, fitted, fit);

    for (std::size_t i = 0; i < methods.size(); ++i) {
      const std::string label = fmt::format("{}{}", robust ? "robust " : "", methods[i].Name());
      EXPECT_EQ(beside[i].prediction_images, alone[i].prediction_images) << label;
      EXPECT_EQ(beside[i].prediction_per_image, alone[i].prediction_per_image) << label;
      EXPECT_EQ(beside[i].psnr_prediction_per_image, alone[i].psnr_prediction_per_image) << label;
      const LoadedStack streamed = LoadRepresentation(fitted[i]);
      const LoadedStack predicted = LoadRepresentation(whole_set[i]);
      EXPECT_TRUE(
          testing::SameBits(predicted.representation.maps(), streamed.representation.maps()))
          << label;
      EXPECT_EQ(predicted.representation.details(), streamed.representation.details()) << label;
      EXPECT_EQ(predicted.representation.method(), streamed.representation.method()) << label;
    }
  }
}

// pbr's folds stream as the robust ones do (its nonlinear fit per pixel starts from the robust
// photometric stereo of the band), with its robust options: the in-memory held-out prediction,
// bounds as above.
TEST(StreamedEvaluationTest, BandsGiveTheInMemoryPbrPrediction) {
  testing::TempDir dir;
  const fs::path input = WriteCapture(dir / "capture");
  const std::vector<Mask> measured = MeasuredPixelMasks(LoadPhotometricSet(input).set);
  EvaluationOptions in_memory;
  in_memory.hold_out_every = 4;
  in_memory.robust.emplace();
  in_memory.robust->measured = measured;
  try {
    ExpectStreamedPredictionMatches(input, {Method::Parse("pbr")}, in_memory);
  } catch (const Error& error) {
    // A build without Ceres (PHOTOMAT_WITH_CERES=OFF) has no pbr fit, and says so.
    if (std::string(error.what()).find("built without") != std::string::npos) {
      GTEST_SKIP() << error.what();
    }
    throw;
  }
}

TEST(StreamedEvaluationTest, PredictionRefusesWhatItCannotStream) {
  testing::TempDir dir;
  const fs::path input = WriteCapture(dir / "capture");
  StreamedSet set = OpenStreamedSet(input);
  std::vector<MethodEvaluation> one(1);
  // The neural basis is trained apart, on the set held whole.
  const std::vector<Method> neural = {Method::Parse("neural")};
  StreamedPredictionOptions robust;
  robust.robust.emplace();
  EXPECT_THAT([&] { PredictStreamed(set, neural, one, robust); },
              ThrowsMessage<Error>(HasSubstr("neural is trained on its own")));
  // Holding out every image but none: too few left for Gradient.
  const std::vector<Method> gradient = {Method::Parse("gradient")};
  StreamedPredictionOptions every;
  every.hold_out_every = 1;
  EXPECT_THAT([&] { PredictStreamed(set, gradient, one, every); },
              ThrowsMessage<Error>(HasSubstr("a prediction fold fits 0 images; gradient needs 3")));
  // The SSIM and colour difference are compared band by band for held-out images only.
  StreamedPredictionOptions leave_one_out;
  leave_one_out.appearance = true;
  EXPECT_THAT([&] { PredictStreamed(set, gradient, one, leave_one_out); },
              ThrowsMessage<Error>(HasSubstr("held-out images only")));
}

TEST(StreamedEvaluationTest, AStackOfAnotherSizeIsRefused) {
  testing::TempDir dir;
  const fs::path input = WriteCapture(dir / "capture");
  const auto other = testing::LambertianSet(SurfacePattern::kBumps, 16);
  SaveRepresentation(dir / "small.exr", Fit(other.set, Method::Parse("gradient")));
  StreamedSet set = OpenStreamedSet(input);
  StackBandReader stack(dir / "small.exr");
  EXPECT_THAT([&] { EvaluateStackStreamed(set, stack); },
              ThrowsMessage<Error>(HasSubstr("small.exr: a 16x16 stack of 3 channels cannot be "
                                             "evaluated against")));
}

}  // namespace
}  // namespace photomat
