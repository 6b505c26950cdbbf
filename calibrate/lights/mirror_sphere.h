#pragma once

#include <Eigen/Core>
#include <filesystem>
#include <optional>
#include <string>
#include <string_view>
#include <vector>

#include "core/image.h"
#include "core/light_direction.h"
#include "core/progress.h"

namespace photomat {

// Light directions from a mirror (chrome) sphere photographed under each light.
//
// Image coordinates here are continuous pixel coordinates: x to the right, y down, the centre of
// pixel (column c, row r) at (c + 0.5, r + 0.5). Light directions are in photomat's frame (x right,
// y up, z toward the camera).
//
// Pipeline (CalibrateLightsFromMirrorSphere):
//   1. the spheres' outlines: from a given mask (sub-pixel edge points where an anti-aliased or
//      binary mask crosses one half; each connected region of the mask is one sphere, ordered
//      left to right) or, without a mask, one sphere found by OpenCV's Hough circle detection on
//      the median of every pixel over the images, refined with sub-pixel edge points along
//      radial profiles;
//   2. per image and sphere, the specular highlight: the brightest smoothed pixel inside the
//      sphere, its blob (connected pixels above half of the peak over the sphere's median) and
//      the blob's intensity-weighted centroid, with a clear error for a highlight that is too
//      weak, a large saturated blob (its centre is not measurable), or one at the sphere's rim;
//   3. the unrefined estimate: per sphere, the light is the view vector reflected about the
//      sphere's normal at the highlight (orthographic camera by default, view vector +z; or
//      perspective with known intrinsics, the view ray through the highlight pixel); with several
//      spheres the light is the normalised mean of their directions (the distant-light
//      assumption);
//   4. the refinement (Ceres, mirror_sphere_refinement.h): one problem whose unknowns are every
//      sphere's circle and one light per image, with residuals from every outline (Huber loss)
//      and every highlight (Cauchy loss): the highlight each sphere would show under the light,
//      where its normal bisects the view vector and the direction to the light, minus the one
//      measured. With one sphere and distant lights each light has exactly its two highlight
//      residuals, so the highlights cannot check the sphere (the lights just follow the fitted
//      outline); with two or more spheres each light is seen several times, the highlights
//      constrain the spheres and the noise of each highlight averages out, and near point lights
//      (LightModel::kNear) are triangulated: the lamp's position is where the mirror rays of all
//      spheres meet. The solver's result is used only when it converged; otherwise the
//      unrefined estimate is kept and the refinement's report says why.
struct SphereCircle {
  Eigen::Vector2d centre = Eigen::Vector2d::Zero();  // continuous pixel coordinates
  double radius = 0.0;                               // pixels
};

// Pinhole intrinsics in OpenCV's convention (pixel centres at integer coordinates; DiLiGenT's
// K.txt, OpenCV's calibrateCamera): u = fx X / Z + cx, v = fy Y / Z + cy.
struct CameraIntrinsics {
  double fx = 0.0, fy = 0.0, cx = 0.0, cy = 0.0;
};
// Reads a 3 x 3 matrix "fx 0 cx / 0 fy cy / 0 0 1" (whitespace separated, 9 numbers).
CameraIntrinsics ReadCameraIntrinsics(const std::filesystem::path& path);

// The sphere outline from a mask image read as linear coverage (any channel; values in [0, 1]):
// sub-pixel edge points where the coverage crosses 0.5 along rows and columns, fitted by a circle
// (algebraic start, Ceres geometric refinement with a Huber loss; the algebraic fit alone in a
// build without Ceres). Throws Error naming `source` when the mask holds no circle-like region.
SphereCircle FitSphereToMask(const Image& mask, const std::filesystem::path& source = {});

// Sub-pixel edge points of the mask (where coverage crosses 0.5), for the joint refinement.
std::vector<Eigen::Vector2d> MaskEdgePoints(const Image& mask);

// Finds the sphere in the images without a mask: Hough circles (OpenCV) on the per-pixel median
// over all images (the sphere's body and outline without the moving highlights), refined by
// sub-pixel gradient maxima along radial profiles. `edge_points` receives those points. Throws
// Error naming `source` when no circle is found.
SphereCircle DetectSphere(const std::vector<Image>& images, const std::filesystem::path& source,
                          std::vector<Eigen::Vector2d>* edge_points = nullptr);

struct HighlightOptions {
  // The peak must exceed this (absolute, linear full scale = 1) ...
  double minimum_peak = 0.02;
  // ... and this multiple of the sphere's median value.
  double minimum_contrast = 4.0;
  // A blob with clipped pixels is rejected when its equivalent radius exceeds this fraction of
  // the sphere's radius: the centre of a large flat plateau is not the mirror point.
  double maximum_saturated_radius = 0.06;
  // A value at or above this (linear, full scale 1) is clipped.
  double saturation_level = 0.999;
  // The highlight must lie within this fraction of the radius from the centre (near the rim the
  // normal changes too fast for the direction to be reliable).
  double maximum_radius_fraction = 0.97;
};

struct Highlight {
  Eigen::Vector2d position = Eigen::Vector2d::Zero();  // sub-pixel, continuous coordinates
  double peak = 0.0;
  int blob_pixels = 0;
  int saturated_pixels = 0;
};

// The specular highlight of one image of the sphere. Throws Error naming `image_name` and the
// fault (too weak, saturated blob, at the rim).
Highlight LocateHighlight(const Image& image, const SphereCircle& sphere,
                          const HighlightOptions& options, const std::string& image_name);

// The light direction whose mirror reflection lands at `highlight` (orthographic camera).
LightDirection LightFromHighlight(const SphereCircle& sphere, const Eigen::Vector2d& highlight);
// The same for a perspective camera: the sphere's 3-D centre (camera frame, units of its radius)
// follows from the outline and the intrinsics.
LightDirection LightFromHighlight(const SphereCircle& sphere, const Eigen::Vector2d& highlight,
                                  const CameraIntrinsics& camera);
// Inverse of the orthographic LightFromHighlight: where the highlight of `light` appears.
Eigen::Vector2d HighlightFromLight(const SphereCircle& sphere, const LightDirection& light);

// What the lights are. IMPLEMENTER CHOICE: distant by default (what an .lp file holds); near
// point lights need two or more spheres in the images (one sphere sees a near lamp in one
// direction only, not at a distance) and an orthographic camera. The spheres are taken to rest
// on the sample plane (their centres one radius above it), the frame being near_light.h's
// sample frame: pixel units, origin at the image centre, x right, y up, z toward the camera.
enum class LightModel { kDistant, kNear };
std::string_view ToString(LightModel model);
// "distant" or "near"; throws Error for any other name.
LightModel ParseLightModel(std::string_view name);

// The centre of the sphere of `circle` (in a width x height image) in the sample frame: the
// sphere rests on the sample plane.
Eigen::Vector3d SphereCentreInSampleFrame(const SphereCircle& circle, int width, int height);
// The point of that sphere where its highlight is seen at `highlight` (sample frame).
Eigen::Vector3d MirrorPointInSampleFrame(const SphereCircle& circle,
                                         const Eigen::Vector2d& highlight, int width, int height);

struct MirrorSphereOptions {
  HighlightOptions highlight;
  std::optional<CameraIntrinsics> camera;  // unset: orthographic
  LightModel light_model = LightModel::kDistant;
  // The Ceres joint refinement (step 4). In a build without Ceres, true is an Error
  // (MirrorSphereRefinementAvailable() in mirror_sphere_refinement.h).
  bool refine = true;
  // The solver's iteration budget for each of its passes; a solve that does not converge within
  // it is not used (the unrefined estimate is kept and the report says so).
  int refine_max_iterations = 100;
  Progress* progress = nullptr;
};

// What became of the refinement.
struct MirrorSphereRefinementReport {
  bool requested = false;
  bool used = false;   // the refined estimate is the result
  std::string status;  // "not requested", "converged", or why it was not used
  int iterations = 0;  // over both passes
  // The highlight localisation noise the refinement weighed the highlights with (pixels), and
  // whether it was measured from the highlights' own residuals (two or more spheres) or assumed
  // equal to the outline's RMS (one sphere: the highlights have no redundancy).
  double highlight_sigma_pixels = 0.0;
  bool highlight_sigma_measured = false;
};

// One sphere of the calibration.
struct MirrorSphereFit {
  SphereCircle initial;               // from its outline alone
  SphereCircle refined;               // as refined (the initial circle when not refined)
  std::vector<Highlight> highlights;  // one per image
  double edge_rms_pixels = 0.0;       // RMS distance of the edge points from `refined`
  int edge_points = 0;
};

struct MirrorSphereCalibration {
  // The first (leftmost) sphere, as refined and before; its highlights and outline.
  SphereCircle sphere;
  SphereCircle initial;
  std::vector<Highlight> highlights;
  double edge_rms_pixels = 0.0;
  int edge_points = 0;
  bool perspective = false;
  std::vector<MirrorSphereFit> spheres;  // every sphere, left to right
  LightModel light_model = LightModel::kDistant;
  // One per image: the distant light, or for near lights the direction from the sample's centre
  // (the origin of the sample frame) to the lamp.
  std::vector<LightDirection> lights;
  // Near lights, refined: the lamps' positions in the sample frame (pixel units); else empty.
  std::vector<Eigen::Vector3d> lamp_positions;
  // One per light when refined: the light's expected RMS angular error in degrees (the square
  // root of the trace of its direction's covariance, from the Ceres covariance of the solve
  // with each residual weighed by its noise); empty when not refined.
  std::vector<double> light_uncertainty_degrees;
  MirrorSphereRefinementReport refinement;
};

// Each connected region of the mask (coverage over one half) with at least a few edge points is
// a sphere: its sub-pixel edge points, the regions ordered by the mean x of their points.
std::vector<std::vector<Eigen::Vector2d>> MaskSphereOutlines(const Image& mask);

// The whole pipeline. `mask` (coverage in [0, 1]) selects the spheres when given; otherwise one
// sphere is detected. `names` name the images in messages. Every image's highlight is located on
// every sphere; if any fails, one Error lists every failing image with its fault.
MirrorSphereCalibration CalibrateLightsFromMirrorSphere(const std::vector<Image>& images,
                                                        const std::vector<std::string>& names,
                                                        const std::optional<Image>& mask,
                                                        const MirrorSphereOptions& options,
                                                        const std::filesystem::path& source = {});

}  // namespace photomat
