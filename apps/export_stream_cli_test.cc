// `photomat export` of a photometric set streams (README, "Streamed relighting and export",
// "From the photographs"): the set is fitted in bands into scratch stacks, exported from them and
// the scratch removed. These run the built executable.
#include <fmt/format.h>
#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <functional>
#include <string>
#include <vector>

#include "core/atomic_file.h"
#include "core/image_io.h"
#include "core/json_file.h"
#include "relight/formats/compact_stack.h"
#include "relight/formats/ptm_file.h"
#include "relight/formats/relight_web_format.h"
#include "relight/formats/rti_file.h"
#include "tests/support/layouts.h"
#include "tests/support/test_support.h"

namespace photomat {
namespace {

namespace fs = std::filesystem;

using ::testing::HasSubstr;
using ::testing::Not;
using testing::RunPhotomat;
using testing::RunResult;
using testing::TempDir;

// How two files' quantised planes differ: the largest difference of a byte, and the fraction of
// bytes that differ.
struct PlaneDifference {
  int largest = 0;
  double fraction = 0.0;
};

PlaneDifference ComparePlanes(const std::vector<std::vector<std::uint8_t>>& a,
                              const std::vector<std::vector<std::uint8_t>>& b) {
  EXPECT_EQ(a.size(), b.size());
  PlaneDifference difference;
  std::size_t differing = 0, total = 0;
  for (std::size_t p = 0; p < std::min(a.size(), b.size()); ++p) {
    EXPECT_EQ(a[p].size(), b[p].size());
    for (std::size_t i = 0; i < std::min(a[p].size(), b[p].size()); ++i) {
      const int d = std::abs(static_cast<int>(a[p][i]) - static_cast<int>(b[p][i]));
      difference.largest = std::max(difference.largest, d);
      differing += d != 0 ? 1 : 0;
      ++total;
    }
  }
  difference.fraction = total > 0 ? static_cast<double>(differing) / static_cast<double>(total) : 0;
  return difference;
}

// The streamed .ptm against the in-memory one: the same header to float rounding and the same
// bytes but for a rare one-code step (the fits round by band, README "From the photographs").
void ExpectSamePtm(const fs::path& streamed_path, const fs::path& whole_path) {
  const PtmFile streamed = ReadPtmFile(streamed_path), whole = ReadPtmFile(whole_path);
  EXPECT_EQ(streamed.format, whole.format);
  EXPECT_EQ(streamed.width, whole.width);
  EXPECT_EQ(streamed.height, whole.height);
  for (std::size_t j = 0; j < whole.scale.size(); ++j) {
    EXPECT_NEAR(streamed.scale[j], whole.scale[j], 1e-4 * std::abs(whole.scale[j])) << j;
    EXPECT_NEAR(streamed.bias[j], whole.bias[j], 1) << j;
  }
  const PlaneDifference difference = ComparePlanes(streamed.planes, whole.planes);
  std::printf("%s vs in memory: largest byte difference %d, %.3g%% of the bytes differ\n",
              streamed_path.filename().c_str(), difference.largest, 100 * difference.fraction);
  // Measured: identical files (no byte differs) at 96 x 80 in bands of 1 row and at 1536 x 1536
  // in bands of 36. The bounds allow what float rounding by band can make (README "From the
  // photographs"): one-code steps, each needing a coefficient within rounding of a quantisation
  // boundary, on at most 0.1 % of the bytes.
  EXPECT_LE(difference.largest, 1);
  EXPECT_LE(difference.fraction, 0.001);
}

void ExpectSameRti(const fs::path& streamed_path, const fs::path& whole_path) {
  const RtiFile streamed = ReadRtiFile(streamed_path), whole = ReadRtiFile(whole_path);
  EXPECT_EQ(streamed.terms, whole.terms);
  EXPECT_EQ(streamed.width, whole.width);
  EXPECT_EQ(streamed.height, whole.height);
  ASSERT_EQ(streamed.scale.size(), whole.scale.size());
  for (std::size_t j = 0; j < whole.scale.size(); ++j) {
    EXPECT_NEAR(streamed.scale[j], whole.scale[j], 1e-4 * std::abs(whole.scale[j])) << j;
    EXPECT_NEAR(streamed.bias[j], whole.bias[j], 1e-4 * std::abs(whole.scale[j])) << j;
  }
  const PlaneDifference difference = ComparePlanes(streamed.planes, whole.planes);
  std::printf("%s vs in memory: largest byte difference %d, %.3g%% of the bytes differ\n",
              streamed_path.filename().c_str(), difference.largest, 100 * difference.fraction);
  EXPECT_LE(difference.largest, 1);  // as ExpectSamePtm
  EXPECT_LE(difference.fraction, 0.001);
}

// The 96 x 80 capture of bumps `dir`/capture exported in memory into `dir`/whole and streamed in
// bands of a few rows (--stream --memory 1) into `dir`/streamed, the outputs those of `files`
// for each folder.
struct InMemoryAndStreamed {
  RunResult whole;
  RunResult streamed;
};
InMemoryAndStreamed ExportInMemoryAndStreamed(
    const TempDir& dir, const std::function<std::string(const std::string&)>& files) {
  const std::string capture =
      testing::GenerateCapture(dir / "capture", "--size 96x80 --pattern bumps --seed 8");
  fs::create_directories(dir / "whole");
  fs::create_directories(dir / "streamed");
  InMemoryAndStreamed runs{
      RunPhotomat("export " + capture + files("whole")),
      RunPhotomat("export " + capture + " --stream --memory 1" + files("streamed"))};
  std::printf("%s", runs.streamed.output.c_str());
  return runs;
}

// A set exported streamed, in bands of a few rows (--stream, --memory 1), writes what the
// in-memory export writes: .ptm (LRGB) and .rti (HSH9) to within one code, the normal and albedo
// maps to float rounding; and leaves no scratch folder.
TEST(ExportStreamCliTest, ASetExportedStreamedEqualsTheInMemoryExport) {
  const TempDir dir;
  const auto [whole, streamed] = ExportInMemoryAndStreamed(dir, [&](const std::string& folder) {
    return " --ptm " + (dir / folder / "c.ptm").string() + " --rti " +
           (dir / folder / "c.rti").string() + " --out " + (dir / folder / "maps").string();
  });
  ASSERT_EQ(whole.exit_code, 0) << whole.output;
  EXPECT_THAT(whole.output, Not(HasSubstr("streamed")));
  ASSERT_EQ(streamed.exit_code, 0) << streamed.output;
  // Two passes over the photographs, each in several bands: the encoded PTM and HSH fits, then
  // the linear Gradient fit.
  EXPECT_THAT(streamed.output, HasSubstr("fitted ptm-lrgb, hsh9 to the 36 photographs "
                                         "(sRGB-encoded) in bands of"));
  EXPECT_THAT(streamed.output, HasSubstr("fitted gradient to the 36 photographs (linear)"));
  EXPECT_THAT(streamed.output, Not(HasSubstr("bands of 80 of 80 rows")));
  EXPECT_THAT(streamed.output, HasSubstr("height by tiled Poisson"));
  ExpectSamePtm(dir / "streamed" / "c.ptm", dir / "whole" / "c.ptm");
  ExpectSameRti(dir / "streamed" / "c.rti", dir / "whole" / "c.rti");
  for (const char* map : {"normal.png", "albedo.png"}) {
    const Image a = ReadImage(dir / "streamed" / "maps" / map).image;
    const Image b = ReadImage(dir / "whole" / "maps" / map).image;
    ASSERT_TRUE(a.SameShape(b)) << map;
    const double difference = testing::LargestDifferenceOverLargestValue(a, b);
    std::printf("%s vs in memory: %.3g of the largest value\n", map, difference);
    // 16-bit PNGs of the same fit to float rounding (measured: 0): at most one code apart.
    EXPECT_LE(difference, 1.5 / 65535) << map;
  }
  EXPECT_TRUE(ReadJsonFile(dir / "streamed" / "maps" / "export.json").contains("streamed"));
  // Nothing else beside the outputs: the scratch stacks are gone.
  EXPECT_THAT(testing::EntriesOf(dir / "streamed"),
              ::testing::ElementsAre("c.ptm", "c.rti", "maps"));
}

// A photograph truncated part-way: the streamed export fails naming it and leaves no .ptm, no
// maps and no scratch folder.
TEST(ExportStreamCliTest, AnImageTruncatedMidwayFailsNamingItAndLeavesNothing) {
  const TempDir dir;
  const std::string capture = (dir / "capture").string();
  testing::GenerateCapture(capture, "--size 64x256 --seed 6");
  const fs::path victim = dir / "capture" / "img_030.png";
  fs::resize_file(victim, fs::file_size(victim) / 2);
  fs::create_directories(dir / "out");
  const RunResult exported =
      RunPhotomat("export " + capture + " --stream --memory 1 --ptm " +
                  (dir / "out" / "c.ptm").string() + " --out " + (dir / "out" / "maps").string());
  EXPECT_EQ(exported.exit_code, 1) << exported.output;
  EXPECT_THAT(exported.output, HasSubstr("img_030.png"));
  EXPECT_TRUE(testing::EntriesOf(dir / "out").empty()) << exported.output;
  // relight's rbf planes, read from the photographs themselves: the same.
  const RunResult rbf =
      RunPhotomat("export " + capture + " --stream --memory 1 --relight-basis rbf --relight-web " +
                  (dir / "out" / "web").string());
  EXPECT_EQ(rbf.exit_code, 1) << rbf.output;
  EXPECT_THAT(rbf.output, HasSubstr("img_030.png"));
  EXPECT_TRUE(testing::EntriesOf(dir / "out").empty()) << rbf.output;
}

// What is made from a whole stack (relight's ptm planes and their ranges, the compact form's PCA,
// the maps with --height fc, a whole-map FFT) is made, streamed, from the one scratch stack
// fitted in bands, loaded whole: the in-memory export's files to within one code (measured: the
// same bytes), and no scratch left.
TEST(ExportStreamCliTest, WholeStackExportsOfASetComeFromItsScratchStack) {
  const TempDir dir;
  const auto [whole, streamed] = ExportInMemoryAndStreamed(dir, [&](const std::string& folder) {
    return " --relight-web " + (dir / folder / "web").string() + " --compact " +
           (dir / folder / "compact").string() + " --out " + (dir / folder / "maps").string() +
           " --height fc";
  });
  ASSERT_EQ(whole.exit_code, 0) << whole.output;
  ASSERT_EQ(streamed.exit_code, 0) << streamed.output;
  EXPECT_THAT(streamed.output, HasSubstr("fitted ptm to the 36 photographs (sRGB-encoded) in "
                                         "bands of"));
  EXPECT_THAT(streamed.output, HasSubstr("fitted gradient to the 36 photographs (linear)"));
  EXPECT_THAT(streamed.output, Not(HasSubstr("bands of 80 of 80 rows")));
  const RelightWebStack a = ReadRelightWeb(dir / "streamed" / "web");
  const RelightWebStack b = ReadRelightWeb(dir / "whole" / "web");
  ASSERT_EQ(a.basis, b.basis);
  for (std::size_t p = 0; p < b.scale.size(); ++p) {
    EXPECT_NEAR(a.scale[p], b.scale[p], 1e-4 * std::abs(b.scale[p])) << p;
    EXPECT_NEAR(a.bias[p], b.bias[p], 1e-4) << p;
  }
  const PlaneDifference web = ComparePlanes(a.planes, b.planes);
  std::printf("relight web planes vs in memory: largest byte difference %d, %.3g%% differ\n",
              web.largest, 100 * web.fraction);
  EXPECT_LE(web.largest, 1);  // as ExpectSamePtm (JPEG planes of the same bytes decode alike)
  EXPECT_LE(web.fraction, 0.001);
  const LoadedStack compact_a = ReadCompactStack(dir / "streamed" / "compact");
  const LoadedStack compact_b = ReadCompactStack(dir / "whole" / "compact");
  EXPECT_EQ(compact_a.representation.method(), "gradient");
  const double compact = testing::LargestDifferenceOverLargestValue(
      compact_a.representation.maps(), compact_b.representation.maps());
  std::printf("compact maps vs in memory: %.3g of the largest value\n", compact);
  EXPECT_LE(compact, 1.5 / 255);  // 8-bit planes: at most one code apart
  for (const char* map : {"normal.png", "albedo.png", "height.exr"}) {
    const Image x = ReadImage(dir / "streamed" / "maps" / map).image;
    const Image y = ReadImage(dir / "whole" / "maps" / map).image;
    ASSERT_TRUE(x.SameShape(y)) << map;
    const double difference = testing::LargestDifferenceOverLargestValue(x, y);
    std::printf("%s vs in memory: %.3g of the largest value\n", map, difference);
    EXPECT_LE(difference, 1.5 / 65535) << map;  // as the maps above
  }
  EXPECT_EQ(ReadJsonFile(dir / "streamed" / "maps" / "export.json")["height_map"]["integrator"],
            "fc");
  EXPECT_THAT(testing::EntriesOf(dir / "streamed"),
              ::testing::ElementsAre("compact", "maps", "web"));
}

// relight's rbf and bilinear planes (a PCA of every pixel's profile at the nodes) are made in
// bands, three passes (relight_web_format.h, RelightWebBands): rbf from the photographs
// themselves, bilinear from the scratch stack of its encoded fit. Against the in-memory export:
// rbf the same folder (the same photographs' values, summed in the same order whatever the
// bands); bilinear to within one code (its fit rounds by band; measured: the same bytes).
TEST(ExportStreamCliTest, RelightsRbfAndBilinearPlanesAreMadeInBands) {
  for (const std::string basis : {"rbf", "bilinear"}) {
    const TempDir dir;
    const auto [whole, streamed] = ExportInMemoryAndStreamed(dir, [&](const std::string& folder) {
      return " --relight-basis " + basis + " --relight-web " + (dir / folder / "web").string();
    });
    ASSERT_EQ(whole.exit_code, 0) << whole.output;
    ASSERT_EQ(streamed.exit_code, 0) << streamed.output;
    EXPECT_THAT(whole.output, HasSubstr("3 passes in bands of 80 of 80 rows"));
    EXPECT_THAT(streamed.output, HasSubstr("; 3 passes in bands of"));
    EXPECT_THAT(streamed.output, Not(HasSubstr("bands of 80 of 80 rows")));
    if (basis == "bilinear") {
      EXPECT_THAT(streamed.output, HasSubstr("fitted bilinear to the 36 photographs "
                                             "(sRGB-encoded) in bands of"));
    } else {
      EXPECT_THAT(streamed.output, Not(HasSubstr("fitted")));  // the photographs themselves
    }
    const RelightWebStack a = ReadRelightWeb(dir / "streamed" / "web");
    const RelightWebStack b = ReadRelightWeb(dir / "whole" / "web");
    EXPECT_EQ(a.basis_values, b.basis_values) << basis;
    ASSERT_EQ(a.scale.size(), b.scale.size()) << basis;
    for (std::size_t p = 0; p < b.scale.size(); ++p) {
      EXPECT_NEAR(a.scale[p], b.scale[p], 1e-4 * std::abs(b.scale[p])) << basis << p;
      EXPECT_NEAR(a.bias[p], b.bias[p], 1e-4) << basis << p;
    }
    const PlaneDifference planes = ComparePlanes(a.planes, b.planes);
    std::printf("%s planes vs in memory: largest byte difference %d, %.3g%% differ\n",
                basis.c_str(), planes.largest, 100 * planes.fraction);
    if (basis == "rbf") {
      EXPECT_EQ(planes.largest, 0);
      EXPECT_EQ(a.scale, b.scale);
      EXPECT_EQ(a.bias, b.bias);
    }
    EXPECT_LE(planes.largest, 1);  // as ExpectSamePtm
    EXPECT_LE(planes.fraction, 0.001);
    EXPECT_THAT(testing::EntriesOf(dir / "streamed"), ::testing::ElementsAre("web"));
  }
}

// Every file under `folder` (relative paths, sorted).
std::vector<std::string> FilesUnder(const fs::path& folder) {
  std::vector<std::string> files;
  for (const auto& entry : fs::recursive_directory_iterator(folder)) {
    if (entry.is_regular_file()) files.push_back(fs::relative(entry.path(), folder).string());
  }
  std::sort(files.begin(), files.end());
  return files;
}

// Whether two JSON values are equal but for numbers within `tolerance`.
bool JsonNear(const nlohmann::json& a, const nlohmann::json& b, double tolerance) {
  if (a.is_number() && b.is_number()) {
    return std::abs(a.get<double>() - b.get<double>()) <= tolerance;
  }
  if (a.type() != b.type() || a.size() != b.size()) return false;
  if (a.is_object()) {
    for (const auto& [key, value] : a.items()) {
      if (!b.contains(key) || !JsonNear(value, b[key], tolerance)) return false;
    }
    return true;
  }
  if (a.is_array()) {
    for (std::size_t i = 0; i < a.size(); ++i) {
      if (!JsonNear(a[i], b[i], tolerance)) return false;
    }
    return true;
  }
  return a == b;
}

// The viewer of a set exported streamed (every method fitted in bands into scratch stacks, then
// the viewer made from those) is the in-memory viewer: the same files, byte for byte but for
// viewer.json, whose light directions went through the stacks' descriptions (normalised again on
// reading: measured, a difference of 1e-16 in some components); tiled (--viewer-tiles always) it
// is written from the stacks in bands.
TEST(ExportStreamCliTest, ASetsViewerExportedStreamedEqualsTheInMemoryViewer) {
  const TempDir dir;
  const std::string capture = (dir / "capture").string();
  testing::GenerateCapture(capture, "--size 40x32 --pattern bumps --seed 9");
  const RunResult whole = RunPhotomat("export " + capture + " --viewer " + (dir / "w").string());
  ASSERT_EQ(whole.exit_code, 0) << whole.output;
  const RunResult streamed =
      RunPhotomat("export " + capture + " --stream --memory 1 --viewer " + (dir / "s").string());
  ASSERT_EQ(streamed.exit_code, 0) << streamed.output;
  EXPECT_THAT(streamed.output, HasSubstr("(linear) in bands of"));
  const std::vector<std::string> files = FilesUnder(dir / "w");
  ASSERT_EQ(FilesUnder(dir / "s"), files);
  EXPECT_TRUE(JsonNear(ReadJsonFile(dir / "s" / "viewer.json"),
                       ReadJsonFile(dir / "w" / "viewer.json"), 1e-15));
  std::size_t differing = 0;
  for (const std::string& file : files) {
    if (file == "viewer.json") continue;
    if (ReadTextFile(dir / "s" / file) != ReadTextFile(dir / "w" / file)) {
      ++differing;
      std::printf("differs: %s\n", file.c_str());
    }
  }
  std::printf("%zu of the %zu other viewer files differ\n", differing, files.size() - 1);
  EXPECT_EQ(differing, 0u);
  const RunResult tiled = RunPhotomat("export " + capture + " --stream --viewer " +
                                      (dir / "t").string() + " --viewer-tiles always");
  ASSERT_EQ(tiled.exit_code, 0) << tiled.output;
  EXPECT_THAT(tiled.output, HasSubstr("as deep-zoom tiles"));
  EXPECT_THAT(testing::EntriesOf(dir.path()), ::testing::ElementsAre("capture", "s", "t", "w"));
}

// What streaming is for: under a hard address-space limit far below what holding the set needs
// (1536 x 1536 x 36 lights x RGB: 3.4 GB at kWholeSetBytesPerPixelImage, 2.04 GB for the images
// as float and their copy alone), `export --ptm --rti` streams by itself (the whole set does not
// fit the default budget) and writes what the in-memory export writes without the limit; the
// in-memory export (a budget it cannot have, --memory 100000) fails under the limit. relight's
// rbf planes (a PCA of every pixel's profile at the 36 nodes, 1 GB as one matrix) come from the
// photographs in bands: the same folder as in memory.
TEST(ExportStreamCliTest, UnderAnAddressSpaceLimitASetStreamsByItselfAndMatches) {
  const TempDir dir;
  const std::string lights =
      testing::WriteLargeLambertianCapture(dir / "capture", 1536, 1536).string();
  // 1000 MiB where the program starts in 453 (testing::StartupAddressSpace).
  const std::size_t limit = testing::StartupAddressSpace("export") + (std::size_t{547} << 20);
  const auto files = [&](const std::string& folder) {
    fs::create_directories(dir / folder);
    return " --ptm " + (dir / folder / "c.ptm").string() + " --rti " +
           (dir / folder / "c.rti").string() + " --relight-basis rbf --relight-web " +
           (dir / folder / "web").string();
  };
  const RunResult limited = RunPhotomat("export " + lights + files("limited"), {limit});
  ASSERT_EQ(limited.exit_code, 0) << limited.output;
  std::printf("%s", limited.output.c_str());
  EXPECT_THAT(limited.output, HasSubstr("in bands of"));
  EXPECT_THAT(limited.output, Not(HasSubstr("bands of 1536 of 1536 rows")));
  const RunResult refused =
      RunPhotomat("export " + lights + files("refused") + " --memory 100000", {limit});
  EXPECT_NE(refused.exit_code, 0) << refused.output;
  EXPECT_THAT(refused.output, HasSubstr("out of memory"));
  EXPECT_TRUE(testing::EntriesOf(dir / "refused").empty());
  const RunResult whole = RunPhotomat("export " + lights + files("whole") + " --memory 100000");
  ASSERT_EQ(whole.exit_code, 0) << whole.output;
  ExpectSamePtm(dir / "limited" / "c.ptm", dir / "whole" / "c.ptm");
  ExpectSameRti(dir / "limited" / "c.rti", dir / "whole" / "c.rti");
  const RelightWebStack web = ReadRelightWeb(dir / "limited" / "web");
  const RelightWebStack web_whole = ReadRelightWeb(dir / "whole" / "web");
  EXPECT_EQ(web.basis_values, web_whole.basis_values);
  EXPECT_EQ(web.scale, web_whole.scale);
  EXPECT_EQ(web.bias, web_whole.bias);
  EXPECT_EQ(ComparePlanes(web.planes, web_whole.planes).largest, 0);
  EXPECT_THAT(testing::EntriesOf(dir / "limited"), ::testing::ElementsAre("c.ptm", "c.rti", "web"));
}

}  // namespace
}  // namespace photomat
