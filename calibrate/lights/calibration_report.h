#pragma once

#include <filesystem>
#include <nlohmann/json.hpp>
#include <string>
#include <vector>

#include "calibrate/lights/mirror_sphere.h"
#include "core/light_direction.h"

namespace photomat {

// The light calibration report: recovered light directions drawn on a hemisphere plot beside the
// given ones (if any), with the angular difference of each pair, as an SVG drawing, a text table
// and JSON.
//
// The plot is the azimuthal-equidistant view from the camera (as photomat's light interpolation
// uses): a light at slant s and tilt t is drawn at radius proportional to s in direction t, with
// +x to the right and +y up; rings mark slants 30, 60 and 90 degrees.
struct LightCalibrationReport {
  std::string title;
  std::vector<std::string> names;  // one per recovered light
  std::vector<LightDirection> recovered;
  std::vector<LightDirection> reference;  // empty, or one per recovered light
  // Empty, or one per recovered light: its expected RMS angular error (degrees; NaN: unknown).
  std::vector<double> uncertainty_degrees;
  // Lines said under the title (how the lights were refined, or why not).
  std::vector<std::string> notes;

  // Angle between recovered and reference light, degrees (empty without a reference).
  std::vector<double> AngularDifferences() const;
  struct Summary {
    double mean = 0.0, median = 0.0, max = 0.0;
  };
  Summary DifferenceSummary() const;

  std::string ToTable() const;
  std::string ToSvg() const;
  nlohmann::json ToJson() const;
};

// A mirror-sphere calibration as its report records it: every sphere (refined and initial circle,
// outline RMS and points), the refinement's outcome (requested, used, its status and iterations,
// the highlight noise it weighed with), and the lines said under the report's title (the
// spheres and light model; whether the refinement was used, and if not, why).
nlohmann::json MirrorSpheresJson(const MirrorSphereCalibration& result);
nlohmann::json MirrorSphereRefinementJson(const MirrorSphereRefinementReport& refinement);
std::vector<std::string> MirrorSphereNotes(const MirrorSphereCalibration& result);

// Writes the SVG (atomically). Throws Error naming the file on failure or for a reference or
// uncertainty list of another length.
void WriteLightCalibrationSvg(const std::filesystem::path& path,
                              const LightCalibrationReport& report);

}  // namespace photomat
