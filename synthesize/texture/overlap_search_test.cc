#include "synthesize/texture/overlap_search.h"

#include <gtest/gtest.h>

#include <ostream>
#include <string>

#include "core/error.h"
#include "core/random.h"

namespace photomat {
namespace {

Image RandomMaps(int width, int height, int channels, std::uint64_t seed) {
  Image image(width, height, channels);
  Random random(seed);
  for (float& v : image.values()) v = static_cast<float>(random.Uniform());
  return image;
}

// A sample that repeats itself every 8 pixels: several candidates match a copied block exactly.
Image PeriodicMaps(int width, int height, int channels) {
  const Image tile = RandomMaps(8, 8, channels, 77);
  Image image(width, height, channels);
  for (int y = 0; y < height; ++y) {
    for (int x = 0; x < width; ++x) {
      for (int c = 0; c < channels; ++c) image.at(x, y, c) = tile.at(x % 8, y % 8, c);
    }
  }
  return image;
}

// A template of `shape` taken from the space at `from`, plus noise of `noise`.
OverlapTemplate TemplateFrom(const Image& space, const OverlapShape& shape, SamplePixel from,
                             double noise, Random& random) {
  OverlapTemplate pattern(shape, space.channels());
  for (int v = 0; v < shape.block; ++v) {
    for (int u = 0; u < shape.block; ++u) {
      if (!shape.Contains(u, v)) continue;
      for (int c = 0; c < space.channels(); ++c) {
        pattern.at(u, v, c) =
            static_cast<float>(space.at(from.x + u, from.y + v, c) + noise * random.Normal());
      }
    }
  }
  return pattern;
}

TEST(OverlapSearchTest, ExactErrorIsTheSumOverTheOverlap) {
  const Image maps = RandomMaps(20, 16, 3, 1);
  const Image space = ChannelTransform::Fit(maps, {}).Apply(maps);
  Random random(2);
  const OverlapShape shape{6, 2, 1, 0, 1};
  const OverlapTemplate pattern = TemplateFrom(space, shape, {3, 4}, 0.1, random);
  for (ErrorMetric metric : {ErrorMetric::kSsd, ErrorMetric::kSad}) {
    const OverlapSearch search(space, 6, metric, 1);
    double expected = 0.0;
    for (int v = 0; v < 6; ++v) {
      for (int u = 0; u < 6; ++u) {
        if (!(u < 2 || v < 1 || v >= 5)) continue;
        for (int c = 0; c < 3; ++c) {
          const double d = static_cast<double>(space.at(9 + u, 7 + v, c)) - pattern.at(u, v, c);
          expected += metric == ErrorMetric::kSsd ? d * d : std::abs(d);
        }
      }
    }
    EXPECT_NEAR(search.ExactError(pattern, {9, 7}), expected, 1e-9 * expected);
  }
}

struct SearchCase {
  ErrorMetric metric;
  int stride;
  OverlapShape shape;
  double noise;
  double tolerance;
  double floor;
  bool periodic;
  const char* name;  // the test's name suffix (gtest names value-parameterised cases by index or
                     // by the parameter's bytes otherwise, which include padding)
};

void PrintTo(const SearchCase& test, std::ostream* out) { *out << test.name; }

class FastSearchTest : public ::testing::TestWithParam<SearchCase> {};

// The heart of "fast search equals brute force": the same candidates, in the same order, held to
// the bit-identical threshold, so the same random draw picks the same block.
TEST_P(FastSearchTest, QualifiesExactlyTheBruteForceCandidates) {
  const SearchCase& test = GetParam();
  const int channels = 4;
  const Image maps =
      test.periodic ? PeriodicMaps(37, 29, channels) : RandomMaps(37, 29, channels, 3);
  MatchingOptions matching;
  matching.metric = test.metric;
  const Image space = ChannelTransform::Fit(maps, matching).Apply(maps);
  Random random(11);
  for (int trial = 0; trial < 6; ++trial) {
    const SamplePixel from{static_cast<int>(random.Index(37 - test.shape.block)),
                           static_cast<int>(random.Index(29 - test.shape.block))};
    const OverlapTemplate pattern = TemplateFrom(space, test.shape, from, test.noise, random);
    OverlapSearch search(space, test.shape.block, test.metric, test.stride);
    const QualifyingBlocks brute =
        search.Qualifying(pattern, test.tolerance, test.floor, SearchMode::kBruteForce);
    const QualifyingBlocks fast =
        search.Qualifying(pattern, test.tolerance, test.floor, SearchMode::kFast);
    EXPECT_EQ(brute.rescored, search.candidate_count());
    EXPECT_LE(fast.rescored, brute.rescored);
    ASSERT_FALSE(brute.positions.empty());
    EXPECT_EQ(fast.positions, brute.positions) << "trial " << trial;
    EXPECT_EQ(fast.threshold, brute.threshold);
  }
}

INSTANTIATE_TEST_SUITE_P(
    Shapes, FastSearchTest,
    ::testing::Values(
        SearchCase{ErrorMetric::kSsd, 1, {8, 2, 0, 0, 0}, 0.05, 0.1, 0.0, false, "SsdLeft"},
        SearchCase{ErrorMetric::kSsd, 1, {8, 2, 2, 0, 0}, 0.05, 0.1, 0.0, false, "SsdLeftTop"},
        SearchCase{ErrorMetric::kSsd, 3, {9, 3, 2, 2, 1}, 0.2, 0.0, 0.0, false, "SsdStride3"},
        SearchCase{ErrorMetric::kSsd, 1, {8, 2, 2, 0, 0}, 0.0, 0.1, 0.0, true, "SsdExactTies"},
        SearchCase{ErrorMetric::kSsd, 1, {8, 0, 3, 0, 0}, 0.0, 0.1, 2.0, true, "SsdFloor"},
        SearchCase{ErrorMetric::kSad, 1, {8, 2, 2, 0, 0}, 0.05, 0.1, 0.0, false, "SadLeftTop"},
        SearchCase{ErrorMetric::kSad, 2, {7, 2, 1, 1, 2}, 0.1, 0.5, 0.0, false, "SadStride2"},
        SearchCase{ErrorMetric::kSad, 1, {8, 2, 2, 0, 0}, 0.0, 0.1, 0.0, true, "SadExactTies"},
        SearchCase{ErrorMetric::kSad, 1, {8, 2, 0, 0, 0}, 0.0, 0.1, 3.0, true, "SadFloor"}),
    [](const ::testing::TestParamInfo<SearchCase>& case_info) {
      return std::string(case_info.param.name);
    });

TEST(OverlapSearchTest, FindsACopiedBlockWithZeroError) {
  const Image maps = RandomMaps(30, 30, 3, 4);
  const Image space = ChannelTransform::Fit(maps, {}).Apply(maps);
  Random random(1);
  const OverlapTemplate pattern = TemplateFrom(space, {8, 2, 2, 0, 0}, {13, 5}, 0.0, random);
  OverlapSearch search(space, 8, ErrorMetric::kSsd, 1);
  const QualifyingBlocks found = search.Qualifying(pattern, 0.1, 0.0, SearchMode::kFast);
  ASSERT_EQ(found.positions.size(), 1u);  // random data: only the source matches exactly
  EXPECT_EQ(found.positions[0], (SamplePixel{13, 5}));
  EXPECT_EQ(found.threshold, 0.0);
  // The bounds are tight: only a handful of candidates need their exact sums.
  EXPECT_LT(found.rescored, search.candidate_count() / 20);
  // A floor lets near matches qualify too.
  const QualifyingBlocks floored = search.Qualifying(pattern, 0.1, 1e9, SearchMode::kFast);
  EXPECT_EQ(floored.positions.size(), static_cast<std::size_t>(search.candidate_count()));
}

TEST(OverlapSearchTest, CandidatesFollowTheStride) {
  const Image maps = RandomMaps(30, 20, 1, 4);
  const Image space = ChannelTransform::Fit(maps, {}).Apply(maps);
  const OverlapSearch every(space, 8, ErrorMetric::kSsd, 1);
  EXPECT_EQ(every.candidate_count(), 23 * 13);
  const OverlapSearch grid(space, 8, ErrorMetric::kSsd, 8);
  EXPECT_EQ(grid.candidate_count(), 3 * 2);
  EXPECT_EQ(grid.Candidate(4), (SamplePixel{8, 8}));
  EXPECT_THROW(OverlapSearch(space, 21, ErrorMetric::kSsd, 1), Error);
  EXPECT_THROW(OverlapSearch(space, 8, ErrorMetric::kSsd, 0), Error);
  EXPECT_EQ(ParseSearchMode("brute"), SearchMode::kBruteForce);
  EXPECT_THROW(ParseSearchMode("fft"), Error);
}

}  // namespace
}  // namespace photomat
