#include "relight/web/viewer_pyramid.h"

#include <gtest/gtest.h>

#include <bit>
#include <cstdint>

#include "core/atomic_file.h"
#include "core/error.h"
#include "core/json_file.h"
#include "core/random.h"
#include "relight/web/viewer_export.h"
#include "represent/fitting/fit.h"
#include "represent/stack/map_stack.h"
#include "tests/support/synthetic_sets.h"
#include "tests/support/test_support.h"

namespace photomat {
namespace {

namespace fs = std::filesystem;
using testing::TempDir;

// Every level of the pyramid in `folder`, reassembled from its tiles (their cores; the overlaps
// are checked against the neighbours' cores). Unused layer components must be 0.
std::vector<Image> ReassembleLevels(const fs::path& folder, const PyramidLayout& layout, int maps) {
  const int layers = (maps + 3) / 4;
  std::vector<Image> levels;
  for (int level = 0; level < layout.levels(); ++level) {
    Image image(layout.LevelWidth(level), layout.LevelHeight(level), maps);
    Image written(image.width(), image.height(), 1);  // how often each pixel's core was seen
    std::vector<std::pair<TileRect, std::vector<float>>> tiles;
    for (int row = 0; row < layout.Rows(level); ++row) {
      for (int column = 0; column < layout.Columns(level); ++column) {
        const TileRect t = layout.Tile(level, column, row);
        std::vector<float> values =
            ReadFloat32File(folder / PyramidLayout::TilePath(level, column, row));
        EXPECT_EQ(values.size(), static_cast<std::size_t>(layers) * t.width * t.height * 4);
        const int T = layout.tile_size();
        for (int y = row * T; y < std::min((row + 1) * T, image.height()); ++y) {
          for (int x = column * T; x < std::min((column + 1) * T, image.width()); ++x) {
            written.at(x, y, 0) += 1.0f;
            for (int map = 0; map < 4 * layers; ++map) {
              const float v =
                  values[((static_cast<std::size_t>(map / 4) * t.height + (y - t.y)) * t.width +
                          (x - t.x)) *
                             4 +
                         map % 4];
              if (map < maps)
                image.at(x, y, map) = v;
              else
                EXPECT_EQ(v, 0.0f);
            }
          }
        }
        tiles.emplace_back(t, std::move(values));
      }
    }
    for (float seen : written.values()) EXPECT_EQ(seen, 1.0f);
    // Overlaps hold the neighbours' pixels.
    for (const auto& [t, values] : tiles) {
      for (int y = t.y; y < t.y + t.height; ++y) {
        for (int x = t.x; x < t.x + t.width; ++x) {
          for (int map = 0; map < maps; ++map) {
            EXPECT_EQ(values[((static_cast<std::size_t>(map / 4) * t.height + (y - t.y)) * t.width +
                              (x - t.x)) *
                                 4 +
                             map % 4],
                      image.at(x, y, map));
          }
        }
      }
    }
    levels.push_back(std::move(image));
  }
  return levels;
}

// The box average of `image`'s 2 x 2 blocks (of the pixels a block holds at an odd edge).
Image BoxHalf(const Image& image) {
  Image half((image.width() + 1) / 2, (image.height() + 1) / 2, image.channels());
  for (int c = 0; c < image.channels(); ++c) {
    for (int y = 0; y < half.height(); ++y) {
      for (int x = 0; x < half.width(); ++x) {
        double sum = 0.0;
        int count = 0;
        for (int dy = 0; dy < 2; ++dy) {
          for (int dx = 0; dx < 2; ++dx) {
            if (2 * x + dx < image.width() && 2 * y + dy < image.height()) {
              sum += image.at(2 * x + dx, 2 * y + dy, c);
              ++count;
            }
          }
        }
        half.at(x, y, c) = static_cast<float>(sum / count);
      }
    }
  }
  return half;
}

Image RandomMaps(int width, int height, int maps, std::uint64_t seed) {
  Random random(seed);
  Image image(width, height, maps);
  for (float& v : image.values()) v = static_cast<float>(random.Uniform(-2.0, 2.0));
  return image;
}

void ExpectSameValues(const Image& a, const Image& b) {
  ASSERT_TRUE(a.SameShape(b));
  for (std::size_t i = 0; i < a.values().size(); ++i) ASSERT_EQ(a.values()[i], b.values()[i]) << i;
}

TEST(ViewerPyramidTest, LayoutHalvesUntilOneTileAndCutsTilesWithOverlap) {
  const PyramidLayout layout(300, 200, 64);
  ASSERT_EQ(layout.levels(), 4);  // 300x200, 150x100, 75x50, 38x25
  EXPECT_EQ(layout.LevelWidth(3), 38);
  EXPECT_EQ(layout.LevelHeight(3), 25);
  EXPECT_EQ(layout.Columns(0), 5);
  EXPECT_EQ(layout.Rows(0), 4);
  EXPECT_EQ(layout.TileCount(), 20u + 6u + 2u + 1u);
  const TileRect inner = layout.Tile(0, 1, 1);
  EXPECT_EQ(inner.x, 63);
  EXPECT_EQ(inner.y, 63);
  EXPECT_EQ(inner.width, 66);
  EXPECT_EQ(inner.height, 66);
  const TileRect corner = layout.Tile(0, 4, 3);  // no overlap past the image's edges
  EXPECT_EQ(corner.x, 255);
  EXPECT_EQ(corner.width, 45);
  EXPECT_EQ(corner.y, 191);
  EXPECT_EQ(corner.height, 9);
  const TileRect top = layout.Tile(3, 0, 0);
  EXPECT_EQ(top.width, 38);
  EXPECT_EQ(top.height, 25);
  EXPECT_EQ(PyramidLayout::TilePath(2, 1, 0), "2/1_0.f32");
  const nlohmann::json json = layout.ToJson();
  EXPECT_EQ(json["tile_size"], 64);
  EXPECT_EQ(json["overlap"], 1);
  EXPECT_EQ(json["levels"], 4);
  EXPECT_EQ(json["format"], "float32");
  EXPECT_EQ(json["level_sizes"][2], nlohmann::json({75, 50}));
  // A stack no larger than a tile is one level of one tile.
  EXPECT_EQ(PyramidLayout(256, 100).levels(), 1);
  EXPECT_THROW(PyramidLayout(10, 10, 2, 1), Error);
  EXPECT_THROW(PyramidLayout(0, 10), Error);
}

TEST(ViewerPyramidTest, TilingChoice) {
  EXPECT_FALSE(UsesViewerTiles(ViewerTiling::kAuto, 4096, 4096));
  EXPECT_TRUE(UsesViewerTiles(ViewerTiling::kAuto, 4097, 4096));
  EXPECT_TRUE(UsesViewerTiles(ViewerTiling::kAuto, 8688, 5792));
  EXPECT_TRUE(UsesViewerTiles(ViewerTiling::kAlways, 8, 8));
  EXPECT_FALSE(UsesViewerTiles(ViewerTiling::kNever, 10000, 10000));
  EXPECT_EQ(ParseViewerTiling("always"), ViewerTiling::kAlways);
  EXPECT_EQ(ToString(ParseViewerTiling("never")), "never");
  EXPECT_THROW(ParseViewerTiling("sometimes"), Error);
}

// Level 0 reassembles to the maps bit for bit, each coarser level is the box average of the one
// below, whatever the bands the rows come in; odd sizes exercise the edge blocks.
TEST(ViewerPyramidTest, TilesReassembleToTheMapsAndCoarserLevelsAreBoxAverages) {
  TempDir dir;
  const Image maps = RandomMaps(37, 23, 5, 11);
  const PyramidLayout layout(37, 23, 8);
  ASSERT_EQ(layout.levels(), 4);  // 37x23, 19x12, 10x6, 5x3
  for (int band : {1, 3, 23}) {
    SCOPED_TRACE(band);
    const fs::path folder = dir / std::to_string(band);
    fs::create_directories(folder);
    PyramidWriter writer(folder, layout, maps.channels());
    for (int y = 0; y < maps.height(); y += band) {
      writer.AddRows(maps.Rows(y, std::min(band, maps.height() - y)));
    }
    writer.Finish();
    const std::vector<Image> levels = ReassembleLevels(folder, layout, maps.channels());
    ExpectSameValues(levels[0], maps);
    for (int level = 1; level < layout.levels(); ++level) {
      SCOPED_TRACE(level);
      ExpectSameValues(levels[level], BoxHalf(levels[level - 1]));
    }
    std::size_t files = 0, bytes = 0;
    for (const auto& entry : fs::recursive_directory_iterator(folder)) {
      if (!entry.is_regular_file()) continue;
      ++files;
      bytes += entry.file_size();
    }
    EXPECT_EQ(files, layout.TileCount());
    EXPECT_EQ(bytes, layout.FileBytes(maps.channels()));
  }
}

TEST(ViewerPyramidTest, MissingOrSurplusRowsAreErrors) {
  TempDir dir;
  const Image maps = RandomMaps(20, 10, 3, 5);
  const PyramidLayout layout(20, 10, 8);
  PyramidWriter writer(dir.path(), layout, 3);
  writer.AddRows(maps.Rows(0, 6));
  EXPECT_THROW(writer.Finish(), Error);
  writer.AddRows(maps.Rows(6, 4));
  writer.Finish();
  EXPECT_THROW(writer.AddRows(maps.Rows(0, 1)), Error);
  EXPECT_THROW(writer.AddRows(RandomMaps(19, 1, 3, 1)), Error);
}

// `export --viewer` of a large stack: the tiles of the stack read in bands under a small budget
// equal the stack's maps, the descriptor says where they are, and there is no whole-image file.
TEST(ViewerPyramidTest, StreamedExportWritesThePyramidOfEveryStackInBands) {
  TempDir dir;
  const auto synthetic = testing::LambertianSet(SurfacePattern::kBricks, 40);
  std::vector<fs::path> stacks;
  std::vector<Representation> fits;
  for (const char* name : {"gradient", "ptm"}) {
    fits.push_back(Fit(synthetic.set, Method::Parse(name)));
    stacks.push_back(dir / (std::string(name) + ".exr"));
    SaveRepresentation(stacks.back(), fits.back());
  }
  ViewerExportOptions options;
  options.tile_size = 16;
  options.display_maps = false;  // (viewer_display_pyramids_test.cc)
  const PyramidLayout layout(40, 40, 16);
  // The pyramid's buffers and a few rows: bands of a few rows.
  options.memory_bytes = PyramidWriter::BufferBytes(layout, 18) + 40 * 4 * 40 * 5;
  ExportViewerStreamed(dir / "viewer", stacks, options);

  const nlohmann::json manifest = ReadJsonFile(dir / "viewer" / "viewer.json");
  EXPECT_EQ(manifest["width"], 40);
  EXPECT_EQ(manifest["views"].size(), 0u);
  ASSERT_EQ(manifest["methods"].size(), 2u);
  for (std::size_t m = 0; m < fits.size(); ++m) {
    const nlohmann::json& data = manifest["methods"][m]["data"];
    SCOPED_TRACE(fits[m].method());
    EXPECT_FALSE(data.contains("file"));
    EXPECT_EQ(data["layers"], (fits[m].maps().channels() + 3) / 4);
    nlohmann::json expected = layout.ToJson();
    expected["folder"] = "maps/" + fits[m].method() + "/levels";
    EXPECT_EQ(data["pyramid"], expected);
    const std::vector<Image> levels =
        ReassembleLevels(dir / "viewer" / data["pyramid"]["folder"].get<std::string>(), layout,
                         fits[m].maps().channels());
    ExpectSameValues(levels[0], fits[m].maps());
    for (int level = 1; level < layout.levels(); ++level) {
      ExpectSameValues(levels[level], BoxHalf(levels[level - 1]));
    }
    EXPECT_FALSE(fs::exists(dir / "viewer" / "maps" / (fits[m].method() + ".f32")));
  }

  // A budget below the pyramid's buffers is an error naming the stack; nothing is written.
  options.memory_bytes = PyramidWriter::BufferBytes(layout, 18) / 2;
  try {
    ExportViewerStreamed(dir / "viewer2", stacks, options);
    ADD_FAILURE() << "no error";
  } catch (const Error& error) {
    EXPECT_NE(std::string(error.what()).find("ptm.exr"), std::string::npos) << error.what();
    EXPECT_NE(std::string(error.what()).find("needs at least"), std::string::npos) << error.what();
  }
  EXPECT_FALSE(fs::exists(dir / "viewer2"));
}

// In memory (a .ptm, a photometric set), --viewer-tiles always gives the same pyramid.
TEST(ViewerPyramidTest, InMemoryExportTilesWhenAsked) {
  TempDir dir;
  const auto synthetic = testing::LambertianSet(SurfacePattern::kBricks, 24);
  const Representation fit = Fit(synthetic.set, Method::Parse("ptm"));
  ViewerExportOptions options;
  options.tiling = ViewerTiling::kAlways;
  options.tile_size = 8;
  ExportViewer(dir / "viewer", {fit}, options);
  const nlohmann::json manifest = ReadJsonFile(dir / "viewer" / "viewer.json");
  const nlohmann::json& data = manifest["methods"][0]["data"];
  const PyramidLayout layout(24, 24, 8);
  ASSERT_EQ(data["pyramid"]["levels"], layout.levels());
  const std::vector<Image> levels = ReassembleLevels(
      dir / "viewer" / data["pyramid"]["folder"].get<std::string>(), layout, fit.maps().channels());
  ExpectSameValues(levels[0], fit.maps());
  EXPECT_EQ(manifest["views"].size(), 0u);
  options.tiling = ViewerTiling::kNever;
  ExportViewer(dir / "viewer", {fit}, options);
  EXPECT_TRUE(ReadJsonFile(dir / "viewer" / "viewer.json")["methods"][0]["data"].contains("file"));
}

}  // namespace
}  // namespace photomat
