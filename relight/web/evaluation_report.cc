#include "relight/web/evaluation_report.h"

#include <fmt/format.h>
#include <tbb/parallel_for.h>

#include <algorithm>
#include <cmath>
#include <limits>
#include <numeric>
#include <optional>
#include <span>

#include "core/atomic_file.h"
#include "core/error.h"
#include "core/image_io.h"
#include "core/json_file.h"
#include "core/markup.h"
#include "core/memory_limits.h"
#include "relight/render/display_image.h"
#include "relight/render/output_folder.h"
#include "relight/web/published_name.h"
#include "relight/web/report_charts.h"
#include "relight/web/report_pictures.h"
#include "represent/fitting/fit.h"
#include "represent/model/method.h"
#include "represent/stack/stack_band_reader.h"
#include "represent/streaming/streamed_folds.h"

namespace photomat {
namespace {

namespace fs = std::filesystem;

constexpr const char* kReportFormat = "photomat-report";
constexpr const char* kReportManifest = "report.json";

double Percentile(std::vector<double> values, double fraction) {
  if (values.empty()) return 0.0;
  const auto k = static_cast<std::size_t>(std::clamp(fraction, 0.0, 1.0) * (values.size() - 1));
  std::nth_element(values.begin(), values.begin() + k, values.end());
  return values[k];
}

// The photograph and its relightings are brightened alike when the photograph is dark, so that a
// DiLiGenT image (values around 0.1) shows: its 99.5th percentile goes to 0.8, never darker.
double DisplayGain(const Image& captured, const Mask& mask) {
  std::vector<double> values;
  for (std::size_t p = 0; p < captured.pixel_count(); ++p) {
    if (!mask[p]) continue;
    for (float v : captured.pixel(p)) values.push_back(v);
  }
  const double high = Percentile(values, 0.995);
  return high > 0.0 ? std::clamp(0.8 / high, 1.0, 64.0) : 1.0;
}

Image Scaled(Image image, double gain) {
  for (float& v : image.values()) v = static_cast<float>(v * gain);
  return image;
}

void WriteDisplayImage(const fs::path& path, const Image& linear) {
  ImageWriteOptions options;
  options.sample_type = SampleType::kUint8;
  options.encoding = ColourSpace::kSrgb;
  WriteImage(path, linear, options);
}

std::string LightText(const LightDirection& l) {
  return fmt::format("slant {:.1f}&#176;, tilt {:.1f}&#176;", l.SlantDegrees(), l.TiltDegrees());
}

const char* kStyle = R"(
body { font: 15px/1.45 system-ui, sans-serif; color: #1d1f23; margin: 24px auto; max-width: 1100px; padding: 0 16px; }
h1 { font-size: 24px; margin-bottom: 4px; }
h2 { font-size: 19px; margin-top: 32px; border-bottom: 1px solid #ddd; padding-bottom: 4px; }
h3 { font-size: 16px; margin: 16px 0 4px; }
.meta { color: #555; }
table { border-collapse: collapse; margin: 8px 0; }
th, td { padding: 4px 10px; border-bottom: 1px solid #e3e3e3; text-align: right; }
th:first-child, td:first-child { text-align: left; }
thead th { background: #f3f4f6; }
.chart { width: 100%; max-width: 760px; height: auto; display: block; }
.chart text { font: 12px system-ui, sans-serif; fill: #333; }
.chart .title { font-size: 14px; font-weight: 600; }
.colour-bar text { font: 11px system-ui, sans-serif; fill: #333; }
.grid { display: flex; flex-wrap: wrap; gap: 14px; }
figure { margin: 0; }
figcaption { font-size: 13px; color: #444; max-width: 220px; }
img.pixels { image-rendering: pixelated; min-width: 200px; max-width: 280px; height: auto; background: #222; }
.compare td, .compare th { vertical-align: top; text-align: center; border: none; }
.compare th { min-width: 130px; }
.compare img { display: block; margin: 0 auto; }
.note { color: #555; font-size: 13px; }
)";

}  // namespace

std::vector<int> ChooseReportImages(const std::vector<LightDirection>& lights, int count) {
  const int n = static_cast<int>(lights.size());
  count = std::min(count, n);
  if (count <= 0) return {};
  const LightDirection start = LightDirection::FromSlantTilt(45.0, 0.0);
  std::vector<int> chosen;
  std::vector<double> distance(n);
  for (int i = 0; i < n; ++i) distance[i] = lights[i].AngleToDegrees(start);
  chosen.push_back(
      static_cast<int>(std::min_element(distance.begin(), distance.end()) - distance.begin()));
  std::fill(distance.begin(), distance.end(), INFINITY);
  while (static_cast<int>(chosen.size()) < count) {
    for (int i = 0; i < n; ++i) {
      distance[i] = std::min(distance[i], lights[i].AngleToDegrees(lights[chosen.back()]));
    }
    chosen.push_back(
        static_cast<int>(std::max_element(distance.begin(), distance.end()) - distance.begin()));
  }
  std::sort(chosen.begin(), chosen.end());
  return chosen;
}

namespace {

// The report's ranking section: mean ranks, the Friedman test, pairwise p-values, the diagram.
std::string RankingSection(const MethodComparison& c) {
  const FriedmanTest& f = c.friedman;
  std::string html = fmt::format(
      "<section id=\"ranking\">\n<h2>Ranking of methods</h2>\n<p class=\"note\">Each of the {} "
      "predicted images ranks the methods ({} ranks 1; ties share their mean rank). The "
      "Friedman test asks whether the methods differ at all; the Nemenyi test compares every "
      "pair (p-values adjusted for the {} pairs); methods joined by a bar in the diagram differ "
      "by less than the critical difference.</p>\n"
      "<table class=\"ranking\">\n<thead><tr><th>rank</th><th>method</th><th>mean rank</th>"
      "<th>mean {}</th></tr></thead>\n<tbody>\n",
      c.images.size(), RankingMeasureBest(c.measure, /*html=*/true),
      c.methods.size() * (c.methods.size() - 1) / 2, RankingMeasureLabel(c.measure, /*html=*/true));
  const std::vector<int> order = c.RankOrder();
  for (std::size_t r = 0; r < order.size(); ++r) {
    const int m = order[r];
    html += fmt::format("<tr><td>{}</td><td>{}</td><td>{:.2f}</td><td>{:.5f}</td></tr>\n", r + 1,
                        EscapeMarkup(c.methods[m]), f.mean_ranks[m], c.mean_values[m]);
  }
  html += fmt::format(
      "</tbody>\n</table>\n<p class=\"friedman\">Friedman &#967;&#178; = {:.2f} ({} degrees of "
      "freedom, corrected for ties), p = {}; Kendall's W = {:.3f}; Iman&#8211;Davenport F = {}, "
      "p = {}. Nemenyi critical difference at &#945; = {}: {:.2f} mean ranks.</p>\n",
      f.chi_square, f.degrees_of_freedom, FormatPValue(f.p_value), f.kendalls_w,
      std::isfinite(f.iman_davenport_f) ? fmt::format("{:.2f}", f.iman_davenport_f) : "&#8734;",
      FormatPValue(f.iman_davenport_p_value), c.alpha, c.critical_difference);
  html += CriticalDifferenceDiagramSvg(c) + "\n<table class=\"pairwise\">\n<thead><tr><th></th>";
  for (int m : order) html += "<th>" + EscapeMarkup(c.methods[m]) + "</th>";
  html += "</tr></thead>\n<tbody>\n";
  for (int i : order) {
    html += "<tr><td>" + EscapeMarkup(c.methods[i]) + "</td>";
    for (int j : order) {
      html += i == j ? std::string("<td>&#8211;</td>")
                     : fmt::format("<td{}>{}</td>",
                                   c.pairwise_p(i, j) < c.alpha ? " class=\"significant\"" : "",
                                   FormatPValue(c.pairwise_p(i, j)));
    }
    html += "</tr>\n";
  }
  return html + "</tbody>\n</table>\n</section>\n";
}

// Where image `index` sits in an evaluation's prediction_images, or -1 when it was not predicted.
int PredictionPosition(const MethodEvaluation& e, int index) {
  const auto found = std::find(e.prediction_images.begin(), e.prediction_images.end(), index);
  return found == e.prediction_images.end() ? -1
                                            : static_cast<int>(found - e.prediction_images.begin());
}

// What the report shows, decided from the evaluations alone (in memory and streamed alike).
struct ReportPlan {
  bool prediction = false;
  // Held-out evaluation (EvaluationOptions::hold_out_every): one fit without the predicted images
  // predicts each of them, instead of one fit per image. Empty for leave-one-out.
  std::vector<int> held_out;
  std::vector<int> kept_images;  // the images of the held-out fit
  std::vector<int> shown;        // the captured images shown beside their relighting
  bool any_normals = false;
};

ReportPlan PlanReport(const fs::path& folder, int images, const std::vector<LightDirection>& lights,
                      const std::vector<MethodEvaluation>& evaluations,
                      const EvaluationReportOptions& options) {
  if (evaluations.empty()) throw Error(folder, "no evaluation to report");
  for (const MethodEvaluation& e : evaluations) {
    if (static_cast<int>(e.reconstruction_per_image.size()) != images) {
      throw Error(folder, fmt::format("the {} evaluation has {} images, the set {}",
                                      e.method.Name(), e.reconstruction_per_image.size(), images));
    }
  }
  ReportPlan plan;
  plan.prediction = std::all_of(evaluations.begin(), evaluations.end(),
                                [](const auto& e) { return e.eta_prediction.has_value(); });
  if (plan.prediction && static_cast<int>(evaluations.front().prediction_images.size()) < images) {
    plan.held_out = evaluations.front().prediction_images;
  }
  for (const MethodEvaluation& e : evaluations) {
    if (plan.prediction && !plan.held_out.empty() && e.prediction_images != plan.held_out) {
      throw Error(folder, fmt::format("{} and {} predicted different images",
                                      evaluations.front().method.Name(), e.method.Name()));
    }
  }
  for (int i = 0; i < images; ++i) {
    if (std::find(plan.held_out.begin(), plan.held_out.end(), i) == plan.held_out.end()) {
      plan.kept_images.push_back(i);
    }
  }
  plan.shown = options.images;
  if (plan.shown.empty() && plan.held_out.empty()) plan.shown = ChooseReportImages(lights);
  if (plan.shown.empty()) {
    // By default the report shows held-out images, whose predictions it can show.
    std::vector<LightDirection> held_out_lights;
    for (int i : plan.held_out) held_out_lights.push_back(lights[i]);
    for (int i : ChooseReportImages(held_out_lights)) plan.shown.push_back(plan.held_out[i]);
  }
  for (int i : plan.shown) {
    if (i < 0 || i >= images) {
      throw Error(fmt::format("image {} is not in the set (0 to {})", i, images - 1));
    }
  }
  plan.any_normals = std::any_of(evaluations.begin(), evaluations.end(),
                                 [](const auto& e) { return e.normals.has_value(); });
  return plan;
}

// The robust options `method` was fitted with by the evaluation (none: least squares).
const std::optional<RobustFitOptions>& FitOptionsFor(const Method& method,
                                                     const EvaluationReportOptions& options) {
  if (method.kind == Method::Kind::kPbr && options.pbr_robust) return options.pbr_robust;
  return options.robust;
}

// The set as the page states it.
struct ReportSet {
  fs::path source;
  int images = 0, width = 0, height = 0, channels = 0;
  std::size_t pixels = 0;  // evaluated (the mask's)
  std::vector<LightDirection> lights;
  std::vector<std::string> names;
};

// The report's pictures at display size (report_pictures.h), gathered band by band (each picture
// in row order): the mask, the captured images shown, every method's relighting of their lights
// and, where they were predicted, their prediction; and the normal error maps. Pictures of
// different methods or shown images may be added from different threads at once.
class ReportPictures {
 public:
  ReportPictures(int width, int height, int channels, const ReportPlan& plan,
                 const std::vector<MethodEvaluation>& evaluations, bool truth)
      : factor_(ReportDisplayFactor(width, height)),
        mask_(width, height, 1, factor_),
        relit_(evaluations.size()),
        predicted_(evaluations.size()),
        errors_(evaluations.size()) {
    const auto reduction = [&] { return DisplayReduction(width, height, channels, factor_); };
    for (std::size_t s = 0; s < plan.shown.size(); ++s) captured_.push_back(reduction());
    for (std::size_t m = 0; m < evaluations.size(); ++m) {
      for (int index : plan.shown) {
        relit_[m].push_back(reduction());
        predicted_[m].emplace_back();
        if (plan.prediction && PredictionPosition(evaluations[m], index) >= 0) {
          predicted_[m].back().emplace(reduction());
        }
      }
      if (truth && evaluations[m].normals) {
        errors_[m].emplace(width, height, 1, factor_, /*skip_negative=*/true);
      }
    }
  }

  int factor() const { return factor_; }
  void AddMask(int first, const Mask& band) {
    Image values(band.width(), band.height(), 1);
    for (std::size_t p = 0; p < band.pixel_count(); ++p) values.values()[p] = band[p] ? 1.0f : 0.0f;
    mask_.Add(first, values.View());
  }
  void AddCaptured(std::size_t shown, int first, ConstImageView band) {
    captured_[shown].Add(first, band);
  }
  void AddRelit(std::size_t method, std::size_t shown, int first, ConstImageView band) {
    relit_[method][shown].Add(first, band);
  }
  void AddPredicted(std::size_t method, std::size_t shown, int first, ConstImageView band) {
    predicted_[method][shown]->Add(first, band);
  }
  bool WantsErrors(std::size_t method) const { return errors_[method].has_value(); }
  void AddErrors(std::size_t method, int first, ConstImageView band) {
    errors_[method]->Add(first, band);
  }

  // The reduced mask: a display pixel is set when any pixel of its block is.
  Mask DisplayMask() const {
    const Image mean = mask_.Result();
    Mask mask(mean.width(), mean.height(), false);
    for (std::size_t p = 0; p < mean.pixel_count(); ++p) mask.Set(p, mean.values()[p] > 0.0f);
    return mask;
  }
  Image Captured(std::size_t shown) const { return captured_[shown].Result(); }
  Image Relit(std::size_t method, std::size_t shown) const {
    return relit_[method][shown].Result();
  }
  // None where the image was not predicted. Rows a prediction never reached (bands the mask left
  // empty, which a streamed fold skips) count as 0, the fit's value outside the mask.
  std::optional<Image> Predicted(std::size_t method, std::size_t shown) {
    std::optional<DisplayReduction>& predicted = predicted_[method][shown];
    if (!predicted) return std::nullopt;
    predicted->CountMissingRowsAsZero();
    return predicted->Result();
  }
  // None without truth or when the method gives no normals (EstimateNormals).
  std::optional<Image> Errors(std::size_t method) const {
    const std::optional<DisplayReduction>& errors = errors_[method];
    return errors && errors->has_rows() ? std::optional(errors->Result()) : std::nullopt;
  }

 private:
  int factor_;
  DisplayReduction mask_;
  std::vector<DisplayReduction> captured_;
  std::vector<std::vector<DisplayReduction>> relit_;
  std::vector<std::vector<std::optional<DisplayReduction>>> predicted_;
  std::vector<std::optional<DisplayReduction>> errors_;
};

// The error map of a band's fit against its truth, when the method gives normals.
void AddNormalErrors(ReportPictures& pictures, std::size_t method, int first,
                     const Representation& fit, const Image& truth, const Mask& mask) {
  if (!pictures.WantsErrors(method)) return;
  if (const auto normals = EstimateNormals(fit)) {
    pictures.AddErrors(method, first, AngularErrorMap(*normals, truth, mask).View());
  }
}

// The page's head and its first line: the set and the kind of fits.
std::string PageHead(const ReportSet& info, const EvaluationReportOptions& options) {
  return fmt::format(
      "<!doctype html>\n<html lang=\"en\">\n<head>\n<meta charset=\"utf-8\">\n"
      "<title>{0}</title>\n<link rel=\"icon\" href=\"data:,\">\n<style>{1}</style>\n</head>\n"
      "<body>\n<h1>{0}</h1>\n<p class=\"meta\">{2}: {3} images of {4}&#215;{5} pixels, {6} "
      "channel(s), {7} pixels evaluated; {8} fits.</p>\n",
      EscapeMarkup(options.title), kStyle, EscapeMarkup(PublishedName(info.source)), info.images,
      info.width, info.height, info.channels, info.pixels,
      options.robust ? "robust" : "least-squares");
}

// Whether any evaluation has the value `has` looks for.
template <typename Has>
bool AnyEvaluation(const std::vector<MethodEvaluation>& evaluations, Has has) {
  return std::any_of(evaluations.begin(), evaluations.end(), has);
}

// The table of errors per method: eta, the predictions' PSNR, SSIM and colour difference where
// the evaluation measured them, and the normal errors where truth exists.
std::string ErrorTable(const std::vector<MethodEvaluation>& evaluations, const ReportPlan& plan) {
  std::string html =
      "<h2>Errors per method</h2>\n<p class=\"note\">Dong's eta "
      "(thesis eq. 4.5.1): the mean over images of the RMS of relit minus captured, over "
      "the standard deviation of the captured image. Reconstruction: the fit of all images "
      "relit at each; prediction: " +
      (plan.held_out.empty()
           ? std::string("each image relit by a fit that left it out")
           : fmt::format("each of the {} held-out images relit by the fit of the other {}",
                         plan.held_out.size(), plan.kept_images.size())) +
      ".</p>\n";
  const bool psnr =
      AnyEvaluation(evaluations, [](const auto& e) { return e.psnr_prediction.has_value(); });
  const bool ssim =
      AnyEvaluation(evaluations, [](const auto& e) { return e.ssim_prediction.has_value(); });
  const bool colour = AnyEvaluation(
      evaluations, [](const auto& e) { return e.delta_e2000_prediction.has_value(); });
  if (ssim || colour) {
    html +=
        "<p class=\"note\">PSNR, SSIM and mean CIEDE2000 colour difference of the predicted "
        "images against the captured ones over the mask, with the captured image's largest "
        "value as white (SSIM and colour difference of the sRGB renderings).</p>\n";
  }
  html +=
      "<table class=\"eta\">\n<thead><tr><th>method</th><th>eta reconstruction</th>"
      "<th>eta prediction</th>";
  if (psnr) html += "<th>PSNR (dB)</th>";
  if (ssim) html += "<th>SSIM</th>";
  if (colour) html += "<th>&#916;E 2000</th>";
  if (plan.any_normals) {
    html +=
        "<th>normal mean (&#176;)</th><th>median (&#176;)</th><th>&lt; 5&#176;</th>"
        "<th>&lt; 10&#176;</th>";
  }
  html += "</tr></thead>\n<tbody>\n";
  const auto cell = [](const std::optional<double>& value, int decimals) {
    return fmt::format("<td>{}</td>",
                       value ? fmt::format("{:.{}f}", *value, decimals) : std::string("–"));
  };
  for (const MethodEvaluation& e : evaluations) {
    html += fmt::format("<tr><td>{}</td><td>{:.5f}</td>{}", EscapeMarkup(e.method.Name()),
                        e.eta_reconstruction, cell(e.eta_prediction, 5));
    if (psnr) html += cell(e.psnr_prediction, 2);
    if (ssim) html += cell(e.ssim_prediction, 4);
    if (colour) html += cell(e.delta_e2000_prediction, 3);
    if (plan.any_normals) {
      html += e.normals
                  ? fmt::format("<td>{:.2f}</td><td>{:.2f}</td><td>{:.1f} %</td><td>{:.1f} %</td>",
                                e.normals->mean_degrees, e.normals->median_degrees,
                                100 * e.normals->fraction_below_5_degrees,
                                100 * e.normals->fraction_below_10_degrees)
                  : "<td>–</td><td>–</td><td>–</td><td>–</td>";
    }
    html += "</tr>\n";
  }
  return html + "</tbody>\n</table>\n";
}

// The charts: eta per method, the normal errors per method, and each method's error per image.
std::string Charts(const std::vector<MethodEvaluation>& evaluations, const ReportPlan& plan,
                   int images) {
  BarChart summary{"eta per method",      "eta", {}, {{"reconstruction", {}}},
                   "chart summary-chart", ""};
  if (plan.prediction) summary.series.push_back({"prediction", {}});
  for (const MethodEvaluation& e : evaluations) {
    summary.categories.push_back(e.method.Name());
    summary.series[0].values.push_back(e.eta_reconstruction);
    if (plan.prediction) summary.series[1].values.push_back(*e.eta_prediction);
  }
  std::string html = "<h2>Charts</h2>\n" + BarChartSvg(summary) + "\n";
  if (plan.any_normals) {
    BarChart normal_chart{"normal angular error", "degrees", {}, {{"mean", {}}, {"median", {}}},
                          "chart normal-chart",   ""};
    for (const MethodEvaluation& e : evaluations) {
      if (!e.normals) continue;
      normal_chart.categories.push_back(e.method.Name());
      normal_chart.series[0].values.push_back(e.normals->mean_degrees);
      normal_chart.series[1].values.push_back(e.normals->median_degrees);
    }
    html += BarChartSvg(normal_chart) + "\n";
  }
  html += "<h2>Per-image error of each method</h2>\n";
  for (const MethodEvaluation& e : evaluations) {
    BarChart chart{
        fmt::format("{}: eta per image", e.method.Name()), "e_k / sigma_k",      {},
        {{"reconstruction", e.reconstruction_per_image}},  "chart method-chart", e.method.Name()};
    if (!e.prediction_per_image.empty()) {
      // By image index: images that were not predicted draw no bar.
      std::vector<double> predicted(images, std::numeric_limits<double>::quiet_NaN());
      for (std::size_t i = 0; i < e.prediction_images.size(); ++i) {
        predicted[e.prediction_images[i]] = e.prediction_per_image[i];
      }
      chart.series.push_back({"prediction", predicted});
    }
    for (int i = 0; i < images; ++i) chart.categories.push_back(std::to_string(i));
    html += BarChartSvg(chart) + "\n";
  }
  return html;
}

// The normal error heat maps, on one scale for every method (written into `temp`/images); empty
// when no method has them.
std::string NormalErrorSection(const fs::path& temp,
                               const std::vector<MethodEvaluation>& evaluations,
                               const std::vector<std::optional<Image>>& errors) {
  if (std::none_of(errors.begin(), errors.end(), [](const auto& e) { return e.has_value(); })) {
    return {};
  }
  std::vector<double> all;
  for (const auto& map : errors) {
    if (!map) continue;
    for (float v : map->values()) {
      if (v >= 0.0f) all.push_back(v);
    }
  }
  const double scale = std::max(5.0, 5.0 * std::ceil(Percentile(all, 0.95) / 5.0));
  std::string html = fmt::format(
      "<h2>Normal angular error</h2>\n<p class=\"note\">Angle between each "
      "method's normals and the ground truth, per pixel, on one scale for all "
      "methods (0 to {} degrees; larger errors show as red, pixels without "
      "truth grey).</p>\n{}\n<div class=\"grid\">\n",
      ReportNumber(scale), ColourBarSvg(scale));
  for (std::size_t m = 0; m < evaluations.size(); ++m) {
    if (!errors[m]) continue;
    const std::string name = evaluations[m].method.Name();
    const std::string file = fmt::format("images/normal-error-{}.png", name);
    WriteDisplayCodes(temp / file, HeatMap(*errors[m], scale));
    html += fmt::format(
        "<figure><img class=\"pixels heat-map\" src=\"{}\" alt=\"normal error "
        "of {}\"><figcaption>{}: mean {:.2f}&#176;, median {:.2f}&#176;"
        "</figcaption></figure>\n",
        file, EscapeMarkup(name), EscapeMarkup(name), evaluations[m].normals->mean_degrees,
        evaluations[m].normals->median_degrees);
  }
  return html + "</div>\n";
}

// The cell of a method's prediction of shown image `index` (its picture written into
// `temp`/images), or a note where the image was not predicted.
std::string PredictedCell(const fs::path& temp, const MethodEvaluation& e, int index,
                          const std::optional<Image>& prediction, double gain) {
  if (!prediction) return "<td class=\"note\">not held out</td>";
  const std::string name = e.method.Name();
  const std::string predicted = fmt::format("images/predicted-{}-{}.png", name, index);
  WriteDisplayImage(temp / predicted, Scaled(*prediction, gain));
  const auto position = static_cast<std::size_t>(PredictionPosition(e, index));
  // The in-memory evaluation's appearance measures of this image, when it has them.
  std::string appearance;
  if (!e.ssim_prediction_per_image.empty()) {
    appearance += fmt::format(", SSIM {:.3f}", e.ssim_prediction_per_image[position]);
  }
  if (!e.delta_e2000_prediction_per_image.empty()) {
    appearance += fmt::format(", &#916;E {:.2f}", e.delta_e2000_prediction_per_image[position]);
  }
  return fmt::format(
      "<td><img class=\"pixels\" src=\"{}\" alt=\"{} predicted\"><br>e/&#963; {}{}</td>", predicted,
      EscapeMarkup(name), ReportNumber(e.prediction_per_image[position]), appearance);
}

// The note above the table of captured and relit pictures.
std::string CapturedAndRelitNote(const ReportPlan& plan, int factor) {
  return "<h2>Captured and relit</h2>\n<p class=\"note\">Each row: a captured image and every "
         "method's relighting of its light by the fit of all images" +
         std::string(!plan.prediction ? ""
                     : plan.held_out.empty()
                         ? ", and below it the prediction by a fit without that image"
                         : ", and below it, for a held-out image, its prediction by "
                           "the fit without the held-out images") +
         ". Values shown through the sRGB curve; a dark row is brightened by the stated "
         "factor, the same for every image in it." +
         (factor > 1 ? fmt::format(" Pictures are shown at 1/{} of the images' size, each pixel "
                                   "the mean of a {}&#215;{} block.",
                                   factor, factor, factor)
                     : std::string()) +
         "</p>\n";
}

// The table of each shown image beside every method's relighting of its light and, below, their
// predictions (the pictures written into `temp`/images).
std::string CapturedAndRelitSection(const fs::path& temp, const ReportSet& info,
                                    const std::vector<MethodEvaluation>& evaluations,
                                    const ReportPlan& plan, ReportPictures& pictures,
                                    const Mask& mask) {
  std::string html = CapturedAndRelitNote(plan, pictures.factor()) +
                     "<table class=\"compare\">\n<tr><th></th><th>captured</th>";
  for (const MethodEvaluation& e : evaluations) {
    html += "<th>" + EscapeMarkup(e.method.Name()) + "</th>";
  }
  html += "</tr>\n";
  for (std::size_t s = 0; s < plan.shown.size(); ++s) {
    const int index = plan.shown[s];
    const Image captured_image = pictures.Captured(s);
    const double gain = DisplayGain(captured_image, mask);
    const std::string captured = fmt::format("images/captured-{}.png", index);
    WriteDisplayImage(temp / captured, Scaled(captured_image, gain));
    html += fmt::format(
        "<tr class=\"relit-row\"><th>image {}<br>{}<br>{}{}</th><td><img "
        "class=\"pixels\" src=\"{}\" alt=\"captured image {}\"></td>",
        index, EscapeMarkup(fs::path(info.names[index]).filename().string()),
        LightText(info.lights[index]),
        gain > 1.0 ? fmt::format("<br>shown &#215;{:.2g}", gain) : "", captured, index);
    std::string predicted_row = "<tr class=\"predicted-row\"><th>predicted</th><td></td>";
    for (std::size_t m = 0; m < evaluations.size(); ++m) {
      const std::string name = evaluations[m].method.Name();
      const std::string relit = fmt::format("images/relit-{}-{}.png", name, index);
      WriteDisplayImage(temp / relit, Scaled(pictures.Relit(m, s), gain));
      html += fmt::format(
          "<td><img class=\"pixels\" src=\"{}\" alt=\"{} relit\"><br>e/&#963; {}</td>", relit,
          EscapeMarkup(name), ReportNumber(evaluations[m].reconstruction_per_image[index]));
      if (plan.prediction) {
        predicted_row += PredictedCell(temp, evaluations[m], index, pictures.Predicted(m, s), gain);
      }
    }
    html += "</tr>\n";
    if (plan.prediction) html += predicted_row + "</tr>\n";
  }
  return html + "</table>\n";
}

// Writes the page, its pictures and report.json into `folder`, whole or not at all.
void WriteReportFolder(const fs::path& folder, const ReportSet& info,
                       const std::vector<MethodEvaluation>& evaluations, const ReportPlan& plan,
                       ReportPictures& pictures, const EvaluationReportOptions& options) {
  const Mask mask = pictures.DisplayMask();
  std::vector<std::optional<Image>> errors;
  for (std::size_t m = 0; m < evaluations.size(); ++m) errors.push_back(pictures.Errors(m));
  WriteFolderAtomically(folder, kReportManifest, kReportFormat, [&](const fs::path& temp) {
    fs::create_directories(temp / "images");
    std::string html = PageHead(info, options) + ErrorTable(evaluations, plan);
    if (options.comparison) html += RankingSection(*options.comparison);
    html += Charts(evaluations, plan, info.images) + NormalErrorSection(temp, evaluations, errors) +
            CapturedAndRelitSection(temp, info, evaluations, plan, pictures, mask) +
            "<p class=\"note\">Written by photomat. report.json holds the numbers.</p>\n"
            "</body>\n</html>\n";
    WriteTextFileAtomically(temp / "index.html", html);
    WriteJsonFile(temp / kReportManifest,
                  {{"format", kReportFormat},
                   {"version", 1},
                   {"title", options.title},
                   {"source", PublishedName(info.source)},
                   {"images_shown", plan.shown},
                   {"display_factor", pictures.factor()},
                   {"evaluation", EvaluationsToJson(evaluations)},
                   {"comparison",
                    options.comparison ? options.comparison->ToJson() : nlohmann::json(nullptr)}});
  });
}

// The prediction folds of the shown images: leave-one-out, one fold per shown image that was
// predicted; held out, the one fold without the held-out images, predicting those shown.
std::vector<PredictionFold> ShownFolds(const ReportPlan& plan, int images) {
  if (!plan.prediction) return {};
  if (!plan.held_out.empty()) {
    PredictionFold fold{plan.kept_images, {}};
    for (int index : plan.shown) {
      if (std::find(plan.held_out.begin(), plan.held_out.end(), index) != plan.held_out.end()) {
        fold.predicted.push_back(index);
      }
    }
    return fold.predicted.empty() ? std::vector<PredictionFold>{} : std::vector{fold};
  }
  std::vector<PredictionFold> folds;
  for (int index : plan.shown) {
    PredictionFold fold{{}, {index}};
    for (int i = 0; i < images; ++i) {
      if (i != index) fold.fitted.push_back(i);
    }
    folds.push_back(std::move(fold));
  }
  return folds;
}

}  // namespace

void WriteEvaluationReport(const fs::path& folder, const PhotometricSet& set,
                           const std::vector<MethodEvaluation>& evaluations, const Image* truth,
                           const EvaluationReportOptions& options) {
  const ReportPlan plan = PlanReport(folder, set.size(), set.lights(), evaluations, options);
  NullProgress no_progress;
  Progress& progress = OrNull(options.progress, no_progress);
  const Mask mask = set.MaskOrAll();
  const Observations observations(set);
  // The fits as the evaluation made them: least squares, or robust with its options.
  const auto fit = [&](const Method& method, std::span<const int> selected) {
    const std::optional<RobustFitOptions>& options_for = FitOptionsFor(method, options);
    if (!options_for) {
      return FitObservations(observations, set.lights(), method, selected, set.source());
    }
    RobustFitOptions robust = *options_for;
    robust.progress = nullptr;
    return RobustFit(observations, set.lights(), selected, robust, set.source()).Fit(method);
  };
  // The pictures in one band each.
  ReportPictures pictures(set.width(), set.height(), set.channels(), plan, evaluations,
                          truth != nullptr);
  pictures.AddMask(0, mask);
  for (std::size_t s = 0; s < plan.shown.size(); ++s) {
    pictures.AddCaptured(s, 0, set.image(plan.shown[s]).View());
  }
  std::vector<int> every_image(set.size());
  std::iota(every_image.begin(), every_image.end(), 0);
  const std::vector<PredictionFold> folds = ShownFolds(plan, set.size());
  progress.Start("report", evaluations.size());
  for (std::size_t m = 0; m < evaluations.size(); ++m) {
    const Method& method = evaluations[m].method;
    const Representation all = fit(method, every_image);
    for (std::size_t s = 0; s < plan.shown.size(); ++s) {
      pictures.AddRelit(m, s, 0, all.Relight(set.light(plan.shown[s])).View());
    }
    if (truth) AddNormalErrors(pictures, m, 0, all, *truth, mask);
    for (const PredictionFold& fold : folds) {
      std::optional<Representation> fold_fit;
      for (std::size_t s = 0; s < plan.shown.size(); ++s) {
        const int index = plan.shown[s];
        if (std::find(fold.predicted.begin(), fold.predicted.end(), index) ==
                fold.predicted.end() ||
            PredictionPosition(evaluations[m], index) < 0) {
          continue;
        }
        if (!fold_fit) fold_fit = fit(method, fold.fitted);
        pictures.AddPredicted(m, s, 0, fold_fit->Relight(set.light(index)).View());
      }
    }
    progress.Advance();
  }
  progress.Finish();
  const ReportSet info{set.source(),   set.size(),      set.width(),  set.height(),
                       set.channels(), mask.CountSet(), set.lights(), set.image_names()};
  WriteReportFolder(folder, info, evaluations, plan, pictures, options);
}

namespace {

// The fits' stacks and the truth, opened and checked against the set's size.
struct StreamedReportInputs {
  std::vector<StackBandReader> fits;
  std::optional<ImageBandReader> truth;
  std::size_t stored_channels = 0;  // of all fits
};

StreamedReportInputs OpenReportInputs(const fs::path& folder, const StreamedSet& set,
                                      std::span<const fs::path> stacks, std::size_t evaluations,
                                      const std::optional<fs::path>& truth) {
  if (stacks.size() != evaluations) {
    throw Error(folder, fmt::format("{} stacks for {} evaluations", stacks.size(), evaluations));
  }
  const auto check_size = [&](const fs::path& path, int w, int h) {
    if (w != set.width() || h != set.height()) {
      throw Error(path,
                  fmt::format("{}x{}, but the images are {}x{}", w, h, set.width(), set.height()));
    }
  };
  StreamedReportInputs inputs;
  for (const fs::path& path : stacks) {
    const StackBandReader& fit = inputs.fits.emplace_back(path);
    check_size(path, fit.width(), fit.height());
    inputs.stored_channels += static_cast<std::size_t>(fit.stored_channels());
  }
  if (truth) {
    inputs.truth.emplace(*truth);
    check_size(*truth, inputs.truth->width(), inputs.truth->height());
  }
  return inputs;
}

// Pass 1: the photographs shown, every fit's relighting of them and its normal errors. Only the
// shown photographs are decoded (a subset of the set, opened anew). Returns the pixels the mask
// sets.
std::size_t GatherRelitPictures(StreamedSet& set, StreamedReportInputs& inputs,
                                const ReportPlan& plan, int band_rows, ReportPictures& pictures,
                                Progress& progress) {
  const int width = set.width(), height = set.height();
  std::optional<StreamedSet> shown;
  if (!plan.shown.empty()) shown.emplace(set.Subset(plan.shown));
  std::size_t pixels = 0;
  progress.Start("report: pictures",
                 static_cast<std::size_t>((height + band_rows - 1) / band_rows));
  for (int first = 0; first < height; first += band_rows) {
    const int rows = std::min(band_rows, height - first);
    const Mask mask = set.MaskRows(first, rows);
    pixels += mask.CountSet();
    pictures.AddMask(first, mask);
    if (shown) {
      const PhotometricSet band = shown->ReadBand(rows);
      for (std::size_t s = 0; s < plan.shown.size(); ++s) {
        pictures.AddCaptured(s, first, band.image(static_cast<int>(s)).View());
      }
    }
    std::optional<Image> truth_band;
    if (inputs.truth) {
      truth_band.emplace(width, rows, inputs.truth->channels());
      inputs.truth->ReadNext(truth_band->View());
    }
    for (std::size_t m = 0; m < inputs.fits.size(); ++m) {
      const LoadedStack fit = inputs.fits[m].ReadNext(rows);
      tbb::parallel_for(std::size_t{0}, plan.shown.size(), [&](std::size_t s) {
        pictures.AddRelit(m, s, first,
                          fit.representation.Relight(set.lights()[plan.shown[s]]).View());
      });
      if (truth_band) AddNormalErrors(pictures, m, first, fit.representation, *truth_band, mask);
    }
    progress.Advance();
  }
  progress.Finish();
  return pixels;
}

// Pass 2: the shown images' predictions, by their folds fitted band by band; pbr in a pass of
// its own when it was fitted with options of its own.
void GatherPredictedPictures(StreamedSet& set, const std::vector<MethodEvaluation>& evaluations,
                             const ReportPlan& plan, const EvaluationReportOptions& options,
                             const StreamedReportOptions& bands, ReportPictures& pictures) {
  const std::vector<PredictionFold> folds = ShownFolds(plan, set.size());
  if (folds.empty()) return;
  for (const bool pbr_pass : {false, true}) {
    std::vector<std::size_t> members;
    std::vector<Method> methods;
    for (std::size_t m = 0; m < evaluations.size(); ++m) {
      const Method& method = evaluations[m].method;
      if ((method.kind == Method::Kind::kPbr && options.pbr_robust) != pbr_pass) continue;
      members.push_back(m);
      methods.push_back(method);
    }
    if (members.empty()) continue;
    FoldFitOptions fold_options;
    fold_options.memory_bytes = bands.memory_bytes;
    fold_options.band_rows = bands.band_rows;
    fold_options.robust = FitOptionsFor(methods.front(), options);
    fold_options.progress = options.progress;
    const auto add_prediction = [&](const FoldFit& fold) {
      const std::size_t m = members[fold.method];
      const std::vector<int>& predicted = folds[fold.fold].predicted;
      for (std::size_t s = 0; s < plan.shown.size(); ++s) {
        const int index = plan.shown[s];
        if (std::find(predicted.begin(), predicted.end(), index) == predicted.end() ||
            PredictionPosition(evaluations[m], index) < 0) {
          continue;
        }
        pictures.AddPredicted(m, s, fold.first_row, fold.fit.Relight(set.lights()[index]).View());
      }
    };
    VisitFoldFits(set, methods, folds, add_prediction, fold_options);
  }
}

}  // namespace

void WriteEvaluationReportStreamed(const fs::path& folder, StreamedSet& set,
                                   std::span<const fs::path> stacks,
                                   const std::vector<MethodEvaluation>& evaluations,
                                   const std::optional<fs::path>& truth,
                                   const EvaluationReportOptions& options,
                                   const StreamedReportOptions& bands) {
  const ReportPlan plan = PlanReport(folder, set.size(), set.lights(), evaluations, options);
  StreamedReportInputs inputs = OpenReportInputs(folder, set, stacks, evaluations.size(), truth);
  const int width = set.width(), height = set.height();
  NullProgress no_progress;
  Progress& progress = OrNull(options.progress, no_progress);
  // A band holds the shown photographs' band, every fit's band and the truth's (floats), and a
  // relit image, normals and errors at a time.
  const std::size_t pixel_bytes =
      4 * (plan.shown.size() * static_cast<std::size_t>(set.channels()) + inputs.stored_channels +
           3 + 8);
  const int band_rows = BudgetedBandRows(bands.band_rows, bands.memory_bytes, kMinimumReportMemory,
                                         static_cast<std::size_t>(width) * pixel_bytes, height);
  ReportPictures pictures(width, height, set.channels(), plan, evaluations, truth.has_value());
  const std::size_t pixels = GatherRelitPictures(set, inputs, plan, band_rows, pictures, progress);
  GatherPredictedPictures(set, evaluations, plan, options, bands, pictures);
  const ReportSet info{set.source(),   set.size(), width,        height,
                       set.channels(), pixels,     set.lights(), set.image_names()};
  WriteReportFolder(folder, info, evaluations, plan, pictures, options);
}

}  // namespace photomat
