#include "synthesize/texture/boundary_cut.h"

#include <gtest/gtest.h>

#include <cstdlib>
#include <functional>
#include <limits>

#include "core/error.h"
#include "core/random.h"

namespace photomat {
namespace {

double PathCost(const std::vector<double>& errors, const std::vector<int>& path, int width) {
  double cost = 0.0;
  for (std::size_t r = 0; r < path.size(); ++r) cost += errors[r * width + path[r]];
  return cost;
}

// The cheapest 8-connected path by trying them all.
double CheapestPathByEnumeration(const std::vector<double>& errors, int length, int width) {
  double best = std::numeric_limits<double>::infinity();
  std::vector<int> path(length);
  std::function<void(int)> extend = [&](int row) {
    if (row == length) {
      best = std::min(best, PathCost(errors, path, width));
      return;
    }
    for (int c = 0; c < width; ++c) {
      if (row > 0 && std::abs(c - path[row - 1]) > 1) continue;
      path[row] = c;
      extend(row + 1);
    }
  };
  extend(0);
  return best;
}

TEST(BoundaryCutTest, FindsTheCheapestConnectedPath) {
  Random random(5);
  for (int trial = 0; trial < 20; ++trial) {
    const int length = 6, width = 1 + trial % 5;
    std::vector<double> errors(length * width);
    for (double& e : errors) e = random.Uniform();
    const std::vector<int> path = MinimumErrorPath(errors, length, width);
    ASSERT_EQ(path.size(), static_cast<std::size_t>(length));
    for (int r = 0; r < length; ++r) {
      EXPECT_GE(path[r], 0);
      EXPECT_LT(path[r], width);
      if (r > 0) {
        EXPECT_LE(std::abs(path[r] - path[r - 1]), 1) << "8-connected";
      }
    }
    EXPECT_NEAR(PathCost(errors, path, width), CheapestPathByEnumeration(errors, length, width),
                1e-12);
  }
}

TEST(BoundaryCutTest, FollowsAWanderingValley) {
  const int length = 8, width = 5;
  const std::vector<int> valley = {0, 1, 2, 3, 4, 3, 3, 2};
  std::vector<double> errors(length * width, 1.0);
  for (int r = 0; r < length; ++r) errors[r * width + valley[r]] = 0.0;
  EXPECT_EQ(MinimumErrorPath(errors, length, width), valley);
  EXPECT_THROW(MinimumErrorPath(errors, length, width + 1), Error);
}

TEST(BoundaryCutTest, CutsEveryStripAndCombinesThemInCorners) {
  const int b = 7;
  const OverlapShape shape{b, 2, 3, 2, 1};
  Random random(9);
  std::vector<double> errors(b * b);
  for (double& e : errors) e = random.Uniform();
  const auto at = [&](int u, int v) { return errors[v * b + u]; };
  // Each strip on its own, laid out along the cut (rows for vertical strips, columns for
  // horizontal ones).
  const auto strip = [&](int first, int width, bool vertical) {
    std::vector<double> out;
    for (int along = 0; along < b; ++along) {
      for (int k = 0; k < width; ++k) {
        out.push_back(vertical ? at(first + k, along) : at(along, first + k));
      }
    }
    std::vector<int> path = MinimumErrorPath(out, b, width);
    for (int& p : path) p += first;
    return path;
  };
  const BlockCuts cuts = CutBlock(shape, errors);
  EXPECT_EQ(cuts.left, strip(0, 2, true));
  EXPECT_EQ(cuts.right, strip(b - 2, 2, true));
  EXPECT_EQ(cuts.top, strip(0, 3, false));
  EXPECT_EQ(cuts.bottom, strip(b - 1, 1, false));
  for (int v = 0; v < b; ++v) {
    EXPECT_GE(cuts.left[v], 0);
    EXPECT_LT(cuts.left[v], 2);
    EXPECT_GE(cuts.right[v], b - 2);
    EXPECT_EQ(cuts.bottom[v], b - 1);  // a one-pixel strip: the cut is the strip
  }
  PlacedBlock block;
  block.overlap = shape;
  block.cuts = cuts;
  for (int v = 0; v < b; ++v) {
    for (int u = 0; u < b; ++u) {
      const bool expected =
          u >= cuts.left[v] && u <= cuts.right[v] && v >= cuts.top[u] && v <= cuts.bottom[u];
      EXPECT_EQ(block.TakesNew(u, v), expected) << u << "," << v;
    }
  }
  EXPECT_TRUE(CutBlock({b, 0, 0, 0, 0}, errors).left.empty());
  EXPECT_THROW(CutBlock(shape, std::vector<double>(10)), Error);
}

}  // namespace
}  // namespace photomat
