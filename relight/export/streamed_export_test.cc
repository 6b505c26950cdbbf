#include <fmt/format.h>
#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <string>

#include "core/error.h"
#include "core/image_io.h"
#include "core/json_file.h"
#include "relight/export/export.h"
#include "represent/fitting/fit.h"
#include "represent/model/shading.h"
#include "tests/support/synthetic_sets.h"
#include "tests/support/test_support.h"

namespace photomat {
namespace {

namespace fs = std::filesystem;

// RMS of a - b over b's range (the bricks cover every pixel).
double RelativeRmsDifference(const Image& a, const Image& b) {
  double sum = 0.0, count = 0.0, low = INFINITY, high = -INFINITY;
  for (std::size_t p = 0; p < b.pixel_count(); ++p) {
    const double d = a.pixel(p)[0] - b.pixel(p)[0];
    sum += d * d;
    count += 1.0;
    low = std::min(low, double{b.pixel(p)[0]});
    high = std::max(high, double{b.pixel(p)[0]});
  }
  return std::sqrt(sum / count) / (high - low);
}

// `stack` saved as `dir`/NAME.exr, beside the empty folders NAME-whole and NAME-streamed for the
// in-memory and streamed exports.
struct StackAndExportFolders {
  fs::path stack, whole, streamed;
};
StackAndExportFolders SaveStackBesideExportFolders(const fs::path& dir, const std::string& name,
                                                   const LoadedStack& stack) {
  const StackAndExportFolders paths{dir / (name + ".exr"), dir / (name + "-whole"),
                                    dir / (name + "-streamed")};
  SaveRepresentation(paths.stack, stack.representation, stack.provenance);
  fs::create_directories(paths.whole);
  fs::create_directories(paths.streamed);
  return paths;
}

// The streamed export writes the files of the in-memory one: normals, albedo, the stack's maps and
// its derived layers value for value; the height by tiled Poisson, measured against the exact
// solve. Bands of 9 rows, tiles of 64 + 8 over a 150 x 130 map: several of each.
TEST(StreamedExportTest, StreamedFilesEqualTheInMemoryExport) {
  testing::TempDir dir;
  const auto synthetic = testing::LambertianSet(SurfacePattern::kBricks, 64);
  // A larger stack from the small fit's maps tiled: 150 x 130, no multiple of band or tile.
  for (const char* name : {"gradient", "ptm", "eigen6"}) {
    const Representation small = Fit(synthetic.set, Method::Parse(name));
    Image maps(150, 130, small.maps().channel_names());
    for (int c = 0; c < maps.channels(); ++c) {
      for (int y = 0; y < 130; ++y) {
        for (int x = 0; x < 150; ++x) maps.at(x, y, c) = small.maps().at(x % 64, y % 64, c);
      }
    }
    const LoadedStack stack{small.WithMaps(std::move(maps)),
                            {synthetic.set.lights(), "linear", "synthetic"}};
    const auto [stack_path, whole, streamed] =
        SaveStackBesideExportFolders(dir.path(), name, stack);
    ExportMaps(stack, whole);
    StreamedExportOptions options;
    options.band_rows = 9;
    options.poisson.tile = 64;
    options.poisson.overlap = 8;
    options.poisson.coarse_factor = 4;
    StackBandReader reader(stack_path);
    StreamedExportReport report;
    const nlohmann::json description = ExportMapsStreamed(reader, streamed, options, &report);
    EXPECT_EQ(report.band_rows, 9);
    for (const char* file : {"normal.png", "albedo.png"}) {
      EXPECT_TRUE(
          testing::SameBits(ReadImage(streamed / file).image, ReadImage(whole / file).image))
          << name << " " << file;
    }
    const Image height = ReadImage(streamed / "height.exr").image;
    const double difference = RelativeRmsDifference(height, ReadImage(whole / "height.exr").image);
    std::printf("%s: streamed export height against the in-memory one: relative RMS %.3g\n", name,
                difference);
    // Measured: 2.1e-3 for each method (the same normals); bound 1.4 x.
    EXPECT_LT(difference, 3e-3) << name;
    // stack.exr: the same maps, the derived layers and the streamed height.
    const LoadedStack whole_stack = LoadRepresentation(whole / "stack.exr");
    const LoadedStack streamed_stack = LoadRepresentation(streamed / "stack.exr");
    EXPECT_TRUE(
        testing::SameBits(streamed_stack.representation.maps(), whole_stack.representation.maps()));
    ASSERT_EQ(streamed_stack.extra_layers.channel_names(),
              whole_stack.extra_layers.channel_names());
    const int layers = streamed_stack.extra_layers.channels();
    for (int c = 0; c + 1 < layers; ++c) {
      const auto a = streamed_stack.extra_layers.plane(c), b = whole_stack.extra_layers.plane(c);
      ASSERT_TRUE(std::equal(a.begin(), a.end(), b.begin())) << name << " layer " << c;
    }
    const auto stored_height = streamed_stack.extra_layers.plane(layers - 1);
    EXPECT_TRUE(std::equal(stored_height.begin(), stored_height.end(), height.values().begin()));
    // export.json and the tile as in memory; the streamed export says how it was made.
    const nlohmann::json written = ReadJsonFile(streamed / "export.json");
    EXPECT_EQ(written["normals"]["source"],
              ReadJsonFile(whole / "export.json")["normals"]["source"]);
    EXPECT_EQ(written["streamed"]["tile"], 64);
    EXPECT_TRUE(fs::exists(streamed / "tile.gltf"));
    // The height range (height.png's attributes; export.json's "height" key holds the image
    // height, which shadows the height map's entry there): as in memory, within the tiling.
    const auto range = [](const fs::path& png) {
      const auto attributes = ReadImage(png).info.attributes;
      return std::pair(std::stod(attributes.at("photomat:height_min")),
                       std::stod(attributes.at("photomat:height_max")));
    };
    const auto [low, high] = range(streamed / "height.png");
    const auto [whole_low, whole_high] = range(whole / "height.png");
    EXPECT_NEAR(low, whole_low, 0.05 * (whole_high - whole_low)) << name;
    EXPECT_NEAR(high, whole_high, 0.05 * (whole_high - whole_low)) << name;
    // No scratch file is left.
    for (const auto& entry : fs::directory_iterator(streamed)) {
      EXPECT_FALSE(entry.path().filename().string().starts_with(".")) << entry.path();
    }
  }
}

// A pbr stack streams: its specular texture's scale (the largest F0 over the mask) is gathered in
// the first pass and the pbr maps written in the last, equal to the in-memory export's.
TEST(StreamedExportTest, PbrMapsEqualTheInMemoryExport) {
  testing::TempDir dir;
  // 23 x 19 varied maps (base colour, roughness, F0, a tilted normal), the largest F0 in the last
  // band and a few pixels uncovered (all maps 0).
  Image maps(23, 19, MicrofacetShading().MapNames());
  for (int y = 0; y < maps.height(); ++y) {
    for (int x = 0; x < maps.width(); ++x) {
      if ((x + 3 * y) % 17 == 0) continue;
      const float nx = 0.3f * std::sin(0.4f * x), ny = 0.2f * std::cos(0.3f * y);
      const float nz = std::sqrt(1.0f - nx * nx - ny * ny);
      const float values[] = {0.2f + 0.02f * x,
                              0.5f,
                              0.1f + 0.03f * y,
                              0.1f + 0.03f * y,
                              0.02f + 0.004f * y + 0.001f * x,
                              nx,
                              ny,
                              nz};
      for (int c = 0; c < 8; ++c) maps.at(x, y, c) = values[c];
    }
  }
  const fs::path stack_path = dir / "pbr.exr";
  SaveRepresentation(stack_path,
                     Representation("pbr", maps, std::make_shared<MicrofacetShading>()));
  const fs::path whole = dir / "whole";
  const fs::path streamed = dir / "streamed";
  fs::create_directories(whole);
  fs::create_directories(streamed);
  const nlohmann::json whole_description = ExportMaps(LoadRepresentation(stack_path), whole);
  StreamedExportOptions options;
  options.band_rows = 4;
  options.poisson.tile = 8;
  options.poisson.overlap = 2;
  options.poisson.coarse_factor = 2;
  StackBandReader reader(stack_path);
  const nlohmann::json description = ExportMapsStreamed(reader, streamed, options);
  for (const char* file : {"normal.png", "albedo.png", "roughness.exr", "roughness.png", "f0.exr",
                           "specular_level.png", "metallic_roughness.png", "specular.png",
                           "base_color.exr", "base_color.png"}) {
    EXPECT_TRUE(testing::SameBits(ReadImage(streamed / file).image, ReadImage(whole / file).image))
        << file;
  }
  // The largest F0 (0.02 + 0.004 x 18 + 0.001 x 22 = 0.114) scales the specular texture.
  EXPECT_EQ(description["pbr"], whole_description["pbr"]);
  EXPECT_NEAR(description["pbr"]["specular"]["specular_color_factor"].get<double>(), 0.114 / 0.04,
              1e-5);
  EXPECT_EQ(ReadJsonFile(streamed / "export.json")["pbr"], whole_description["pbr"]);
}

// --height fc streamed: the gradients of pass 1 read back whole for one FFT. The same files as the
// in-memory export, bit for bit: normals, albedo, the height (the same gradients through the same
// transform) and its range, stack.exr; for Gradient (normals from its maps) and PTM (from its
// luminance maximum, the albedo by a Lambertian fit relit at the capture lights), with a mask
// (the PTM stack zero on a corner) and bands of 7 rows.
TEST(StreamedExportTest, FrankotChellappaEqualsTheInMemoryExport) {
  testing::TempDir dir;
  const auto synthetic = testing::LambertianSet(SurfacePattern::kBumps, 48);
  for (const char* name : {"gradient", "ptm"}) {
    Representation fit = Fit(synthetic.set, Method::Parse(name));
    if (std::string(name) == "ptm") {
      Image maps = fit.maps();
      for (int c = 0; c < maps.channels(); ++c) {
        for (int y = 0; y < 10; ++y) {
          for (int x = 0; x < 12; ++x) maps.at(x, y, c) = 0.0f;
        }
      }
      fit = fit.WithMaps(std::move(maps));
    }
    const LoadedStack stack{fit, {synthetic.set.lights(), "linear", "synthetic"}};
    const auto [stack_path, whole, streamed] =
        SaveStackBesideExportFolders(dir.path(), name, stack);
    ExportOptions fc;
    fc.height = HeightIntegrator::kFrankotChellappa;
    const nlohmann::json whole_description = ExportMaps(stack, whole, fc);
    StreamedExportOptions options;
    options.maps = fc;
    options.band_rows = 7;
    StackBandReader reader(stack_path);
    const nlohmann::json description = ExportMapsStreamed(reader, streamed, options);
    for (const char* file : {"normal.png", "albedo.png", "height.exr", "height.png"}) {
      EXPECT_TRUE(
          testing::SameBits(ReadImage(streamed / file).image, ReadImage(whole / file).image))
          << name << " " << file;
    }
    EXPECT_EQ(description["height_map"], whole_description["height_map"]) << name;
    EXPECT_EQ(description["height_map"]["integrator"], "fc");
    EXPECT_EQ(description["streamed"], nlohmann::json({{"band_rows", 7}}));
    const LoadedStack whole_stack = LoadRepresentation(whole / "stack.exr");
    const LoadedStack streamed_stack = LoadRepresentation(streamed / "stack.exr");
    EXPECT_TRUE(testing::SameBits(streamed_stack.extra_layers, whole_stack.extra_layers)) << name;
    for (const auto& entry : fs::directory_iterator(streamed)) {
      EXPECT_FALSE(entry.path().filename().string().starts_with(".")) << entry.path();
    }
  }
}

}  // namespace
}  // namespace photomat
