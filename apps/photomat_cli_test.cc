// End-to-end tests of the photomat command line: each runs the built executable.
#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include <cstring>
#include <fstream>
#include <iterator>
#include <string>
#include <vector>

#include "apps/command_table.h"
#include "capture/io/load_photometric_set.h"
#include "core/image_io.h"
#include "core/json_file.h"
#include "represent/stack/map_stack.h"
#include "tests/support/test_support.h"

namespace photomat {
namespace {

using testing::RunPhotomat;
using testing::RunResult;

using ::testing::HasSubstr;
using ::testing::Not;
using testing::TempDir;

TEST(PhotomatCliTest, GenerateFitRelightEvaluate) {
  TempDir dir;
  const std::string capture = (dir / "capture").string();
  testing::GenerateCapture(capture, "--size 40x32 --pattern bumps --seed 4");
  EXPECT_EQ(LoadPhotometricSet(capture).set.size(), 36);

  const RunResult fit = RunPhotomat("fit " + capture + " --method gradient,ptm,eigen6 --out " +
                                    (dir / "stacks").string());
  ASSERT_EQ(fit.exit_code, 0) << fit.output;
  EXPECT_TRUE(std::filesystem::exists(dir / "stacks" / "stacks.json"));
  const LoadedStack ptm = LoadRepresentation(dir / "stacks" / "ptm.exr");
  EXPECT_EQ(ptm.representation.maps().channels(), 18);

  const RunResult one =
      RunPhotomat("relight " + (dir / "stacks").string() +
                  " --method gradient --light 60,120 --out " + (dir / "g.png").string());
  ASSERT_EQ(one.exit_code, 0) << one.output;
  EXPECT_EQ(ReadImage(dir / "g.png").image.width(), 40);
  const RunResult bad_light =
      RunPhotomat("relight " + (dir / "stacks").string() +
                  " --method gradient --light 100,0 --out " + (dir / "bad.png").string());
  EXPECT_EQ(bad_light.exit_code, 1);
  EXPECT_EQ(bad_light.output, "photomat: error: \"100,0\": slant must be in [0, 90] degrees\n");
  EXPECT_FALSE(std::filesystem::exists(dir / "bad.png"));

  const RunResult sweep =
      RunPhotomat("relight " + (dir / "stacks" / "eigen6.exr").string() +
                  " --sweep 5,45 --format exr --out " + (dir / "sweep").string());
  ASSERT_EQ(sweep.exit_code, 0) << sweep.output;
  EXPECT_EQ(LoadPhotometricSet(dir / "sweep").set.size(), 5);

  const RunResult evaluate = RunPhotomat(
      "evaluate " + capture + " --methods 3i,gradient,eigen3 --json " + (dir / "e.json").string());
  ASSERT_EQ(evaluate.exit_code, 0) << evaluate.output;
  EXPECT_THAT(evaluate.output, HasSubstr("eta_reconstr."));
  const nlohmann::json json = ReadJsonFile(dir / "e.json");
  for (const char* method : {"3i", "gradient", "eigen3"}) {
    ASSERT_TRUE(json.contains(method)) << method;
    EXPECT_LT(json[method]["eta_reconstruction"].get<double>(), 1e-3);
    EXPECT_TRUE(json[method].contains("eta_prediction"));
  }
  // The manifest names its ground truth, so normals are scored without --gt-normals.
  EXPECT_LT(json["gradient"]["normals"]["mean_angular_error_deg"].get<double>(), 0.1);
  EXPECT_FALSE(json["eigen3"].contains("normals"));
}

TEST(PhotomatCliTest, FitWritesTheChosenLosslessExrCompression) {
  TempDir dir;
  const std::string capture = (dir / "capture").string();
  testing::GenerateCapture(capture, "--size 40x32 --pattern bumps --seed 5");
  // The default on a full frame (auto: none), rle, the smallest on real stacks (zip) and piz:
  // the same maps, bit for bit.
  std::vector<Image> maps;
  for (const char* compression : {"", "rle", "zip", "piz"}) {
    SCOPED_TRACE(compression);
    const std::filesystem::path out = dir / (std::string("fit_") + compression);
    const std::string option = *compression ? std::string(" --exr-compression ") + compression : "";
    const RunResult fit =
        RunPhotomat("fit " + capture + " --method ptm --out " + out.string() + option);
    ASSERT_EQ(fit.exit_code, 0) << fit.output;
    ImageReadOptions keep;
    keep.keep_alpha = true;
    const LoadedImage stored = ReadImage(out / "ptm.exr", keep);
    EXPECT_EQ(stored.info.attributes.at("compression"), *compression ? compression : "none");
    maps.push_back(LoadRepresentation(out / "ptm.exr").representation.maps());
  }
  for (std::size_t i = 1; i < maps.size(); ++i) {
    ASSERT_TRUE(maps[i].SameShape(maps[0]));
    EXPECT_EQ(std::memcmp(maps[i].values().data(), maps[0].values().data(),
                          maps[0].values().size() * sizeof(float)),
              0);
  }
  // With a mask, auto is rle: the zero background's runs compress.
  Mask mask(40, 32, true);
  for (int x = 0; x < 40; ++x) mask.Set(static_cast<std::size_t>(x), false);  // the first row
  WriteMask(dir / "capture" / "mask.png", mask);
  nlohmann::json manifest = ReadJsonFile(dir / "capture" / "manifest.json");
  manifest["mask"] = "mask.png";
  WriteJsonFile(dir / "capture" / "manifest.json", manifest);
  const std::filesystem::path masked = dir / "fit_masked";
  const RunResult masked_fit =
      RunPhotomat("fit " + capture + " --method ptm --out " + masked.string());
  ASSERT_EQ(masked_fit.exit_code, 0) << masked_fit.output;
  EXPECT_EQ(ReadImage(masked / "ptm.exr").info.attributes.at("compression"), "rle");
  const RunResult lossy = RunPhotomat("fit " + capture + " --method ptm --out " +
                                      (dir / "lossy").string() + " --exr-compression dwaa");
  EXPECT_EQ(lossy.exit_code, 1);
  EXPECT_EQ(lossy.output,
            "photomat: error: unknown EXR compression 'dwaa' (none, rle, zips, zip or piz)\n");
  EXPECT_FALSE(std::filesystem::exists(dir / "lossy"));
}

TEST(PhotomatCliTest, ErrorsAreOneLineAndNonZero) {
  const RunResult missing = RunPhotomat("fit /nonexistent/set --out /tmp/x");
  EXPECT_EQ(missing.exit_code, 1);
  EXPECT_EQ(missing.output, "photomat: error: /nonexistent/set: no such file or folder\n");
  TempDir dir;
  const RunResult method = RunPhotomat("fit " + dir.path().string() + " --method hsh --out /tmp/x");
  EXPECT_EQ(method.exit_code, 1);
  EXPECT_THAT(method.output, HasSubstr("unknown method \"hsh\""));
  // A valid light, so that the stack is what is wrong (the light is checked after the stack is
  // read: GenerateFitRelightEvaluate checks a bad light on a real stack).
  const RunResult stack = RunPhotomat("relight /nonexistent/stack.exr --light 40,0 --out y.png");
  EXPECT_EQ(stack.exit_code, 1);
  EXPECT_EQ(stack.output, "photomat: error: /nonexistent/stack.exr: no such map stack\n");
}

TEST(PhotomatCliTest, EverySubcommandHasHelp) {
  for (const char* command : {"generate", "fit", "relight", "evaluate", "demo"}) {
    const RunResult help = RunPhotomat(std::string(command) + " --help");
    EXPECT_EQ(help.exit_code, 0) << command;
    EXPECT_THAT(help.output, HasSubstr("Usage: photomat " + std::string(command))) << command;
  }
  EXPECT_NE(RunPhotomat("").exit_code, 0);  // a subcommand is required
}

// `photomat` runs every listed subcommand's program; one whose component this build left out stays
// listed and fails with one line that says what is missing and why (README "Optional
// components").
TEST(PhotomatCliTest, EveryListedCommandRunsOrSaysWhatThisBuildLacks) {
  const RunResult top = RunPhotomat("--help");
  ASSERT_EQ(top.exit_code, 0);
  for (const app::CommandInfo& command : app::Commands()) {
    const std::string name(command.name);
    EXPECT_THAT(top.output, HasSubstr("\n  " + name + " ")) << name;
    const RunResult help = RunPhotomat(name + " --help");
    if (!command.component || app::ComponentAbsence(*command.component).empty()) {
      EXPECT_EQ(help.exit_code, 0) << name << ": " << help.output;
      EXPECT_THAT(help.output, HasSubstr("Usage: photomat " + name)) << name;
    } else {
      EXPECT_EQ(help.exit_code, 1) << name;
      EXPECT_EQ(help.output, "photomat: error: " + app::BuiltWithout(*command.component) + "\n");
      EXPECT_THAT(help.output, HasSubstr("=OFF: ")) << name;
    }
  }
  // carve is part of `solid`, and needs meshes as well.
  if (app::ComponentAbsence(app::Component::kSolids).empty()) {
    const RunResult carve = RunPhotomat("solid carve --help");
    if (app::ComponentAbsence(app::Component::kCarving).empty()) {
      EXPECT_EQ(carve.exit_code, 0) << carve.output;
    } else {
      EXPECT_EQ(carve.exit_code, 1);
      EXPECT_THAT(carve.output, HasSubstr(app::BuiltWithout(app::Component::kCarving)));
    }
  }
}

std::string FileText(const std::filesystem::path& path) {
  std::ifstream in(path, std::ios::binary);
  return {std::istreambuf_iterator<char>(in), std::istreambuf_iterator<char>()};
}

TEST(PhotomatCliTest, DemoRunsTheWholePipeline) {
  TempDir dir;
  const RunResult demo = RunPhotomat("demo --size 32 --sweep 4 --out " + dir.path().string());
  ASSERT_EQ(demo.exit_code, 0) << demo.output;
  EXPECT_THAT(demo.output, HasSubstr("4/4 relight"));
  const nlohmann::json evaluation = ReadJsonFile(dir / "evaluation.json");
  EXPECT_EQ(evaluation.size(), 6u);
  EXPECT_EQ(LoadPhotometricSet(dir / "relit" / "eigen6").set.size(), 4);
  // The report and the viewer, and where to open them.
  EXPECT_THAT(demo.output, HasSubstr((dir / "report" / "index.html").string()));
  EXPECT_THAT(demo.output, HasSubstr("http.server --directory " + (dir / "viewer").string()));
  EXPECT_TRUE(std::filesystem::exists(dir / "report" / "images" / "normal-error-gradient.png"));
  const nlohmann::json viewer = ReadJsonFile(dir / "viewer" / "viewer.json");
  EXPECT_EQ(viewer["methods"].size(), 6u);
  EXPECT_EQ(viewer["capture_lights"].size(), 36u);
  EXPECT_TRUE(std::filesystem::exists(dir / "viewer" / "index.html"));
}

TEST(PhotomatCliTest, ExportWritesTheWebViewerOfAFitFolderAPtmFileOrASet) {
  TempDir dir;
  const std::string capture = (dir / "capture").string();
  const std::string stacks = (dir / "stacks").string();
  testing::GenerateCapture(capture, "--size 20x16 --seed 3");
  ASSERT_EQ(
      RunPhotomat("fit " + capture + " --method eigen3,ptm,gradient --out " + stacks).exit_code, 0);
  // Every stack of the fit folder, in photomat's method order, linear values.
  const RunResult all = RunPhotomat("export " + stacks + " --viewer " + (dir / "v1").string());
  ASSERT_EQ(all.exit_code, 0) << all.output;
  EXPECT_THAT(all.output, HasSubstr("http.server --directory " + (dir / "v1").string()));
  const nlohmann::json v1 = ReadJsonFile(dir / "v1" / "viewer.json");
  ASSERT_EQ(v1["methods"].size(), 3u);
  EXPECT_EQ(v1["methods"][0]["name"], "gradient");
  EXPECT_EQ(v1["methods"][1]["name"], "ptm");
  EXPECT_EQ(v1["methods"][2]["name"], "eigen3");
  EXPECT_EQ(v1["methods"][1]["values"], "linear");
  EXPECT_EQ(v1["capture_lights"].size(), 36u);
  // Published: the title is the input's name, and no file names the machine's folders.
  EXPECT_EQ(v1["title"], "stacks");
  EXPECT_THAT(FileText(dir / "v1" / "viewer.json"), Not(HasSubstr(dir.path().string())));
  EXPECT_THAT(FileText(dir / "v1" / "index.html"), Not(HasSubstr(dir.path().string())));

  // A .ptm file holds display codes: the viewer is told so, as `relight` decodes them.
  const std::string ptm = (dir / "x.ptm").string();
  ASSERT_EQ(RunPhotomat("export " + stacks + " --method ptm --ptm " + ptm).exit_code, 0);
  ASSERT_EQ(RunPhotomat("export " + ptm + " --viewer " + (dir / "v2").string()).exit_code, 0);
  const nlohmann::json v2 = ReadJsonFile(dir / "v2" / "viewer.json");
  ASSERT_EQ(v2["methods"].size(), 1u);
  EXPECT_EQ(v2["methods"][0]["values"], "srgb");

  // A photometric set: the --method fit (or every method's).
  const RunResult set =
      RunPhotomat("export " + capture + " --method gradient --viewer " + (dir / "v3").string());
  ASSERT_EQ(set.exit_code, 0) << set.output;
  EXPECT_EQ(ReadJsonFile(dir / "v3" / "viewer.json")["methods"].size(), 1u);
}

TEST(PhotomatCliTest, NeuralTrainingRunsInItsOwnProgram) {
  const std::vector<std::string> neural = {"fit", "in", "--method", "neural", "--out", "o"};
  const std::vector<std::string> ptm = {"fit", "in", "--method", "ptm", "--out", "o"};
  const std::vector<std::string> equals = {"fit", "in", "--method=neural"};
  auto program = [](const std::vector<std::string>& words) {
    std::vector<char*> arguments;
    for (const std::string& word : words) arguments.push_back(const_cast<char*>(word.c_str()));
    return std::string(app::FindCommandFor(arguments)->program);
  };
  EXPECT_EQ(program(neural), "photomat-neural");
  EXPECT_EQ(program(equals), "photomat-neural");
  EXPECT_EQ(program(ptm), "photomat-pipeline");
  EXPECT_EQ(program({"evaluate", "in", "--methods", "neural", "--hold-out-every", "4"}),
            "photomat-neural");
  EXPECT_EQ(program({"evaluate", "in", "--methods", "ptm,neural"}), "photomat-pipeline");
  EXPECT_EQ(program({"relight", "s.exr", "--method", "neural"}), "photomat-pipeline");
}

// `fit --method neural` trains (tiny here), and the stack relights like every method's.
TEST(PhotomatCliTest, NeuralFitsAndRelightsOrSaysWhatThisBuildLacks) {
  TempDir dir;
  const std::string capture = (dir / "capture").string();
  const std::string stacks = (dir / "stacks").string();
  testing::GenerateCapture(capture, "--size 12x10 --seed 4");
  const RunResult fit = RunPhotomat("fit " + capture + " --method neural --neural-k 4 " +
                                    "--neural-epochs 2 --seed 3 --out " + stacks);
  if (!app::ComponentAbsence(app::Component::kNeural).empty()) {
    EXPECT_EQ(fit.exit_code, 1);
    EXPECT_THAT(fit.output, HasSubstr(app::BuiltWithout(app::Component::kNeural)));
    return;
  }
  ASSERT_EQ(fit.exit_code, 0) << fit.output;
  const LoadedStack neural = LoadRepresentation(dir / "stacks" / "neural.exr");
  EXPECT_EQ(neural.representation.maps().channels(), 4);
  EXPECT_EQ(neural.representation.shading()->kind(), "neural");
  EXPECT_EQ(neural.representation.details()["neural"]["seed"], 3);
  const RunResult relit = RunPhotomat("relight " + stacks + " --method neural --sweep 3 --out " +
                                      (dir / "relit").string());
  ASSERT_EQ(relit.exit_code, 0) << relit.output;
  EXPECT_EQ(LoadPhotometricSet(dir / "relit").set.size(), 3);
  const RunResult evaluate = RunPhotomat("evaluate " + capture + " --methods neural " +
                                         "--hold-out-every 6 --neural-k 4 --neural-epochs 2 " +
                                         "--json " + (dir / "e.json").string());
  ASSERT_EQ(evaluate.exit_code, 0) << evaluate.output;
  const nlohmann::json e = ReadJsonFile(dir / "e.json");
  EXPECT_EQ(e["neural"]["prediction_images"].size(), 6u);
  EXPECT_GT(e["neural"]["eta_prediction"].get<double>(), 0.0);
  // How the predictions look, as for every method in memory (a two-epoch training: far from 1).
  EXPECT_EQ(e["neural"]["ssim_prediction_per_image"].size(), 6u);
  EXPECT_EQ(e["neural"]["delta_e2000_prediction_per_image"].size(), 6u);
  EXPECT_LT(e["neural"]["ssim_prediction"].get<double>(), 1.0);
  EXPECT_GT(e["neural"]["delta_e2000_prediction"].get<double>(), 0.0);
  // The training's options and summary travel with the score.
  EXPECT_EQ(e["neural"]["neural"]["max_epochs"], 2);
  EXPECT_EQ(e["neural"]["neural_training"]["epochs"], 2);
  EXPECT_THAT(evaluate.output, HasSubstr("trained 2 epochs"));
  const RunResult mixed =
      RunPhotomat("fit " + capture + " --method ptm,neural --out " + (dir / "mixed").string());
  EXPECT_EQ(mixed.exit_code, 1);
  EXPECT_THAT(mixed.output, HasSubstr("neural is trained on its own"));
}

TEST(PhotomatCliTest, RbfAndBilinearFitRelightAndExportLikeEveryMethod) {
  TempDir dir;
  const std::string capture = (dir / "capture").string();
  const std::string stacks = (dir / "stacks").string();
  testing::GenerateCapture(capture, "--size 20x16 --seed 4");
  const RunResult fit = RunPhotomat("fit " + capture + " --method rbf,bilinear --planes 5 " +
                                    "--rbf-width 20 --grid-size 8 --out " + stacks);
  ASSERT_EQ(fit.exit_code, 0) << fit.output;
  const LoadedStack rbf = LoadRepresentation(dir / "stacks" / "rbf.exr");
  EXPECT_EQ(rbf.representation.layout().basis_size, 5);
  EXPECT_EQ(rbf.representation.details()["rbf"]["width_deg"], 20.0);
  EXPECT_EQ(rbf.representation.details()["rbf"]["width_from"], "option");
  EXPECT_EQ(rbf.representation.details()["rbf"]["regularisation_from"], "leave-one-out");
  const LoadedStack bilinear = LoadRepresentation(dir / "stacks" / "bilinear.exr");
  EXPECT_EQ(bilinear.representation.basis().ToJson()["grid_size"], 8);
  const RunResult relit = RunPhotomat("relight " + stacks + " --method bilinear --sweep 3 --out " +
                                      (dir / "relit").string());
  ASSERT_EQ(relit.exit_code, 0) << relit.output;
  EXPECT_EQ(LoadPhotometricSet(dir / "relit").set.size(), 3);
  // The viewer has no formula for these bases: they go through its coefficient table.
  const RunResult viewer = RunPhotomat("export " + stacks + " --viewer " + (dir / "v").string());
  ASSERT_EQ(viewer.exit_code, 0) << viewer.output;
  const nlohmann::json v = ReadJsonFile(dir / "v" / "viewer.json");
  ASSERT_EQ(v["methods"].size(), 2u);
  for (const auto& method : v["methods"]) EXPECT_EQ(method["basis"]["kind"], "table");
  const RunResult bad =
      RunPhotomat("fit " + capture + " --method rbf --rbf-width 0 --out " + (dir / "bad").string());
  EXPECT_NE(bad.exit_code, 0);
}

TEST(PhotomatCliTest, EvaluateWritesAReportOfTheChosenImages) {
  TempDir dir;
  const std::string capture = (dir / "capture").string();
  testing::GenerateCapture(capture, "--size 20x16 --seed 2");
  const RunResult evaluate =
      RunPhotomat("evaluate " + capture + " --methods gradient,ptm --no-prediction --report " +
                  (dir / "report").string() + " --report-images 1,35");
  ASSERT_EQ(evaluate.exit_code, 0) << evaluate.output;
  EXPECT_THAT(evaluate.output, HasSubstr((dir / "report" / "index.html").string()));
  const nlohmann::json report = ReadJsonFile(dir / "report" / "report.json");
  EXPECT_EQ(report["images_shown"], nlohmann::json({1, 35}));
  EXPECT_TRUE(std::filesystem::exists(dir / "report" / "images" / "relit-ptm-35.png"));
  EXPECT_EQ(report["source"], "capture");
  EXPECT_EQ(report["title"], "photomat evaluation of capture");
  EXPECT_THAT(FileText(dir / "report" / "report.json"), Not(HasSubstr(dir.path().string())));
  EXPECT_THAT(FileText(dir / "report" / "index.html"), Not(HasSubstr(dir.path().string())));

  const RunResult bad = RunPhotomat("evaluate " + capture + " --methods gradient --no-prediction " +
                                    "--report " + (dir / "r2").string() + " --report-images 1,x");
  EXPECT_EQ(bad.exit_code, 1);
  EXPECT_THAT(bad.output, HasSubstr("expected image indices"));
  const RunResult outside =
      RunPhotomat("evaluate " + capture + " --methods gradient " + "--no-prediction --report " +
                  (dir / "r3").string() + " --report-images 36");
  EXPECT_EQ(outside.exit_code, 1);
  EXPECT_THAT(outside.output, HasSubstr("image 36 is not in the set"));
  EXPECT_FALSE(std::filesystem::exists(dir / "r3"));
}

}  // namespace
}  // namespace photomat
