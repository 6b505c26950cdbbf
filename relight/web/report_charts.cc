#include "relight/web/report_charts.h"

#include <fmt/format.h>

#include <Eigen/Core>
#include <algorithm>
#include <cmath>

#include "core/error.h"
#include "core/light_direction.h"
#include "core/markup.h"

namespace photomat {
namespace {

constexpr std::array<const char*, 4> kSeriesColours = {"#4e79a7", "#f28e2b", "#59a14f", "#e15759"};

// Anchors of the heat colour scale, evenly spaced over [0, 1], linear in between.
constexpr std::array<std::array<float, 3>, 5> kHeatAnchors = {{{0.05f, 0.05f, 0.35f},
                                                               {0.10f, 0.45f, 0.85f},
                                                               {0.25f, 0.80f, 0.55f},
                                                               {0.95f, 0.85f, 0.20f},
                                                               {0.85f, 0.15f, 0.10f}}};
constexpr float kUndefinedGrey = 0.18f;

// 1, 2 or 5 times a power of ten, so that about `ticks` steps cover `top`.
double NiceStep(double top, int ticks) {
  const double raw = top / ticks;
  const double power = std::pow(10.0, std::floor(std::log10(raw)));
  for (double m : {1.0, 2.0, 5.0, 10.0}) {
    if (m * power >= raw) return m * power;
  }
  return 10.0 * power;
}

std::string HexColour(const std::array<float, 3>& rgb) {
  const auto code = [](float v) {
    return static_cast<int>(std::lround(std::clamp(v, 0.0f, 1.0f) * 255));
  };
  return fmt::format("#{:02x}{:02x}{:02x}", code(rgb[0]), code(rgb[1]), code(rgb[2]));
}

}  // namespace

std::string ReportNumber(double value) {
  if (!std::isfinite(value)) return "–";
  return fmt::format("{:.4g}", value);
}

std::string ColourBarSvg(double max_degrees) {
  std::string svg = fmt::format(
      "<svg class=\"colour-bar\" viewBox=\"0 0 320 44\" width=\"320\" height=\"44\" role=\"img\" "
      "aria-label=\"colour scale from 0 to {} degrees\">\n<defs><linearGradient id=\"heat\">",
      ReportNumber(max_degrees));
  for (std::size_t i = 0; i < kHeatAnchors.size(); ++i) {
    svg +=
        fmt::format("<stop offset=\"{}\" stop-color=\"{}\"/>",
                    static_cast<double>(i) / (kHeatAnchors.size() - 1), HexColour(kHeatAnchors[i]));
  }
  svg +=
      "</linearGradient></defs>\n<rect x=\"10\" y=\"4\" width=\"300\" height=\"16\" "
      "fill=\"url(#heat)\"/>\n";
  const double step = NiceStep(max_degrees, 5);
  for (double tick = 0.0; tick <= max_degrees + 1e-9; tick += step) {
    const double x = 10.0 + 300.0 * tick / max_degrees;
    svg += fmt::format(
        "<line x1=\"{0:.1f}\" x2=\"{0:.1f}\" y1=\"20\" y2=\"25\" stroke=\"#333\"/>"
        "<text x=\"{0:.1f}\" y=\"38\" text-anchor=\"middle\">{1}&#176;</text>\n",
        x, ReportNumber(tick));
  }
  return svg + "</svg>";
}

std::array<float, 3> HeatColour(double fraction) {
  const double f = std::clamp(std::isfinite(fraction) ? fraction : 1.0, 0.0, 1.0);
  const double position = f * (kHeatAnchors.size() - 1);
  const auto i = std::min(static_cast<std::size_t>(position), kHeatAnchors.size() - 2);
  const auto t = static_cast<float>(position - i);
  std::array<float, 3> rgb;
  for (int c = 0; c < 3; ++c) rgb[c] = (1 - t) * kHeatAnchors[i][c] + t * kHeatAnchors[i + 1][c];
  return rgb;
}

Image AngularErrorMap(const Image& estimated, const Image& truth, const Mask& mask) {
  if (estimated.width() != truth.width() || estimated.height() != truth.height() ||
      estimated.channels() < 3 || truth.channels() < 3) {
    throw Error(fmt::format("normals {}x{}x{} and truth {}x{}x{} do not match", estimated.width(),
                            estimated.height(), estimated.channels(), truth.width(), truth.height(),
                            truth.channels()));
  }
  Image errors(truth.width(), truth.height(), std::vector<std::string>{"error_deg"});
  for (std::size_t p = 0; p < truth.pixel_count(); ++p) {
    const auto t = truth.pixel(p);
    const auto e = estimated.pixel(p);
    const Eigen::Vector3d tv(t[0], t[1], t[2]), ev(e[0], e[1], e[2]);
    const bool valid = (mask.width() != truth.width() || mask[p]) && tv.squaredNorm() >= 0.25 &&
                       ev.squaredNorm() != 0.0;
    errors.pixel(p)[0] = valid ? static_cast<float>(AngleBetweenDegrees(tv, ev)) : -1.0f;
  }
  return errors;
}

Image HeatMap(const Image& errors, double max_degrees) {
  Image colours(errors.width(), errors.height(), 3);
  for (std::size_t p = 0; p < errors.pixel_count(); ++p) {
    const float e = errors.pixel(p)[0];
    const std::array<float, 3> rgb =
        e < 0.0f ? std::array{kUndefinedGrey, kUndefinedGrey, kUndefinedGrey}
                 : HeatColour(e / max_degrees);
    std::copy(rgb.begin(), rgb.end(), colours.pixel(p).begin());
  }
  return colours;
}

std::string BarChartSvg(const BarChart& chart) {
  constexpr double kWidth = 760, kHeight = 290;
  constexpr double kLeft = 60, kRight = 16, kTop = 40, kBottom = 46;
  const double plot_width = kWidth - kLeft - kRight, plot_height = kHeight - kTop - kBottom;
  double top = 0.0;
  for (const auto& s : chart.series) {
    for (double v : s.values) {
      if (std::isfinite(v)) top = std::max(top, v);
    }
  }
  const double step = NiceStep(top > 0.0 ? top : 1.0, 5);
  top = step * std::ceil((top > 0.0 ? top : 1.0) / step - 1e-9);
  const auto y_of = [&](double v) { return kTop + plot_height * (1.0 - v / top); };

  std::string svg = fmt::format(
      "<svg class=\"{}\" viewBox=\"0 0 {} {}\" width=\"{}\" height=\"{}\" role=\"img\" "
      "aria-label=\"{}\"{}>\n",
      EscapeMarkup(chart.css_class), kWidth, kHeight, kWidth, kHeight, EscapeMarkup(chart.title),
      chart.method.empty() ? "" : fmt::format(" data-method=\"{}\"", EscapeMarkup(chart.method)));
  svg += fmt::format("<text class=\"title\" x=\"{}\" y=\"20\">{}</text>\n", kLeft,
                     EscapeMarkup(chart.title));
  // Legend, right-aligned in the title row.
  double legend_x = kWidth - kRight;
  for (std::size_t s = chart.series.size(); s-- > 0;) {
    legend_x -= 14.0 + 7.5 * chart.series[s].name.size() + 16.0;
    svg += fmt::format(
        "<rect x=\"{:.1f}\" y=\"10\" width=\"12\" height=\"12\" fill=\"{}\"/>"
        "<text x=\"{:.1f}\" y=\"20\">{}</text>\n",
        legend_x, kSeriesColours[s % kSeriesColours.size()], legend_x + 16,
        EscapeMarkup(chart.series[s].name));
  }
  // Axes and grid.
  for (double tick = 0.0; tick <= top + 1e-9 * top; tick += step) {
    const double y = y_of(tick);
    svg += fmt::format(
        "<line x1=\"{}\" x2=\"{}\" y1=\"{:.1f}\" y2=\"{:.1f}\" stroke=\"#e3e3e3\"/>"
        "<text x=\"{}\" y=\"{:.1f}\" text-anchor=\"end\">{}</text>\n",
        kLeft, kWidth - kRight, y, y, kLeft - 6, y + 4, ReportNumber(tick));
  }
  svg += fmt::format(
      "<text x=\"14\" y=\"{:.1f}\" transform=\"rotate(-90 14 {:.1f})\" "
      "text-anchor=\"middle\">{}</text>\n",
      kTop + plot_height / 2, kTop + plot_height / 2, EscapeMarkup(chart.y_label));
  svg +=
      fmt::format("<line x1=\"{0}\" x2=\"{1}\" y1=\"{2:.1f}\" y2=\"{2:.1f}\" stroke=\"#333\"/>\n",
                  kLeft, kWidth - kRight, kTop + plot_height);
  // Bars.
  const std::size_t categories = std::max<std::size_t>(chart.categories.size(), 1);
  const double group = plot_width / categories;
  const double bar = group * 0.8 / std::max<std::size_t>(chart.series.size(), 1);
  const std::size_t label_every = (chart.categories.size() + 39) / 40;
  for (std::size_t c = 0; c < chart.categories.size(); ++c) {
    const double group_x = kLeft + c * group + group * 0.1;
    for (std::size_t s = 0; s < chart.series.size(); ++s) {
      if (c >= chart.series[s].values.size()) continue;
      const double v = chart.series[s].values[c];
      if (!std::isfinite(v)) continue;
      const double y = y_of(std::max(v, 0.0));
      svg += fmt::format(
          "<rect class=\"bar\" x=\"{:.2f}\" y=\"{:.2f}\" width=\"{:.2f}\" height=\"{:.2f}\" "
          "fill=\"{}\" data-value=\"{}\"><title>{}, {}: {}</title></rect>\n",
          group_x + s * bar, y, std::max(bar - 0.5, 0.5), kTop + plot_height - y,
          kSeriesColours[s % kSeriesColours.size()], v, EscapeMarkup(chart.categories[c]),
          EscapeMarkup(chart.series[s].name), ReportNumber(v));
    }
    if (c % label_every == 0) {
      svg += fmt::format("<text x=\"{:.1f}\" y=\"{:.1f}\" text-anchor=\"middle\">{}</text>\n",
                         kLeft + (c + 0.5) * group, kTop + plot_height + 16,
                         EscapeMarkup(chart.categories[c]));
    }
  }
  return svg + "</svg>";
}

std::vector<std::pair<int, int>> IndistinguishableRuns(const MethodComparison& comparison) {
  const std::vector<int> order = comparison.RankOrder();
  const auto rank = [&](int position) { return comparison.friedman.mean_ranks[order[position]]; };
  std::vector<std::pair<int, int>> runs;
  const int k = static_cast<int>(order.size());
  int covered = 0;  // the last position a run already reaches
  for (int first = 0; first < k; ++first) {
    int last = first;
    while (last + 1 < k && rank(last + 1) - rank(first) < comparison.critical_difference) ++last;
    if (last > first && last > covered) {
      runs.emplace_back(first, last);
      covered = last;
    }
  }
  return runs;
}

std::string CriticalDifferenceDiagramSvg(const MethodComparison& comparison) {
  const std::vector<int> order = comparison.RankOrder();
  const int k = static_cast<int>(order.size());
  const std::vector<double>& ranks = comparison.friedman.mean_ranks;
  constexpr double kWidth = 760, kAxisLeft = 190, kAxisRight = 570, kAxisY = 64, kRowStep = 22;
  const double unit = (kAxisRight - kAxisLeft) / std::max(k - 1, 1);
  // Rank 1 (best) on the right, as Demsar draws it.
  const auto x_of = [&](double rank) { return kAxisRight - (rank - 1.0) * unit; };
  const std::vector<std::pair<int, int>> runs = IndistinguishableRuns(comparison);
  const double first_row = kAxisY + 20 + 8.0 * runs.size();
  const int right_count = (k + 1) / 2;  // the better half is labelled on the right
  const double height = first_row + kRowStep * std::max(right_count, k - right_count) + 8;

  std::string svg = fmt::format(
      "<svg class=\"cd-diagram\" viewBox=\"0 0 {0} {1:.0f}\" width=\"{0}\" height=\"{1:.0f}\" "
      "role=\"img\" aria-label=\"critical difference diagram: mean ranks of the methods, "
      "critical difference {2:.2f}\" data-critical-difference=\"{2}\">\n",
      kWidth, height, comparison.critical_difference);
  // The critical difference, above the axis from its left end.
  const double cd_end = std::min(kAxisLeft + comparison.critical_difference * unit, kWidth - 10);
  svg += fmt::format(
      "<g class=\"cd-bar\"><line x1=\"{0}\" x2=\"{1:.1f}\" y1=\"18\" y2=\"18\" stroke=\"#333\" "
      "stroke-width=\"2\"/><line x1=\"{0}\" x2=\"{0}\" y1=\"13\" y2=\"23\" stroke=\"#333\"/>"
      "<line x1=\"{1:.1f}\" x2=\"{1:.1f}\" y1=\"13\" y2=\"23\" stroke=\"#333\"/>"
      "<text x=\"{2:.1f}\" y=\"10\" text-anchor=\"middle\">CD = {3:.2f}</text></g>\n",
      kAxisLeft, cd_end, 0.5 * (kAxisLeft + cd_end), comparison.critical_difference);
  svg += fmt::format(
      "<line x1=\"{0}\" x2=\"{1}\" y1=\"{2}\" y2=\"{2}\" stroke=\"#333\" stroke-width=\"1.5\"/>\n",
      kAxisLeft, kAxisRight, kAxisY);
  for (int tick = 1; tick <= k; ++tick) {
    svg += fmt::format(
        "<line x1=\"{0:.1f}\" x2=\"{0:.1f}\" y1=\"{1}\" y2=\"{2}\" stroke=\"#333\"/>"
        "<text x=\"{0:.1f}\" y=\"{3}\" text-anchor=\"middle\">{4}</text>\n",
        x_of(tick), kAxisY - 6, kAxisY, kAxisY - 10, tick);
  }
  for (std::size_t g = 0; g < runs.size(); ++g) {
    const double y = kAxisY + 12 + 8.0 * g;
    svg += fmt::format(
        "<line class=\"cd-group\" x1=\"{:.1f}\" x2=\"{:.1f}\" y1=\"{:.1f}\" y2=\"{:.1f}\" "
        "stroke=\"#111\" stroke-width=\"4\" stroke-linecap=\"round\"/>\n",
        x_of(ranks[order[runs[g].first]]) + 3, x_of(ranks[order[runs[g].second]]) - 3, y, y);
  }
  for (int position = 0; position < k; ++position) {
    const int m = order[position];
    const bool right = position < right_count;
    // Rows from the top: the best method on the right, the worst on the left.
    const int row = right ? position : k - 1 - position;
    const double x = x_of(ranks[m]), y = first_row + kRowStep * row;
    const double end = right ? kAxisRight + 24 : kAxisLeft - 24;
    svg += fmt::format(
        "<g class=\"cd-method\" data-cd-method=\"{0}\" data-mean-rank=\"{1}\">"
        "<polyline points=\"{2:.1f},{3} {2:.1f},{4:.1f} {5:.1f},{4:.1f}\" fill=\"none\" "
        "stroke=\"#4e79a7\"/><circle cx=\"{2:.1f}\" cy=\"{3}\" r=\"3\" fill=\"#4e79a7\"/>"
        "<text x=\"{6:.1f}\" y=\"{7:.1f}\" text-anchor=\"{8}\">{0} ({1:.2f})</text></g>\n",
        EscapeMarkup(comparison.methods[m]), ranks[m], x, kAxisY, y, end, end + (right ? 4 : -4),
        y + 4, right ? "start" : "end");
  }
  return svg + "</svg>";
}

}  // namespace photomat
