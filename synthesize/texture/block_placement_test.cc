#include "synthesize/texture/block_placement.h"

#include <gtest/gtest.h>

#include "core/error.h"

namespace photomat {
namespace {

TEST(BlockPlacementTest, PositionsCoverTheOutputWithTheOverlap) {
  for (int extent : {40, 64, 100, 511, 512}) {
    const std::vector<int> positions = BlockPositions(extent, 32, 8, false);
    EXPECT_EQ(positions.front(), 0);
    EXPECT_EQ(positions.back() + 32, extent) << "the last block ends at the edge";
    for (std::size_t i = 1; i < positions.size(); ++i) {
      const int overlap = positions[i - 1] + 32 - positions[i];
      if (i + 1 < positions.size()) {
        EXPECT_EQ(overlap, 8) << extent;
      }
      EXPECT_GE(overlap, 8) << extent;
      EXPECT_LT(overlap, 32) << extent;
    }
  }
  EXPECT_EQ(BlockPositions(20, 32, 8, false), std::vector<int>{0});  // one block, cropped
}

TEST(BlockPlacementTest, TileablePositionsWrapWithBoundedOverlaps) {
  for (int extent : {48, 64, 100, 257, 512}) {
    const std::vector<int> positions = BlockPositions(extent, 32, 8, true);
    ASSERT_GE(positions.size(), 2u);
    EXPECT_EQ(positions.front(), 0);
    for (std::size_t i = 0; i < positions.size(); ++i) {
      const int next = i + 1 < positions.size() ? positions[i + 1] : extent;  // wraps to 0
      const int overlap = positions[i] + 32 - next;
      EXPECT_GE(overlap, 1) << extent;
      EXPECT_LE(overlap, 16) << extent;
    }
  }
  EXPECT_THROW(BlockPositions(30, 32, 8, true), Error);  // one block cannot wrap onto itself
  EXPECT_THROW(BlockPositions(100, 32, 17, false), Error);
  EXPECT_THROW(BlockPositions(100, 32, 0, false), Error);
}

TEST(BlockPlacementTest, OverlapShapeCountsItsPixels) {
  const OverlapShape shapes[] = {
      {8, 2, 0, 0, 0}, {8, 2, 3, 0, 0}, {8, 2, 3, 2, 1}, {8, 4, 0, 4, 0}};
  for (const OverlapShape& shape : shapes) {
    int count = 0;
    for (int v = 0; v < 8; ++v) {
      for (int u = 0; u < 8; ++u) count += shape.Contains(u, v);
    }
    EXPECT_EQ(shape.PixelCount(), count);
  }
}

TEST(BlockPlacementTest, CutsDecideWhichPixelsTakeTheNewBlock) {
  PlacedBlock block;
  block.overlap = {4, 2, 2, 0, 0};
  block.cuts.left = {1, 1, 0, 0};
  block.cuts.top = {1, 0, 1, 1};
  EXPECT_FALSE(block.TakesNew(0, 1));  // left of the vertical cut
  EXPECT_TRUE(block.TakesNew(1, 1));
  EXPECT_FALSE(block.TakesNew(2, 0));  // above the horizontal cut
  EXPECT_TRUE(block.TakesNew(1, 0));   // the horizontal cut passes row 0 at column 1
  EXPECT_TRUE(block.TakesNew(0, 2));   // the vertical cut passes column 0 at row 2
  EXPECT_TRUE(block.TakesNew(3, 3));
}

TEST(BlockPlacementTest, RenderingPastesBlocksInOrderAlongTheirCuts) {
  BlockPlacement placement;
  placement.block_size = 4;
  placement.overlap = 2;
  placement.width = placement.canvas_width = 6;
  placement.height = placement.canvas_height = 4;
  placement.sample_width = placement.sample_height = 10;
  placement.column_positions = {0, 2};
  placement.row_positions = {0};
  PlacedBlock first;
  first.source = {0, 0};
  first.overlap.block = 4;
  PlacedBlock second;
  second.column = 1;
  second.x = 2;
  second.source = {5, 5};
  second.overlap = {4, 2, 0, 0, 0};
  second.cuts.left = {0, 1, 1, 0};  // row 0 and 3 take the new block from column 2 on
  placement.blocks = {first, second};
  const SourceMap map = placement.RenderSourceMap();
  EXPECT_EQ(map.at(2, 0), (SamplePixel{5, 5}));  // on the cut: new
  EXPECT_EQ(map.at(2, 1), (SamplePixel{2, 1}));  // left of the cut: old
  EXPECT_EQ(map.at(3, 1), (SamplePixel{6, 6}));
  EXPECT_EQ(map.at(5, 3), (SamplePixel{8, 8}));
  EXPECT_EQ(map.at(1, 2), (SamplePixel{1, 2}));
}

}  // namespace
}  // namespace photomat
