#include "relight/web/viewer_display_pyramids.h"

#include <gtest/gtest.h>

#include "core/image_io.h"
#include "core/json_file.h"
#include "relight/export/export.h"
#include "relight/web/viewer_export.h"
#include "represent/fitting/fit.h"
#include "represent/stack/map_stack.h"
#include "tests/support/synthetic_sets.h"
#include "tests/support/test_support.h"

namespace photomat {
namespace {

namespace fs = std::filesystem;
using testing::TempDir;

// Level 0 of a one-layer pyramid in `folder`, from its tiles' cores.
Image ReassembleLevel0(const fs::path& folder, const PyramidLayout& layout, int channels) {
  Image image(layout.width(), layout.height(), channels);
  const int size = layout.tile_size();
  for (int row = 0; row < layout.Rows(0); ++row) {
    for (int column = 0; column < layout.Columns(0); ++column) {
      const TileRect t = layout.Tile(0, column, row);
      const std::vector<float> values =
          ReadFloat32File(folder / PyramidLayout::TilePath(0, column, row));
      EXPECT_EQ(values.size(), static_cast<std::size_t>(t.width) * t.height * 4);
      for (int y = row * size; y < std::min((row + 1) * size, image.height()); ++y) {
        for (int x = column * size; x < std::min((column + 1) * size, image.width()); ++x) {
          for (int c = 0; c < channels; ++c) {
            image.at(x, y, c) =
                values[(static_cast<std::size_t>(y - t.y) * t.width + (x - t.x)) * 4 + c];
          }
        }
      }
    }
  }
  return image;
}

TEST(ViewerDisplayPyramidsTest, DeepZoomViewsAreTheStreamedExportsMapsTileForTile) {
  TempDir dir;
  const auto synthetic = testing::LambertianSet(SurfacePattern::kBricks, 40);
  // Eigen-6 gives no normals: the views come from Gradient, listed second.
  std::vector<fs::path> stacks;
  for (const char* name : {"eigen6", "gradient"}) {
    stacks.push_back(dir / (std::string(name) + ".exr"));
    SaveRepresentation(stacks.back(), Fit(synthetic.set, Method::Parse(name)));
  }
  ViewerExportOptions options;
  options.tile_size = 16;
  ExportViewerStreamed(dir / "viewer", stacks, options);
  EXPECT_FALSE(fs::exists(dir / "viewer" / ".display-maps"));

  // The same export as `photomat export` streams it.
  fs::create_directories(dir / "export");
  StackBandReader reader(stacks[1]);
  StreamedExportOptions export_options;
  export_options.maps.gltf = false;
  ExportMapsStreamed(reader, dir / "export", export_options);

  const nlohmann::json views = ReadJsonFile(dir / "viewer" / "viewer.json")["views"];
  ASSERT_EQ(views.size(), 3u);
  const PyramidLayout layout(40, 40, 16);
  ImageReadOptions codes;
  codes.colour_space = ColourSpace::kLinear;
  const std::pair<const char*, const char*> expected[] = {
      {"normal", "normal.png"}, {"albedo", "albedo.png"}, {"height", "height.png"}};
  for (std::size_t i = 0; i < 3; ++i) {
    SCOPED_TRACE(expected[i].first);
    const nlohmann::json& view = views[i];
    EXPECT_EQ(view["name"], expected[i].first);
    EXPECT_EQ(view["source"], "gradient");
    EXPECT_EQ(view["data"]["layers"], 1);
    EXPECT_EQ(view["data"]["maps"], i == 2 ? 1 : 3);
    EXPECT_EQ(view["data"]["pyramid"]["levels"], layout.levels());
    const Image map = ReadImage(dir / "export" / expected[i].second, codes).image;
    const Image tiles =
        ReassembleLevel0(dir / "viewer" / view["data"]["pyramid"]["folder"].get<std::string>(),
                         layout, map.channels());
    ASSERT_TRUE(tiles.SameShape(map));
    for (std::size_t v = 0; v < map.values().size(); ++v) {
      ASSERT_EQ(tiles.values()[v], map.values()[v]) << v;
    }
  }
  // The views are not constant: a bricks relief has slopes and albedo edges.
  const Image normal = ReadImage(dir / "export" / "normal.png", codes).image;
  const auto [low, high] = std::minmax_element(normal.values().begin(), normal.values().end());
  EXPECT_GT(*high - *low, 0.1f);
}

TEST(ViewerDisplayPyramidsTest, OnlyMethodsWithNormalsGiveDisplayMaps) {
  const auto synthetic = testing::LambertianSet(SurfacePattern::kBumps, 12);
  EXPECT_TRUE(GivesDisplayMaps(Fit(synthetic.set, Method::Parse("gradient"))));
  EXPECT_TRUE(GivesDisplayMaps(Fit(synthetic.set, Method::Parse("ptm"))));
  EXPECT_FALSE(GivesDisplayMaps(Fit(synthetic.set, Method::Parse("eigen3"))));
}

}  // namespace
}  // namespace photomat
