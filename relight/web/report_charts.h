#pragma once

#include <array>
#include <string>
#include <utility>
#include <vector>

#include "core/image.h"
#include "represent/evaluation/method_comparison.h"

namespace photomat {

// The evaluation report's graphics (evaluation_report.h): inline SVG charts, the critical-
// difference diagram, the heat colour scale of normal errors, and numbers as the page prints
// them. Each returns markup or colours; nothing here writes files.

// A number as the report prints it: four significant digits, "–" when not finite.
std::string ReportNumber(double value);

// A grouped bar chart as inline SVG: one group of bars per category, one bar per series.
struct BarChart {
  struct Series {
    std::string name;
    std::vector<double> values;  // one per category; non-finite values draw no bar
  };
  std::string title;
  std::string y_label;
  std::vector<std::string> categories;
  std::vector<Series> series;
  std::string css_class = "chart";
  std::string method;  // data-method attribute, for per-method charts
};
std::string BarChartSvg(const BarChart& chart);

// Demsar's critical-difference diagram as inline SVG (<svg class="cd-diagram">): the mean-rank axis
// with the best rank on the right, each method's mean rank marked and labelled, the critical
// difference as a bar above the axis, and a thick line joining each largest run of methods (in
// rank order) whose mean ranks differ by less than it: methods the Nemenyi test cannot tell apart.
std::string CriticalDifferenceDiagramSvg(const MethodComparison& comparison);

// The runs the diagram joins: [first, last] positions in rank order (MethodComparison::RankOrder),
// each a largest run of two or more methods spanning less than the critical difference.
std::vector<std::pair<int, int>> IndistinguishableRuns(const MethodComparison& comparison);

// Per-pixel angle in degrees between estimated and true normals (one channel), where the mask is
// set and the truth is a normal (as CompareNormals counts pixels); -1 elsewhere.
Image AngularErrorMap(const Image& estimated, const Image& truth, const Mask& mask);

// The report's colour scale: dark blue (0) through cyan, green and yellow to red (1 and above).
std::array<float, 3> HeatColour(double fraction);
// Display colours (RGB in [0, 1], to be stored as 8-bit codes) of an AngularErrorMap; grey where
// the error is undefined.
Image HeatMap(const Image& errors, double max_degrees);
// The heat scale as an SVG bar from 0 to `max_degrees`, ticks every 1, 2 or 5 x 10^k degrees.
std::string ColourBarSvg(double max_degrees);

}  // namespace photomat
