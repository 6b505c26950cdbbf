// relight's web format against relight itself: folders photomat writes, relit by relight-cli -L,
// match photomat's relighting of the same folder, and folders relight-cli builds read and relight
// in photomat as relight-cli relights them. Needs relight-cli (PHOTOMAT_RELIGHT_CLI, or the build
// bench/peer_table leaves in ~/.cache/photomat-peers/relight-build); SKIPPED with the reason
// otherwise.

#include <fmt/format.h>
#include <gtest/gtest.h>

#include <cmath>
#include <cstdlib>
#include <fstream>
#include <optional>

#include "core/colour.h"
#include "core/image_io.h"
#include "relight/formats/relight_web_format.h"
#include "relight/formats/stack_file.h"
#include "tests/support/synthetic_sets.h"
#include "tests/support/test_support.h"

namespace photomat {
namespace {

namespace fs = std::filesystem;

std::optional<fs::path> RelightCli(std::string& why) {
  if (const char* path = std::getenv("PHOTOMAT_RELIGHT_CLI"); path && *path) {
    if (fs::exists(path)) return fs::path(path);
    why = fmt::format("PHOTOMAT_RELIGHT_CLI={} does not exist", path);
    return std::nullopt;
  }
  const char* home = std::getenv("HOME");
  const fs::path cached = fs::path(home ? home : "/") / ".cache/photomat-peers/relight-build" /
                          "relight-cli/relight-cli";
  if (fs::exists(cached)) return cached;
  why = fmt::format(
      "relight-cli not found: set PHOTOMAT_RELIGHT_CLI or build it with bench/peer_table "
      "(looked for {})",
      cached.string());
  return std::nullopt;
}

#define RELIGHT_CLI_OR_SKIP(var)          \
  std::string var##_why;                  \
  const auto var = RelightCli(var##_why); \
  if (!var) GTEST_SKIP() << var##_why

void RunCommand(const std::string& command, const fs::path& log) {
  const int status = std::system((command + " > " + log.string() + " 2>&1").c_str());
  std::ifstream in(log);
  const std::string output((std::istreambuf_iterator<char>(in)), {});
  ASSERT_EQ(status, 0) << command << "\n" << output;
}

// relight-cli's image of `folder` under `light`: its codes / 255.
Image RelightCliImage(const fs::path& cli, const fs::path& folder, const LightDirection& light,
                      const fs::path& work) {
  const fs::path png = work / "relit.png";
  RunCommand(fmt::format("{} -L {:.6f}:{:.6f}:{:.6f} -D {} {}", cli.string(), light.x(), light.y(),
                         light.z(), png.string(), folder.string()),
             work / "relight-cli.log");
  ImageReadOptions options;
  options.colour_space = ColourSpace::kLinear;  // the stored codes
  return ReadImage(png, options).image;
}

struct Agreement {
  double largest = 0;        // codes
  double mean = 0;           // codes
  std::size_t beyond_1 = 0;  // values more than 1 code apart
  double relight_mean = 0;   // relight-cli's mean code: the images are not blank
};

// relight truncates its float result to a byte (after clamping to 0..255): photomat's value is
// compared as floor(255 v), clamped.
Agreement Compare(const Image& relight, const Image& photomat) {
  Agreement a;
  const std::size_t pixels = photomat.pixel_count();
  double sum = 0;
  for (int c = 0; c < 3; ++c) {
    const auto theirs = relight.plane(c);
    const auto ours = photomat.plane(c);
    for (std::size_t p = 0; p < pixels; ++p) {
      const double expected = std::clamp(std::floor(255.0 * ours[p]), 0.0, 255.0);
      const double d = std::abs(255.0 * theirs[p] - expected);
      a.relight_mean += 255.0 * theirs[p] / (3.0 * pixels);
      a.largest = std::max(a.largest, d);
      sum += d;
      if (d > 1.5) ++a.beyond_1;
    }
  }
  a.mean = sum / (3.0 * pixels);
  return a;
}

std::vector<LightDirection> CrossCheckLights() {
  return {LightDirection::FromSlantTilt(0, 0), LightDirection::FromSlantTilt(35, 70),
          LightDirection::FromSlantTilt(60, 250)};
}

// Must show: a stack photomat writes, relit by relight-cli -L, matches photomat's relighting of
// it within relight's truncation to bytes. Measured (relight 5cca5c3e): identical to floor(255 v)
// at every value for ptm, hsh and rbf at the three lights, bilinear at slant 35 with a few values
// 1 code apart (float rounding at the truncation); the bound allows none more than 1 code apart.
TEST(RelightWebCrossCheckTest, RelightCliRelightsPhotomatFoldersAsPhotomatDoes) {
  RELIGHT_CLI_OR_SKIP(cli);
  const PhotometricSet set = testing::ShadowedSpecularSet(40).set;
  testing::TempDir dir;
  for (auto basis : {RelightWebBasis::kPtm, RelightWebBasis::kHsh, RelightWebBasis::kRbf,
                     RelightWebBasis::kBilinear}) {
    RelightWebOptions options;
    options.basis = basis;
    const fs::path folder = dir / std::string(ToString(basis));
    WriteRelightWeb(folder, RelightWebFromSet(set, options));
    const LoadedStack stack = LoadStackFile(folder);
    for (const auto& light : CrossCheckLights()) {
      const Agreement a = Compare(RelightCliImage(*cli, folder, light, dir.path()),
                                  stack.representation.Relight(light));
      std::cout << ToString(basis) << " at slant " << light.SlantDegrees() << ": largest "
                << a.largest << " codes, mean " << a.mean << "\n";
      EXPECT_EQ(a.beyond_1, 0u) << ToString(basis) << " largest " << a.largest;
      EXPECT_GT(a.relight_mean, 5.0) << ToString(basis);
    }
  }
}

// A folder relight-cli builds from photographs (8-bit sRGB JPEGs and an .lp file) opens in
// photomat and relights as relight-cli relights it, for each of the four bases. Measured:
// identical to floor(255 v) at every value, every basis and light.
TEST(RelightWebCrossCheckTest, PhotomatRelightsRelightCliFoldersAsRelightDoes) {
  RELIGHT_CLI_OR_SKIP(cli);
  const PhotometricSet set = testing::ShadowedSpecularSet(40).set;
  testing::TempDir dir;
  const fs::path photos = dir / "photos";
  fs::create_directories(photos);
  std::ofstream lp(photos / "lights.lp");
  lp << set.size() << "\n";
  for (int i = 0; i < set.size(); ++i) {
    const std::string name = fmt::format("img{:03d}.jpg", i);
    ImageWriteOptions options;
    options.sample_type = SampleType::kUint8;
    options.encoding = ColourSpace::kSrgb;
    WriteImage(photos / name, set.images()[i], options);
    const auto& l = set.lights()[i];
    lp << fmt::format("{} {:.6f} {:.6f} {:.6f}\n", name, l.x(), l.y(), l.z());
  }
  lp.close();
  struct Build {
    std::string arguments;
    std::string method;
  };
  for (const Build& build :
       {Build{"-b ptm -p 18", "ptm"}, Build{"-b hsh -p 27", "hsh9"},
        Build{"-b rbf -p 9", "relight-rbf"}, Build{"-b bilinear -p 9", "relight-bilinear"}}) {
    const fs::path folder = dir / build.method;
    RunCommand(fmt::format("{} {} {} {}", cli->string(), build.arguments, photos.string(),
                           folder.string()),
               dir / "build.log");
    const LoadedStack stack = LoadStackFile(folder);
    EXPECT_EQ(stack.representation.method(), build.method);
    for (const auto& light : CrossCheckLights()) {
      const Agreement a = Compare(RelightCliImage(*cli, folder, light, dir.path()),
                                  stack.representation.Relight(light));
      std::cout << build.method << " (relight-cli's) at slant " << light.SlantDegrees()
                << ": largest " << a.largest << " codes, mean " << a.mean
                << " (relight's mean code " << a.relight_mean << ")\n";
      EXPECT_EQ(a.beyond_1, 0u) << build.method << " largest " << a.largest;
      EXPECT_GT(a.relight_mean, 5.0) << build.method;
    }
  }
}

}  // namespace
}  // namespace photomat
