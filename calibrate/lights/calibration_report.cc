#include "calibrate/lights/calibration_report.h"

#include <fmt/format.h>

#include <algorithm>
#include <cmath>
#include <numbers>
#include <numeric>

#include "core/atomic_file.h"
#include "core/error.h"
#include "core/markup.h"

namespace photomat {
namespace {

constexpr double kPi = std::numbers::pi;
// Plot geometry (SVG user units): the hemisphere's centre and the radius of slant 90.
constexpr double kCentreX = 300.0, kCentreY = 330.0, kRadius = 250.0;

// Plot position of a light: radius proportional to slant (capped at the rim), y up.
std::pair<double, double> PlotPoint(const LightDirection& light) {
  const double slant = std::min(light.SlantDegrees(), 90.0);
  const double tilt = light.TiltDegrees() * kPi / 180.0;
  const double r = kRadius * slant / 90.0;
  return {kCentreX + r * std::cos(tilt), kCentreY - r * std::sin(tilt)};
}

void CheckSizes(const LightCalibrationReport& report) {
  if (!report.reference.empty() && report.reference.size() != report.recovered.size()) {
    throw Error(fmt::format("{} recovered lights but {} reference lights", report.recovered.size(),
                            report.reference.size()));
  }
  if (!report.uncertainty_degrees.empty() &&
      report.uncertainty_degrees.size() != report.recovered.size()) {
    throw Error(fmt::format("{} recovered lights but {} uncertainties", report.recovered.size(),
                            report.uncertainty_degrees.size()));
  }
}

// "0.12" degrees, or "?" for an unknown uncertainty.
std::string UncertaintyText(double degrees) {
  return std::isfinite(degrees) ? fmt::format("{:.2f}", degrees) : "?";
}

}  // namespace

std::vector<double> LightCalibrationReport::AngularDifferences() const {
  CheckSizes(*this);
  std::vector<double> differences;
  for (std::size_t i = 0; i < reference.size(); ++i) {
    differences.push_back(recovered[i].AngleToDegrees(reference[i]));
  }
  return differences;
}

LightCalibrationReport::Summary LightCalibrationReport::DifferenceSummary() const {
  std::vector<double> d = AngularDifferences();
  Summary summary;
  if (d.empty()) return summary;
  summary.mean = std::accumulate(d.begin(), d.end(), 0.0) / static_cast<double>(d.size());
  summary.max = *std::max_element(d.begin(), d.end());
  std::sort(d.begin(), d.end());
  const std::size_t n = d.size();
  summary.median = n % 2 ? d[n / 2] : 0.5 * (d[n / 2 - 1] + d[n / 2]);
  return summary;
}

std::string LightCalibrationReport::ToTable() const {
  const std::vector<double> differences = AngularDifferences();
  const bool has_uncertainty = !uncertainty_degrees.empty();
  std::string table;
  for (const std::string& note : notes) table += note + "\n";
  table += fmt::format("{:>4}  {:<24} {:>8} {:>8}", "#", "image", "slant", "tilt");
  if (has_uncertainty) table += fmt::format(" {:>8}", "+-deg");
  if (!differences.empty())
    table += fmt::format(" {:>10} {:>9} {:>10}", "ref slant", "ref tilt", "angle (deg)");
  table += "\n";
  for (std::size_t i = 0; i < recovered.size(); ++i) {
    const std::string name = i < names.size() ? names[i] : fmt::format("light {}", i);
    table += fmt::format("{:>4}  {:<24} {:>8.2f} {:>8.2f}", i, name, recovered[i].SlantDegrees(),
                         recovered[i].TiltDegrees());
    if (has_uncertainty) table += fmt::format(" {:>8}", UncertaintyText(uncertainty_degrees[i]));
    if (!differences.empty()) {
      table += fmt::format(" {:>10.2f} {:>9.2f} {:>10.2f}", reference[i].SlantDegrees(),
                           reference[i].TiltDegrees(), differences[i]);
    }
    table += "\n";
  }
  if (!differences.empty()) {
    const Summary s = DifferenceSummary();
    table += fmt::format(
        "angular difference to the reference: mean {:.2f}, median {:.2f}, max "
        "{:.2f} degrees\n",
        s.mean, s.median, s.max);
  }
  return table;
}

namespace {

// The hemisphere: slant rings and tilt spokes, labelled, and the image axes.
std::string HemisphereSvg() {
  std::string svg;
  // Slant labels along the 315-degree spoke, clear of the tilt labels.
  for (int slant : {30, 60, 90}) {
    const double r = kRadius * slant / 90.0;
    svg += fmt::format(
        "<circle cx=\"{}\" cy=\"{}\" r=\"{:.1f}\" fill=\"none\" stroke=\"#bbb\"/>\n"
        "<text x=\"{:.1f}\" y=\"{:.1f}\" fill=\"#888\">{}&#176;</text>\n",
        kCentreX, kCentreY, r, kCentreX + r * std::sqrt(0.5) + 3, kCentreY + r * std::sqrt(0.5) - 3,
        slant);
  }
  for (int tilt = 0; tilt < 360; tilt += 30) {
    const double a = tilt * kPi / 180.0;
    svg += fmt::format(
        "<line x1=\"{}\" y1=\"{}\" x2=\"{:.1f}\" y2=\"{:.1f}\" stroke=\"#ddd\"/>\n"
        "<text x=\"{:.1f}\" y=\"{:.1f}\" fill=\"#888\" text-anchor=\"middle\">{}&#176;</text>\n",
        kCentreX, kCentreY, kCentreX + kRadius * std::cos(a), kCentreY - kRadius * std::sin(a),
        kCentreX + (kRadius + 18) * std::cos(a), kCentreY - (kRadius + 18) * std::sin(a) + 4, tilt);
  }
  svg += fmt::format("<text x=\"{}\" y=\"{}\" fill=\"#888\">+x</text>\n", kCentreX + kRadius + 30,
                     kCentreY + 16);
  svg += fmt::format("<text x=\"{}\" y=\"{}\" fill=\"#888\">+y</text>\n", kCentreX + 6,
                     kCentreY - kRadius + 14);
  return svg;
}

// Each recovered light joined to its reference, the references (red rings), then the recovered
// lights (blue dots, numbered). `reference` is empty or one per recovered light.
std::string LightMarksSvg(const std::vector<LightDirection>& recovered,
                          const std::vector<LightDirection>& reference) {
  std::string svg;
  for (std::size_t i = 0; !reference.empty() && i < recovered.size(); ++i) {
    const auto [x1, y1] = PlotPoint(recovered[i]);
    const auto [x2, y2] = PlotPoint(reference[i]);
    svg += fmt::format(
        "<line x1=\"{:.1f}\" y1=\"{:.1f}\" x2=\"{:.1f}\" y2=\"{:.1f}\" "
        "stroke=\"#999\"/>\n",
        x1, y1, x2, y2);
  }
  for (std::size_t i = 0; i < reference.size(); ++i) {
    const auto [x, y] = PlotPoint(reference[i]);
    svg += fmt::format(
        "<circle cx=\"{:.1f}\" cy=\"{:.1f}\" r=\"6\" fill=\"none\" "
        "stroke=\"#d22\" stroke-width=\"1.5\"/>\n",
        x, y);
  }
  for (std::size_t i = 0; i < recovered.size(); ++i) {
    const auto [x, y] = PlotPoint(recovered[i]);
    svg += fmt::format(
        "<circle cx=\"{:.1f}\" cy=\"{:.1f}\" r=\"3.5\" fill=\"#1559c4\"/>\n"
        "<text x=\"{:.1f}\" y=\"{:.1f}\" font-size=\"10\" fill=\"#1559c4\">{}</text>\n",
        x, y, x + 5, y - 5, i);
  }
  return svg;
}

std::string LegendSvg(bool has_reference) {
  std::string svg;
  const double legend_y = kCentreY + kRadius + 50;
  svg += fmt::format(
      "<circle cx=\"40\" cy=\"{0:.0f}\" r=\"3.5\" fill=\"#1559c4\"/>"
      "<text x=\"50\" y=\"{1:.0f}\">recovered</text>\n",
      legend_y, legend_y + 4);
  if (has_reference) {
    svg += fmt::format(
        "<circle cx=\"150\" cy=\"{0:.0f}\" r=\"6\" fill=\"none\" stroke=\"#d22\" "
        "stroke-width=\"1.5\"/><text x=\"162\" y=\"{1:.0f}\">given</text>\n",
        legend_y, legend_y + 4);
  }
  return svg;
}

}  // namespace

std::string LightCalibrationReport::ToSvg() const {
  const std::vector<double> differences = AngularDifferences();
  const bool has_reference = !differences.empty();
  const double table_x = 600.0;
  const double row_height = 16.0;
  const double height =
      std::max(680.0 + row_height * static_cast<double>(notes.size()),
               110.0 + row_height * static_cast<double>(recovered.size() + notes.size()));
  std::string svg = fmt::format(
      "<svg xmlns=\"http://www.w3.org/2000/svg\" width=\"1000\" height=\"{0:.0f}\" "
      "viewBox=\"0 0 1000 {0:.0f}\" font-family=\"sans-serif\" font-size=\"12\">\n"
      "<rect width=\"1000\" height=\"{0:.0f}\" fill=\"white\"/>\n",
      height);
  svg += fmt::format("<text x=\"20\" y=\"30\" font-size=\"18\">{}</text>\n", EscapeMarkup(title));
  for (std::size_t i = 0; i < notes.size(); ++i) {
    svg += fmt::format("<text x=\"20\" y=\"{:.0f}\" fill=\"#555\">{}</text>\n",
                       height - 20.0 - row_height * static_cast<double>(notes.size() - 1 - i),
                       EscapeMarkup(notes[i]));
  }
  if (has_reference) {
    const Summary s = DifferenceSummary();
    svg += fmt::format(
        "<text x=\"20\" y=\"52\">angular difference to the reference: mean {:.2f}, median "
        "{:.2f}, max {:.2f} degrees</text>\n",
        s.mean, s.median, s.max);
  }
  svg += HemisphereSvg() +
         LightMarksSvg(recovered, has_reference ? reference : std::vector<LightDirection>{}) +
         LegendSvg(has_reference);
  // The table.
  double y = 90.0;
  svg += fmt::format(
      "<text x=\"{}\" y=\"{}\" font-family=\"monospace\" font-weight=\"bold\" "
      "xml:space=\"preserve\"> #   slant    tilt{}{}</text>\n",
      table_x, y, uncertainty_degrees.empty() ? "" : "  +-deg",
      has_reference ? "   given:  slant    tilt  angle" : "");
  for (std::size_t i = 0; i < recovered.size(); ++i) {
    y += row_height;
    std::string row = fmt::format("{:>2}  {:6.2f} {:7.2f}", i, recovered[i].SlantDegrees(),
                                  recovered[i].TiltDegrees());
    if (!uncertainty_degrees.empty()) {
      row += fmt::format("  {:>5}", UncertaintyText(uncertainty_degrees[i]));
    }
    if (has_reference) {
      row += fmt::format("   {:6.2f} {:7.2f}  {:5.2f}&#176;", reference[i].SlantDegrees(),
                         reference[i].TiltDegrees(), differences[i]);
    }
    svg += fmt::format(
        "<text x=\"{}\" y=\"{:.0f}\" font-family=\"monospace\" "
        "xml:space=\"preserve\">{}</text>\n",
        table_x, y, row);
  }
  svg += "</svg>\n";
  return svg;
}

nlohmann::json LightCalibrationReport::ToJson() const {
  const std::vector<double> differences = AngularDifferences();
  nlohmann::json lights = nlohmann::json::array();
  for (std::size_t i = 0; i < recovered.size(); ++i) {
    const Eigen::Vector3d& v = recovered[i].vector();
    nlohmann::json entry = {{"name", i < names.size() ? names[i] : ""},
                            {"light", {v.x(), v.y(), v.z()}},
                            {"slant_deg", recovered[i].SlantDegrees()},
                            {"tilt_deg", recovered[i].TiltDegrees()}};
    if (!uncertainty_degrees.empty()) {
      entry["uncertainty_deg"] = std::isfinite(uncertainty_degrees[i])
                                     ? nlohmann::json(uncertainty_degrees[i])
                                     : nlohmann::json(nullptr);
    }
    if (!differences.empty()) {
      const Eigen::Vector3d& r = reference[i].vector();
      entry["reference"] = {r.x(), r.y(), r.z()};
      entry["angle_deg"] = differences[i];
    }
    lights.push_back(entry);
  }
  nlohmann::json json = {{"title", title}, {"lights", lights}};
  if (!notes.empty()) json["notes"] = notes;
  if (!differences.empty()) {
    const Summary s = DifferenceSummary();
    json["angle_deg"] = {{"mean", s.mean}, {"median", s.median}, {"max", s.max}};
  }
  return json;
}

// Every sphere of the calibration, as the report and the manifest record it.
nlohmann::json MirrorSpheresJson(const MirrorSphereCalibration& result) {
  nlohmann::json spheres = nlohmann::json::array();
  for (const MirrorSphereFit& sphere : result.spheres) {
    spheres.push_back({{"centre", {sphere.refined.centre.x(), sphere.refined.centre.y()}},
                       {"radius", sphere.refined.radius},
                       {"initial_centre", {sphere.initial.centre.x(), sphere.initial.centre.y()}},
                       {"initial_radius", sphere.initial.radius},
                       {"edge_rms_px", sphere.edge_rms_pixels},
                       {"edge_points", sphere.edge_points}});
  }
  return spheres;
}

nlohmann::json MirrorSphereRefinementJson(const MirrorSphereRefinementReport& refinement) {
  nlohmann::json json = {{"requested", refinement.requested},
                         {"used", refinement.used},
                         {"status", refinement.status},
                         {"iterations", refinement.iterations}};
  if (refinement.used && refinement.highlight_sigma_pixels > 0.0) {
    json["highlight_sigma_px"] = refinement.highlight_sigma_pixels;
    json["highlight_sigma"] = refinement.highlight_sigma_measured
                                  ? "measured from the highlights' residuals"
                                  : "assumed: the outline's RMS (one sphere)";
  }
  return json;
}

// The report's lines on the spheres and the refinement.
std::vector<std::string> MirrorSphereNotes(const MirrorSphereCalibration& result) {
  std::vector<std::string> notes;
  notes.push_back(fmt::format("{} sphere{}, {} lights", result.spheres.size(),
                              result.spheres.size() == 1 ? "" : "s", ToString(result.light_model)));
  const MirrorSphereRefinementReport& refinement = result.refinement;
  if (!refinement.requested) {
    notes.push_back("refinement: not requested (the unrefined estimate)");
  } else if (!refinement.used) {
    notes.push_back(fmt::format("refinement: NOT USED, {}; the lights are the unrefined estimate",
                                refinement.status));
  } else {
    notes.push_back(fmt::format("refinement: {} in {} iterations; highlight noise {:.3f} px ({})",
                                refinement.status, refinement.iterations,
                                refinement.highlight_sigma_pixels,
                                refinement.highlight_sigma_measured ? "measured" : "assumed"));
  }
  return notes;
}

void WriteLightCalibrationSvg(const std::filesystem::path& path,
                              const LightCalibrationReport& report) {
  std::string svg;
  try {
    svg = report.ToSvg();
  } catch (const Error& error) {
    throw error.InFile(path);
  }
  WriteTextFileAtomically(path, svg);
}

}  // namespace photomat
