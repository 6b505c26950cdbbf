#include "relight/web/report_charts.h"

#include <gtest/gtest.h>

#include <Eigen/Geometry>
#include <cmath>
#include <numbers>
#include <regex>

#include "tests/support/synthetic_sets.h"
#include "tests/support/test_support.h"

namespace photomat {
namespace {

TEST(ReportChartsTest, AngularErrorMapAndHeatMapShowAKnownRotation) {
  // Each true normal is the estimate turned by exactly 12 degrees (about an axis perpendicular to
  // it): every valid pixel errs by 12 degrees.
  const auto synthetic = testing::LambertianSet(SurfacePattern::kBricks, 16);
  const Image& estimated = synthetic.material.normals;
  Image truth = estimated;
  for (std::size_t p = 0; p < truth.pixel_count(); ++p) {
    const auto n = estimated.pixel(p);
    const Eigen::Vector3d v(n[0], n[1], n[2]);
    const Eigen::Vector3d axis = v.cross(Eigen::Vector3d(0.3, 0.5, 0.8));
    const Eigen::Vector3d r =
        Eigen::AngleAxisd(12.0 * std::numbers::pi / 180.0, axis.normalized()) * v;
    for (int c = 0; c < 3; ++c) truth.pixel(p)[c] = static_cast<float>(r[c]);
  }
  for (int c = 0; c < 3; ++c) truth.at(3, 4, c) = 0.0f;  // no truth at (3, 4)
  Mask mask(16, 16, true);
  mask.Set(5, 5, false);
  const Image errors = AngularErrorMap(estimated, truth, mask);
  const Image heat = HeatMap(errors, 24.0);
  const auto expected = HeatColour(0.5);
  for (int y = 0; y < 16; ++y) {
    for (int x = 0; x < 16; ++x) {
      const bool undefined = (x == 3 && y == 4) || (x == 5 && y == 5);
      if (undefined) {
        EXPECT_EQ(errors.at(x, y, 0), -1.0f);
        EXPECT_NEAR(heat.at(x, y, 0), heat.at(x, y, 2), 1e-6);  // grey
        continue;
      }
      ASSERT_NEAR(errors.at(x, y, 0), 12.0, 1e-3);
      for (int c = 0; c < 3; ++c) EXPECT_NEAR(heat.at(x, y, c), expected[c], 1e-4);
    }
  }
  // The scale runs from dark blue to red and clamps above.
  EXPECT_LT(HeatColour(0.0)[0], 0.1f);
  EXPECT_GT(HeatColour(0.0)[2], 0.3f);
  EXPECT_GT(HeatColour(1.0)[0], 0.8f);
  EXPECT_EQ(HeatColour(3.0), HeatColour(1.0));
}

TEST(ReportChartsTest, BarChartBarsAreProportionalToTheirValues) {
  BarChart chart{"a <b> & c",     "eta",
                 {"x", "y", "z"}, {{"one", {0.5, 1.0, 2.0}}, {"two", {1.5, NAN, 0.25}}},
                 "chart",         ""};
  const std::string svg = BarChartSvg(chart);
  EXPECT_NE(svg.find("a &lt;b&gt; &amp; c"), std::string::npos);
  const std::regex bar(
      "<rect class=\"bar\"[^>]* height=\"([0-9.]+)\"[^>]* data-value=\"([0-9.e+-]+)\"");
  std::vector<std::pair<double, double>> bars;  // (height, value)
  for (auto it = std::sregex_iterator(svg.begin(), svg.end(), bar); it != std::sregex_iterator();
       ++it) {
    bars.emplace_back(std::stod((*it)[1].str()), std::stod((*it)[2].str()));
  }
  ASSERT_EQ(bars.size(), 5u);  // the NaN draws nothing
  const double per_unit = bars[0].first / bars[0].second;
  for (const auto& [height, value] : bars) EXPECT_NEAR(height, per_unit * value, 0.02);
}

// Demsar (2006), Figure 1(a): at alpha 0.10 (critical difference 1.12) the Nemenyi test joins
// C4.5+m+cf, C4.5+m and C4.5+cf in one group and C4.5+cf and C4.5 in another.
TEST(ReportChartsTest, CriticalDifferenceDiagramJoinsDemsarsTwoGroups) {
  MethodComparison c;
  c.methods = {"C4.5", "C4.5+m", "C4.5+cf", "C4.5+m+cf"};
  c.friedman.mean_ranks = {3.143, 2.000, 2.893, 1.964};
  c.alpha = 0.10;
  c.critical_difference = 1.12;
  EXPECT_EQ(c.RankOrder(), (std::vector<int>{3, 1, 2, 0}));
  EXPECT_EQ(IndistinguishableRuns(c), (std::vector<std::pair<int, int>>{{0, 2}, {2, 3}}));
  const std::string svg = CriticalDifferenceDiagramSvg(c);
  EXPECT_EQ(testing::CountMatches(svg, "class=\"cd-group\""), 2u);
  EXPECT_EQ(testing::CountMatches(svg, "class=\"cd-method\""), 4u);
  EXPECT_NE(svg.find("CD = 1.12"), std::string::npos);
  // The best mean rank lies to the right of the worst.
  const auto x_of = [&](const std::string& name) {
    const std::regex mark("data-cd-method=\"" + std::regex_replace(name, std::regex("\\+"), "\\+") +
                          "\"[^>]*><polyline points=\"([0-9.]+),");
    std::smatch match;
    EXPECT_TRUE(std::regex_search(svg, match, mark)) << name;
    return std::stod(match[1].str());
  };
  EXPECT_GT(x_of("C4.5+m+cf"), x_of("C4.5"));
  // With a critical difference below every gap nothing is joined.
  c.critical_difference = 0.01;
  EXPECT_TRUE(IndistinguishableRuns(c).empty());
}

}  // namespace
}  // namespace photomat
