// End-to-end tests of `photomat calibrate ...` and of `fit --robust` / `evaluate --robust`: each
// runs the built executable.
#include <fmt/format.h>
#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include "calibrate/lights/light_list.h"
#include "calibrate/radiometry/near_light.h"
#include "calibrate/testing/synthetic_calibration.h"
#include "capture/io/capture_manifest.h"
#include "capture/io/load_photometric_set.h"
#include "capture/io/lp_file.h"
#include "core/atomic_file.h"
#include "core/image_io.h"
#include "core/json_file.h"
#include "tests/support/test_support.h"

namespace photomat {
namespace {

using testing::RunPhotomat;
using testing::RunResult;

namespace fs = std::filesystem;
using ::testing::HasSubstr;
using testing::TempDir;

// A folder of 16-bit sphere images (sphere_0.png .. sphere_N.png, so that natural order matters)
// with an anti-aliased mask, and the true lights as a count + "x y z" list.
std::vector<LightDirection> WriteSphereFolder(const fs::path& folder) {
  std::vector<LightDirection> lights;
  for (int k = 0; k < 12; ++k)
    lights.push_back(LightDirection::FromSlantTilt(25 + 3 * (k % 4), 30.0 * k));
  MirrorSphereRenderOptions options;
  options.width = 160;
  options.height = 120;
  options.sphere = {Eigen::Vector2d(81.3, 58.9), 48.0};
  options.supersampling = 3;
  const MirrorSphereRender render = RenderMirrorSphere(lights, options);
  fs::create_directories(folder);
  ImageWriteOptions sixteen;
  sixteen.sample_type = SampleType::kUint16;
  std::string list = "12\n";
  for (std::size_t i = 0; i < lights.size(); ++i) {
    WriteImage(folder / fmt::format("sphere_{}.png", i), render.images[i], sixteen);
    list += fmt::format("{} {} {}\n", lights[i].x(), lights[i].y(), lights[i].z());
  }
  ImageWriteOptions eight;
  eight.sample_type = SampleType::kUint8;
  WriteImage(folder / "sphere_mask.png", render.coverage, eight);
  testing::WriteFile(folder.parent_path() / "true_lights.txt", list);
  return lights;
}

TEST(CalibrateCliTest, LightsFromASphereFolderWriteLpManifestAndReport) {
  TempDir dir;
  const std::vector<LightDirection> truth = WriteSphereFolder(dir / "sphere");
  const RunResult run = RunPhotomat("calibrate lights " + (dir / "sphere").string() + " --out " +
                                    (dir / "out" / "lights.lp").string() + " --reference " +
                                    (dir / "true_lights.txt").string());
  ASSERT_EQ(run.exit_code, 0) << run.output;
  EXPECT_THAT(run.output, HasSubstr("angular difference to the reference: mean 0."));
  const auto entries = ReadLpFile(dir / "out" / "lights.lp");
  ASSERT_EQ(entries.size(), 12u);
  for (std::size_t i = 0; i < entries.size(); ++i) {
    EXPECT_EQ(entries[i].image, fmt::format("../sphere/sphere_{}.png", i));  // natural order
    EXPECT_LT(entries[i].light.AngleToDegrees(truth[i]), 1.0) << i;
  }
  // The manifest form loads as a photometric set (the sphere images under their lights).
  const LoadedSet manifest = LoadPhotometricSet(dir / "out" / "lights.json");
  EXPECT_EQ(manifest.set.size(), 12);
  EXPECT_LT(manifest.set.light(5).AngleToDegrees(truth[5]), 1.0);
  const std::string svg = ReadTextFile(dir / "out" / "lights_report.svg");
  EXPECT_THAT(svg, HasSubstr("<svg"));
  const nlohmann::json report = ReadJsonFile(dir / "out" / "lights_report.json");
  EXPECT_LT(report["angle_deg"]["mean"].get<double>(), 0.5);
  EXPECT_EQ(report["lights"].size(), 12u);
}

TEST(CalibrateCliTest, AFailingSphereImageIsNamed) {
  TempDir dir;
  WriteSphereFolder(dir / "sphere");
  WriteImage(dir / "sphere" / "sphere_7.png", Image(160, 120, 3));  // black: no highlight
  const RunResult run = RunPhotomat("calibrate lights " + (dir / "sphere").string() + " --out " +
                                    (dir / "lights.lp").string());
  EXPECT_EQ(run.exit_code, 1);
  EXPECT_THAT(run.output,
              HasSubstr("1 of 12 sphere images failed: sphere_7.png: highlight too weak"));
  EXPECT_FALSE(fs::exists(dir / "lights.lp"));
}

TEST(CalibrateCliTest, ApplyNearLightsThenFitImprovesNormals) {
  TempDir dir;
  SyntheticMaterialOptions material_options;
  material_options.width = material_options.height = 48;
  const SyntheticMaterial material = MakeSyntheticMaterial(material_options);
  std::vector<NearLight> lamps;
  std::string lamp_file;
  for (const LightDirection& direction : ThesisLightGrid()) {
    NearLight lamp;
    lamp.position = 96.0 * direction.vector();
    lamp.intensity = lamp.position.squaredNorm();
    lamps.push_back(lamp);
    lamp_file += fmt::format("{} {} {} {}\n", lamp.position.x(), lamp.position.y(),
                             lamp.position.z(), lamp.intensity);
  }
  SaveSetOptions exr;
  exr.sample_type = SampleType::kFloat;
  WriteSyntheticCapture(dir / "near", material, RenderNearLightCapture(material, lamps), exr);
  testing::WriteFile(dir / "lamps.txt", lamp_file);
  const RunResult apply =
      RunPhotomat("calibrate apply " + (dir / "near").string() + " --near-lights " +
                  (dir / "lamps.txt").string() + " --out " + (dir / "corrected").string());
  ASSERT_EQ(apply.exit_code, 0) << apply.output;
  const auto error = [&](const fs::path& set) {
    const RunResult run =
        RunPhotomat("evaluate " + set.string() + " --methods gradient --no-prediction --json " +
                    (dir / "e.json").string());
    EXPECT_EQ(run.exit_code, 0) << run.output;
    return ReadJsonFile(dir / "e.json")["gradient"]["normals"]["mean_angular_error_deg"]
        .get<double>();
  };
  const double before = error(dir / "near"), after = error(dir / "corrected");
  EXPECT_GT(before, 5.0 * after) << before << " " << after;
}

TEST(CalibrateCliTest, FitAndEvaluateRobust) {
  TempDir dir;
  const std::string capture = (dir / "capture").string();
  ASSERT_EQ(RunPhotomat("generate --out " + capture +
                        " --size 40x40 --relief 50 --shadows --specular 0.4 --seed 3")
                .exit_code,
            0);
  const RunResult fit = RunPhotomat("fit " + capture +
                                    " --method gradient,ptm,eigen3 --robust "
                                    "--loss tukey --out " +
                                    (dir / "stacks").string());
  ASSERT_EQ(fit.exit_code, 0) << fit.output;
  EXPECT_THAT(fit.output, HasSubstr("robust fit:"));
  EXPECT_TRUE(fs::exists(dir / "stacks" / "eigen3.exr"));
  const auto normals_error = [&](const std::string& flags) {
    const RunResult run =
        RunPhotomat("evaluate " + capture + " --methods gradient --no-prediction " + flags +
                    " --json " + (dir / "e.json").string());
    EXPECT_EQ(run.exit_code, 0) << run.output;
    return ReadJsonFile(dir / "e.json")["gradient"]["normals"]["mean_angular_error_deg"]
        .get<double>();
  };
  EXPECT_LT(normals_error("--robust"), 0.5 * normals_error(""));
  EXPECT_EQ(
      RunPhotomat("fit " + capture + " --robust --loss l1 --out " + (dir / "x").string()).exit_code,
      1);
}

TEST(CalibrateCliTest, FlatFieldFromATargetMakesItUniform) {
  TempDir dir;
  // A flat target and a sample under the same near lamps; the flat-field from the target.
  std::vector<NearLight> lamps;
  for (const LightDirection& direction : ThesisLightGrid()) {
    NearLight lamp;
    lamp.position = 80.0 * direction.vector();
    lamp.intensity = lamp.position.squaredNorm();
    lamps.push_back(lamp);
  }
  SaveSetOptions exr;
  exr.sample_type = SampleType::kFloat;
  SavePhotometricSet(dir / "target", RenderNearLightTarget(40, 40, lamps), exr);
  ASSERT_EQ(RunPhotomat("calibrate flatfield " + (dir / "target").string() + " --out " +
                        (dir / "ff").string())
                .exit_code,
            0);
  EXPECT_TRUE(fs::exists(dir / "ff" / "flatfield.json"));
  const RunResult applied =
      RunPhotomat("calibrate apply " + (dir / "target").string() + " --flat-field " +
                  (dir / "ff").string() + " --out " + (dir / "flat").string());
  ASSERT_EQ(applied.exit_code, 0) << applied.output;
  const LoadedSet flat = LoadPhotometricSet(dir / "flat");
  const Image& image = flat.set.image(20);
  EXPECT_NEAR(image.at(0, 0, 1) / image.at(39, 39, 1), 1.0, 0.01);  // uniform after the gains
}

TEST(CalibrateCliTest, SemiCalibratedIntensities) {
  TempDir dir;
  SaveSetOptions exr;
  exr.sample_type = SampleType::kFloat;
  // A set whose lights alternate between two brightnesses.
  SyntheticMaterialOptions material_options;
  material_options.width = material_options.height = 32;
  const SyntheticMaterial material = MakeSyntheticMaterial(material_options);
  PhotometricSet equal = RenderSyntheticCapture(material, ThesisLightGrid());
  std::vector<Image> images = equal.images();
  for (std::size_t i = 0; i < images.size(); ++i) {
    for (float& v : images[i].values()) v *= i % 2 ? 1.5f : 0.5f;
  }
  SavePhotometricSet(dir / "uneven", PhotometricSet(images, equal.lights()), exr);
  ASSERT_EQ(RunPhotomat("calibrate intensities " + (dir / "uneven").string() + " --out " +
                        (dir / "intensities.txt").string())
                .exit_code,
            0);
  const auto intensities = ReadLightIntensities(dir / "intensities.txt");
  ASSERT_EQ(intensities.size(), 36u);
  EXPECT_NEAR(intensities[1][0] / intensities[0][0], 3.0, 0.03);
}

TEST(CalibrateCliTest, ResponseCurveFromAnExposureSeries) {
  TempDir dir;
  // A response curve from an exposure series of a gamma-2.2 camera.
  std::string files, times;
  for (int k = 0; k < 5; ++k) {
    const double t = 0.25 * (1 << k);
    Image exposure(48, 32, 3);
    for (int y = 0; y < 32; ++y) {
      for (int x = 0; x < 48; ++x) {
        const double radiance = 0.03 * std::pow(30.0, (x + 48.0 * (y % 4)) / 192.0);
        for (int c = 0; c < 3; ++c) {
          exposure.at(x, y, c) = static_cast<float>(std::pow(std::min(1.0, radiance * t), 1 / 2.2));
        }
      }
    }
    ImageWriteOptions eight;
    eight.sample_type = SampleType::kUint8;
    const fs::path file = dir / fmt::format("exposure_{}.png", k);
    WriteImage(file, exposure, eight);
    files += fmt::format(" {}", file.string());
    times += fmt::format("{}{}", k ? "," : "", t);
  }
  const RunResult response = RunPhotomat("calibrate response" + files + " --times " + times +
                                         " --out " + (dir / "response.json").string());
  ASSERT_EQ(response.exit_code, 0) << response.output;
  EXPECT_EQ(ReadJsonFile(dir / "response.json")["format"], "photomat-response");
  EXPECT_EQ(
      RunPhotomat("calibrate response" + files + " --times 1,2 --out " + (dir / "r.json").string())
          .exit_code,
      1);
}

TEST(CalibrateCliTest, EveryCalibrateSubcommandHasHelp) {
  for (const char* command : {"lights", "flatfield", "intensities", "response", "apply"}) {
    const RunResult help = RunPhotomat(fmt::format("calibrate {} --help", command));
    EXPECT_EQ(help.exit_code, 0) << command;
    EXPECT_THAT(help.output, HasSubstr(fmt::format("Usage: photomat calibrate {}", command)))
        << command;
  }
  EXPECT_NE(RunPhotomat("calibrate").exit_code, 0);
}

// The University of Washington chrome sphere through the command line, compared with the
// lights.txt shipped beside it.
TEST(CalibrateCliTest, UwChromeSphere) {
  PHOTOMAT_TEST_DATA_OR_SKIP(data, "uw-psm");
  TempDir dir;
  const RunResult run =
      RunPhotomat("calibrate lights " + (data / "chrome").string() + " --out " +
                  (dir / "lights.lp").string() + " --reference " + (data / "lights.txt").string() +
                  " --images-for " + (data / "cat").string());
  ASSERT_EQ(run.exit_code, 0) << run.output;
  const auto entries = ReadLpFile(dir / "lights.lp");
  ASSERT_EQ(entries.size(), 12u);
  EXPECT_THAT(entries[10].image, HasSubstr("cat.10.png"));
  EXPECT_LT(ReadJsonFile(dir / "lights_report.json")["angle_deg"]["mean"].get<double>(), 3.5);
  // The sample under the calibrated lights loads and fits.
  EXPECT_EQ(RunPhotomat("fit " + (dir / "lights.lp").string() + " --method gradient --out " +
                        (dir / "stacks").string())
                .exit_code,
            0);
}

}  // namespace
}  // namespace photomat
